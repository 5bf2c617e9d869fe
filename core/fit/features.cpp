#include "fit/features.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <memory>
#include <queue>
#include <type_traits>
#include <unordered_map>

#include <tbb/concurrent_unordered_map.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>
#include <tbb/parallel_sort.h>

#include "common/closest_point.h"
#include "common/dependency_order.h"
#include "common/fill_vector.h"
#include "common/grid_key.h"
#include "common/vec.h"

namespace vdbwrap::fit {
namespace {

using Key = GridKey;
using KeyHash = GridKeyHash;

// A node near a piece: the scan's cell number, the node, its distance to the piece.
struct Candidate {
  uint32_t cell, node;
  double distance;
  bool operator<(const Candidate& o) const { return cell != o.cell ? cell < o.cell : node < o.node; }
};

// Nodes by grid cell, a node in the cell of each of its two given positions, each cell's
// nodes in increasing order: (cell, node) pairs sorted in parallel, and a map from each cell
// to its run. (A map of per-cell vectors is filled serially, with the other cores idle.)
class SortedNodeCells {
 public:
  SortedNodeCells(const std::vector<Vec3>& at, const std::vector<Vec3>& also_at, double inv_cell) {
    const size_t n = at.size();
    FillVector<Entry> entries(2 * n);
    const Key none{INT64_MAX, INT64_MAX, INT64_MAX};  // sorts last: a node whose two cells are one
    tbb::parallel_for(tbb::blocked_range<size_t>(0, n, 8192), [&](const tbb::blocked_range<size_t>& r) {
      for (size_t i = r.begin(); i != r.end(); ++i) {
        const Key a = grid_key(at[i], inv_cell), b = grid_key(also_at[i], inv_cell);
        entries[2 * i] = {a, uint32_t(i)};
        entries[2 * i + 1] = {b == a ? none : b, uint32_t(i)};
      }
    });
    tbb::parallel_sort(entries.begin(), entries.end());
    while (!entries.empty() && entries.back().key == none) entries.pop_back();
    nodes_.resize(entries.size());
    for (size_t i = 0; i < entries.size(); ++i) {
      nodes_[i] = entries[i].node;
      if (i == 0 || !(entries[i].key == entries[i - 1].key)) runs_.push_back({entries[i].key, uint32_t(i)});
    }
    cells_.reserve(runs_.size());
    for (size_t k = 0; k < runs_.size(); ++k) cells_.emplace(runs_[k].key, uint32_t(k));
    runs_.push_back({none, uint32_t(entries.size())});
  }
  template <typename F>
  void for_each_in(const Key& k, F&& fn) const {
    auto it = cells_.find(k);
    if (it == cells_.end()) return;
    for (uint32_t i = runs_[it->second].start; i < runs_[it->second + 1].start; ++i) fn(nodes_[i]);
  }

 private:
  struct Entry {
    Key key;
    uint32_t node;
    bool operator<(const Entry& o) const { return key == o.key ? node < o.node : key < o.key; }
  };
  struct Run {
    Key key;
    uint32_t start;
  };
  std::vector<uint32_t> nodes_;
  std::vector<Run> runs_;
  std::unordered_map<Key, uint32_t, KeyHash> cells_;  // cell -> its run
};

// A piece of a curve with arc-length parameters at its points.
struct Piece {
  std::vector<Vec3> points;
  std::vector<double> arc;
  Box3 box;  // of the points
  bool start_corner = false, end_corner = false;

  // Nearest point on the piece: point, distance and arc parameter.
  Vec3 closest(const Vec3& p, double& distance, double& at) const {
    Vec3 best = points[0];
    distance = std::numeric_limits<double>::infinity();
    at = 0;
    for (size_t i = 0; i + 1 < points.size(); ++i) {
      double t;
      Vec3 q = closest_on_segment(points[i], points[i + 1], p, t);
      double d = norm(q - p);
      if (d < distance) {
        distance = d;
        best = q;
        at = arc[i] + t * (arc[i + 1] - arc[i]);
      }
    }
    return best;
  }
  // The same distance when it is at most r, else a number above r. Squares are compared and
  // one root taken (the root of the least square is the least root); a piece or segment whose
  // box lies farther than r, or than the nearest segment so far, is passed over (with a margin
  // far above the rounding of a distance, so that one it would have given is never the answer).
  double distance_within(const Vec3& p, double r) const {
    constexpr double kMargin = 1 + 1e-6;
    const double reach2 = r * r * kMargin;
    double least = std::numeric_limits<double>::infinity();
    if (box.squared_distance(p) > reach2) return least;
    for (size_t i = 0; i + 1 < points.size(); ++i) {
      const Vec3 &a = points[i], &b = points[i + 1];
      Box3 segment;
      segment.add(a), segment.add(b);
      const double g2 = segment.squared_distance(p);
      if (g2 > reach2 || g2 > least * kMargin) continue;
      double t;
      least = std::min(least, norm2(closest_on_segment(a, b, p, t) - p));
    }
    return std::sqrt(least);
  }
};

std::vector<Piece> split_into_pieces(const FeatureCurve& c, double piece_length) {
  // Resample so that no segment is longer than piece_length / 4, then cut every piece_length.
  std::vector<Vec3> dense;
  for (size_t i = 0; i + 1 < c.points.size(); ++i) {
    const Vec3 &a = c.points[i], &b = c.points[i + 1];
    size_t k = std::max<size_t>(1, size_t(std::ceil(norm(b - a) / (piece_length / 4))));
    for (size_t j = 0; j < k; ++j) dense.push_back(lerp(a, b, double(j) / double(k)));
  }
  dense.push_back(c.points.back());
  std::vector<Piece> pieces;
  Piece cur;
  cur.start_corner = c.start_corner;
  double run = 0;
  cur.points.push_back(dense[0]);
  cur.arc.push_back(0);
  for (size_t i = 1; i < dense.size(); ++i) {
    run += norm(dense[i] - dense[i - 1]);
    cur.points.push_back(dense[i]);
    cur.arc.push_back(run);
    bool last = i + 1 == dense.size();
    if (run >= piece_length || last) {
      cur.end_corner = last && c.end_corner;
      for (const Vec3& q : cur.points) cur.box.add(q);
      pieces.push_back(cur);
      cur = Piece{};
      cur.points.push_back(dense[i]);
      cur.arc.push_back(0);
      run = 0;
    }
  }
  return pieces;
}

}  // namespace

std::vector<FeatureCurve> build_feature_curves(const prep::PreparedInput& in, double corner_angle_deg) {
  // Graph of feature segments over welded points (mesh vertices, and intersection segment
  // ends merged by position).
  const auto& pts = in.mesh.points;
  std::vector<Vec3> node_pos(pts.begin(), pts.end());
  std::unordered_map<Key, uint32_t, KeyHash> extra;
  const double tol = 1e-9 * in.diagonal + 1e-300;
  auto node_at = [&](const Vec3& p) {
    Key k{int64_t(std::llround(p[0] / tol)), int64_t(std::llround(p[1] / tol)), int64_t(std::llround(p[2] / tol))};
    auto [it, added] = extra.emplace(k, uint32_t(node_pos.size()));
    if (added) node_pos.push_back(p);
    return it->second;
  };
  std::vector<std::pair<uint32_t, uint32_t>> segs;
  for (const auto& e : in.feature_edges) segs.emplace_back(e.a, e.b);
  for (const auto& s : in.intersections) {
    uint32_t a = node_at(s.a), b = node_at(s.b);
    if (a != b) segs.emplace_back(a, b);
  }
  std::vector<std::vector<uint32_t>> adj(node_pos.size());  // segment ids per node
  for (uint32_t i = 0; i < segs.size(); ++i) {
    adj[segs[i].first].push_back(i);
    adj[segs[i].second].push_back(i);
  }
  const double cos_corner = std::cos(corner_angle_deg * M_PI / 180.0);
  auto other = [&](uint32_t s, uint32_t v) { return segs[s].first == v ? segs[s].second : segs[s].first; };
  auto is_corner = [&](uint32_t v) {
    if (adj[v].size() != 2) return true;
    Vec3 d0 = normalized(node_pos[other(adj[v][0], v)] - node_pos[v]);
    Vec3 d1 = normalized(node_pos[other(adj[v][1], v)] - node_pos[v]);
    // Straight through: directions opposite (dot -1). A turn sharper than the corner angle is a corner.
    return dot(d0, d1) > -cos_corner;
  };
  std::vector<uint8_t> used(segs.size(), 0);
  std::vector<FeatureCurve> curves;
  auto walk = [&](uint32_t start, uint32_t first_seg) {
    FeatureCurve c;
    c.start_corner = is_corner(start);
    if (first_seg < in.feature_edges.size()) {  // else an intersection line
      c.boundary = in.feature_edges[first_seg].kind == prep::FeatureKind::Boundary;
      c.crease = in.feature_edges[first_seg].kind == prep::FeatureKind::Sharp;
    }
    c.points.push_back(node_pos[start]);
    uint32_t v = start, s = first_seg;
    while (true) {
      used[s] = 1;
      v = other(s, v);
      c.points.push_back(node_pos[v]);
      if (v == start) {
        c.closed = true;
        break;
      }
      if (is_corner(v)) {
        c.end_corner = true;
        break;
      }
      uint32_t next = adj[v][0] == s ? adj[v][1] : adj[v][0];
      if (used[next]) break;
      s = next;
    }
    curves.push_back(std::move(c));
  };
  for (uint32_t v = 0; v < node_pos.size(); ++v)
    if (!adj[v].empty() && is_corner(v))
      for (uint32_t s : adj[v])
        if (!used[s]) walk(v, s);
  for (uint32_t s = 0; s < segs.size(); ++s)
    if (!used[s]) walk(segs[s].first, s);  // closed loops without corners
  return curves;
}

std::vector<std::pair<uint32_t, uint32_t>> snap_to_curves(
    const std::vector<FeatureCurve>& curves, const WrapGraph& graph, const std::vector<Vec3>& lattice,
    std::vector<Vec3>& target, std::vector<uint8_t>& snapped, double radius, double piece_length, double offset,
    SnapStats& stats, const std::function<bool(const Vec3&, const Vec3&)>& reachable) {
  const size_t n = target.size();
  // Nodes bucketed by target position, cells of the radius.
  const double inv = 1.0 / radius;
  auto key = [&](const Vec3& p) { return grid_key(p, inv); };
  const std::vector<Vec3> first_target = target;  // the targets the buckets were built on
  const SortedNodeCells buckets(target, lattice, inv);

  // Corner points already taken by a node, so curves meeting there share it. (Written by
  // curves traced at once: see the order of tracing below.)
  tbb::concurrent_unordered_map<Key, uint32_t, KeyHash> corner_node;
  const double ctol = radius * 1e-6;
  auto corner_key = [&](const Vec3& p) {
    return Key{int64_t(std::llround(p[0] / ctol)), int64_t(std::llround(p[1] / ctol)),
               int64_t(std::llround(p[2] / ctol))};
  };
  std::vector<uint8_t> is_corner_node(n, 0);

  auto place = [&](uint32_t v, const Vec3& on_curve) {
    Vec3 away = lattice[v] - on_curve;
    double d = norm(away);
    target[v] = d > 0 ? on_curve + away * (std::min(offset, d) / d) : on_curve;
    snapped[v] = 1;
  };

  // Per thread: the path search's state over all nodes, reused across pieces (reset through
  // the region and the touched list).
  struct TraceScratch {
    std::vector<double> dist, curve_distance;
    std::vector<uint32_t> prev, touched, component_of;
  };
  tbb::enumerable_thread_specific<TraceScratch> scratch_of([n] {
    TraceScratch sc;
    sc.dist.assign(n, std::numeric_limits<double>::infinity());
    sc.prev.assign(n, UINT32_MAX);
    sc.curve_distance.assign(n, -1);
    sc.component_of.assign(n, UINT32_MAX);
    return sc;
  });

  // The path of wrap nodes hugging one piece, from `carry` (the previous piece's end node)
  // when it lies near, among the nodes within `r` of the piece; empty when there is none.
  // The region of a piece: nodes within r of it, by the nearer of the projected and the
  // lattice position (smoothing rounds a concave corner away from its crease, the lattice
  // node stays close to it). Scanned cell by cell (cells numbered in scan order), each cell's
  // nodes in increasing order, so a region is listed in (cell, node) order.
  auto for_region_cells = [&](const Piece& piece, double r, auto&& fn) {
    const Key lo = key(piece.box.lo - Vec3{r, r, r}), hi = key(piece.box.hi + Vec3{r, r, r});
    uint32_t cell = 0;
    for (int64_t x = lo.x; x <= hi.x; ++x)
      for (int64_t y = lo.y; y <= hi.y; ++y)
        for (int64_t z = lo.z; z <= hi.z; ++z) fn(cell++, Key{x, y, z});
  };
  // The nearer of a node's two positions to the piece when within r, else a number above r.
  auto distance_to = [&](const Piece& piece, double r, uint32_t v) {
    return std::min(piece.distance_within(target[v], r), piece.distance_within(lattice[v], r));
  };
  // The nodes of `cells` (buckets of nodes: a NodeCells or SortedNodeCells) within r of the
  // piece, in scan order.
  using NodeCells = tbb::concurrent_unordered_map<Key, std::vector<uint32_t>, KeyHash>;
  auto for_each_in = [](const auto& cells, const Key& k, auto&& fn) {
    if constexpr (std::is_same_v<std::decay_t<decltype(cells)>, NodeCells>) {
      auto it = cells.find(k);
      if (it != cells.end())
        for (uint32_t v : it->second) fn(v);
    } else {
      cells.for_each_in(k, fn);
    }
  };
  auto nodes_near = [&](const Piece& piece, double r, const auto& cells) {
    std::vector<Candidate> out;
    for_region_cells(piece, r, [&](uint32_t cell, const Key& k) {
      for_each_in(cells, k, [&](uint32_t v) {
        const double d = distance_to(piece, r, v);
        if (d <= r) out.push_back({cell, v, d});
      });
    });
    return out;
  };
  // Corner nodes by the cells they were bucketed in, to find them where they are now.
  NodeCells corner_cells;
  auto mark_corner_node = [&](uint32_t v) {
    if (is_corner_node[v]) return;
    is_corner_node[v] = 1;
    const Key kt = key(first_target[v]), kl = key(lattice[v]);
    corner_cells[kt].push_back(v);
    if (!(kl == kt)) corner_cells[kl].push_back(v);
  };
  // The region as a scan on the wrap as it stands would list it, from candidates found before
  // any node moved. Only snapped nodes moved since: those off corners are never on a path
  // (nor are they anything else's start or end), and corner nodes are found again by their
  // cells, at their present distance.
  auto region_from = [&](const Piece& piece, double r, const std::vector<Candidate>& before) {
    std::vector<Candidate> corners;
    if (!corner_cells.empty()) corners = nodes_near(piece, r, corner_cells);
    std::sort(corners.begin(), corners.end());  // a cell's corner nodes were listed as marked
    std::vector<Candidate> out;
    out.reserve(before.size() + corners.size());
    size_t j = 0;
    for (const Candidate& c : before) {
      if (snapped[c.node]) continue;
      for (; j < corners.size() && corners[j] < c; ++j) out.push_back(corners[j]);
      out.push_back(c);
    }
    out.insert(out.end(), corners.begin() + j, corners.end());
    return out;
  };

  auto find_path = [&](const Piece& piece, double r, uint32_t carry, const std::vector<Candidate>* before,
                       TraceScratch& sc) {
    std::vector<double>& dist = sc.dist;
    std::vector<double>& curve_distance = sc.curve_distance;
    std::vector<uint32_t>& prev = sc.prev;
    std::vector<uint32_t>& touched = sc.touched;
    std::vector<uint32_t>& component_of = sc.component_of;
    std::vector<uint32_t> region;
    for (const Candidate& c : before ? region_from(piece, r, *before) : nodes_near(piece, r, buckets))
      if (curve_distance[c.node] < 0) {
        curve_distance[c.node] = c.distance;
        region.push_back(c.node);
      }
    std::vector<uint32_t> path;
    auto passable = [&](uint32_t v) { return !snapped[v] || is_corner_node[v]; };
    // The region can hold several sheets of the wrap (both sides of a thin wall, a patch
    // across a gap): the path runs on the one that covers most of the piece (the nearest to
    // it on a tie); the other sheets leave the region.
    {
      std::vector<uint32_t> members, stack;
      std::vector<size_t> starts;
      uint32_t ncomp = 0;
      for (uint32_t v0 : region) {
        if (component_of[v0] != UINT32_MAX || !passable(v0)) continue;
        starts.push_back(members.size());
        component_of[v0] = ncomp;
        stack.push_back(v0);
        while (!stack.empty()) {
          uint32_t u = stack.back();
          stack.pop_back();
          members.push_back(u);
          for (uint32_t w : graph.neighbours[u])
            if (curve_distance[w] >= 0 && component_of[w] == UINT32_MAX && passable(w))
              component_of[w] = ncomp, stack.push_back(w);
        }
        ++ncomp;
      }
      starts.push_back(members.size());
      uint32_t best = 0;
      double best_cover = -1, best_near = std::numeric_limits<double>::infinity();
      const double tie = 1e-3 * piece.arc.back();
      for (uint32_t comp = 0; comp < ncomp; ++comp) {
        double a0 = std::numeric_limits<double>::infinity(), a1 = -a0, near = a0;
        for (size_t k = starts[comp]; k < starts[comp + 1]; ++k) {
          double d, at;
          piece.closest(target[members[k]], d, at);
          a0 = std::min(a0, at), a1 = std::max(a1, at), near = std::min(near, curve_distance[members[k]]);
        }
        if (a1 - a0 > best_cover + tie || (std::fabs(a1 - a0 - best_cover) <= tie && near < best_near))
          best = comp, best_cover = a1 - a0, best_near = near;
      }
      for (uint32_t v0 : region)
        if (component_of[v0] != best) curve_distance[v0] = -1;
      // A snapped carry node is outside every component: it joins the chosen one when it
      // touches it.
      if (carry != UINT32_MAX && curve_distance[carry] >= 0 && component_of[carry] == UINT32_MAX) {
        bool touches = false;
        for (uint32_t w : graph.neighbours[carry]) touches |= component_of[w] == best && curve_distance[w] >= 0;
        if (!touches) curve_distance[carry] = -1;
      }
      for (uint32_t v0 : region) component_of[v0] = UINT32_MAX;
    }
    // End nodes: the region node nearest each end point (or the node already at a corner).
    auto nearest_to = [&](const Vec3& q, bool corner) {
      if (corner) {
        auto it = corner_node.find(corner_key(q));
        if (it != corner_node.end() && curve_distance[it->second] >= 0) return it->second;
      }
      uint32_t best = UINT32_MAX;
      double bd = std::numeric_limits<double>::infinity();
      for (uint32_t v : region) {
        if (curve_distance[v] < 0 || (snapped[v] && !is_corner_node[v])) continue;
        double d = norm(target[v] - q);
        if (d < bd) bd = d, best = v;
      }
      return best;
    };
    const uint32_t s = (carry != UINT32_MAX && curve_distance[carry] >= 0)
                           ? carry
                           : nearest_to(piece.points.front(), piece.start_corner);
    const uint32_t e = nearest_to(piece.points.back(), piece.end_corner);
    if (s != UINT32_MAX && e != UINT32_MAX && s != e) {
      // Shortest path hugging the piece; other curves' snapped nodes are not crossed.
      using Item = std::pair<double, uint32_t>;
      std::priority_queue<Item, std::vector<Item>, std::greater<Item>> heap;
      dist[s] = 0;
      touched.push_back(s);
      heap.push({0, s});
      while (!heap.empty()) {
        auto [du, u] = heap.top();
        heap.pop();
        if (du > dist[u]) continue;
        if (u == e) break;
        for (uint32_t w : graph.neighbours[u]) {
          if (curve_distance[w] < 0) continue;
          if (snapped[w] && w != e && !is_corner_node[w]) continue;
          double len = norm(target[w] - target[u]);
          double cost = len * (1.0 + 4.0 * (curve_distance[u] + curve_distance[w]) / (2 * r)) + 1e-12;
          if (du + cost < dist[w]) {
            if (dist[w] == std::numeric_limits<double>::infinity()) touched.push_back(w);
            dist[w] = du + cost;
            prev[w] = u;
            heap.push({dist[w], w});
          }
        }
      }
      if (prev[e] != UINT32_MAX)
        for (uint32_t v = e; v != UINT32_MAX; v = prev[v]) path.push_back(v);
    }
    for (uint32_t v : region) curve_distance[v] = -1;
    for (uint32_t v : touched) dist[v] = std::numeric_limits<double>::infinity(), prev[v] = UINT32_MAX;
    touched.clear();
    std::reverse(path.begin(), path.end());
    return path;
  };

  // The candidates of every piece at once, in parallel, before any node moves: measuring
  // every node near a piece was most of the tracing, which follows the curves one by one.
  std::vector<std::vector<Piece>> pieces_of(curves.size());
  tbb::parallel_for(tbb::blocked_range<size_t>(0, curves.size(), 16), [&](const tbb::blocked_range<size_t>& r) {
    for (size_t c = r.begin(); c != r.end(); ++c) pieces_of[c] = split_into_pieces(curves[c], piece_length);
  });
  std::vector<std::pair<uint32_t, uint32_t>> piece_ids;  // (curve, piece)
  for (uint32_t c = 0; c < curves.size(); ++c)
    for (uint32_t k = 0; k < pieces_of[c].size(); ++k) piece_ids.push_back({c, k});
  std::vector<std::vector<Candidate>> candidates(piece_ids.size());
  tbb::parallel_for(tbb::blocked_range<size_t>(0, piece_ids.size(), 8), [&](const tbb::blocked_range<size_t>& r) {
    for (size_t i = r.begin(); i != r.end(); ++i)
      candidates[i] = nodes_near(pieces_of[piece_ids[i].first][piece_ids[i].second], radius, buckets);
  });

  std::vector<size_t> first_piece(curves.size() + 1, 0);
  for (size_t c = 0; c < curves.size(); ++c) first_piece[c + 1] = first_piece[c] + pieces_of[c].size();

  // One curve, piece by piece: its stats and traced edges.
  auto trace_curve = [&](size_t ci, TraceScratch& sc, SnapStats& stats,
                         std::vector<std::pair<uint32_t, uint32_t>>& traced) {
    const FeatureCurve& c = curves[ci];
    stats.corners += (c.start_corner ? 1 : 0) + (c.end_corner ? 1 : 0);
    const std::vector<Piece>& pieces = pieces_of[ci];
    size_t captured = 0;
    uint32_t carry = UINT32_MAX;  // end node of the previous piece
    for (size_t pi = 0; pi < pieces.size(); ++pi) {
      const Piece& piece = pieces[pi];
      std::vector<Candidate> before;
      before.swap(candidates[first_piece[ci] + pi]);  // freed as the pieces are traced
      ++stats.pieces;
      // Where the wrap is coarse or split into sheets the band may hold no path: a wider one
      // is tried before the piece is given up.
      std::vector<uint32_t> path = find_path(piece, radius, carry, &before, sc);
      if (path.empty()) path = find_path(piece, 2 * radius, carry, nullptr, sc);
      if (path.empty()) {
        carry = UINT32_MAX;
        continue;
      }
      // Move the path onto the piece, keeping its order along the curve (no zig-zag back).
      double last_at = -1;
      std::vector<uint8_t> on(path.size(), 0);
      for (size_t k = 0; k < path.size(); ++k) {
        uint32_t v = path[k];
        Vec3 q;
        if (k == 0 && piece.start_corner) {
          q = piece.points.front();
          last_at = 0;
        } else if (k + 1 == path.size() && piece.end_corner) {
          q = piece.points.back();
          last_at = piece.arc.back();
        } else if (k == 0 && snapped[v]) {
          on[k] = 1;  // shared with the previous piece or a corner: already on the curve
          double d, at;
          piece.closest(target[v], d, at);
          last_at = at;
          continue;
        } else {
          double d, at;
          q = piece.closest(target[v], d, at);
          if (at < last_at) continue;
          last_at = at;
        }
        // From the target or from the lattice node: next to a concave crease the target can
        // lie on the other face (its offset runs along it), the lattice node cannot.
        if (!reachable(target[v], q) && !reachable(lattice[v], q)) continue;
        place(v, q);
        on[k] = 1;
        ++stats.nodes_snapped;
      }
      for (size_t k = 0; k + 1 < path.size(); ++k)
        if (on[k] && on[k + 1]) traced.emplace_back(path[k], path[k + 1]);
      if (piece.start_corner && on[0])
        corner_node[corner_key(piece.points.front())] = path.front(), mark_corner_node(path.front());
      if (piece.end_corner && on.back())
        corner_node[corner_key(piece.points.back())] = path.back(), mark_corner_node(path.back());
      ++stats.pieces_traced;
      ++captured;
      carry = path.back();
    }
    if (captured == pieces.size() && !pieces.empty()) ++stats.curves_captured;
  };

  // Curves are traced at once where they cannot meet. A curve reads and writes only nodes
  // bucketed in cells near its pieces (the wider band, widened by how far a node's two cells
  // can lie apart), and only through maps safe for that. A curve that may meet an earlier one
  // (they share a cell of 8 radii) starts after it ends, so it sees that curve's nodes as a
  // trace one by one in order would, and the result is the same on any number of threads.
  const double shift = tbb::parallel_reduce(
      tbb::blocked_range<size_t>(0, n, 8192), 0.0,
      [&](const tbb::blocked_range<size_t>& r, double most) {
        for (size_t i = r.begin(); i != r.end(); ++i) most = std::max(most, norm(first_target[i] - lattice[i]));
        return most;
      },
      [](double a, double b) { return std::max(a, b); });
  const double reach = 3 * radius + shift;
  const double inv_claim_cell = 1.0 / (8 * radius);
  // Each curve waits for the last earlier curve in each of its cells (that one waits for the
  // ones before it there).
  std::vector<std::vector<uint32_t>> successors(curves.size());
  std::vector<uint32_t> waits(curves.size());
  {
    std::unordered_map<Key, uint32_t, KeyHash> last_in_cell;
    std::vector<Key> cells;
    std::vector<uint32_t> before;
    for (uint32_t ci = 0; ci < curves.size(); ++ci) {
      cells.clear(), before.clear();
      for (const Piece& piece : pieces_of[ci]) {
        const Key lo = grid_key(piece.box.lo - Vec3{reach, reach, reach}, inv_claim_cell);
        const Key hi = grid_key(piece.box.hi + Vec3{reach, reach, reach}, inv_claim_cell);
        for (int64_t x = lo.x; x <= hi.x; ++x)
          for (int64_t y = lo.y; y <= hi.y; ++y)
            for (int64_t z = lo.z; z <= hi.z; ++z) cells.push_back({x, y, z});
      }
      for (const Key& k : cells) {
        auto [it, added] = last_in_cell.emplace(k, ci);
        if (!added && it->second != ci) before.push_back(it->second), it->second = ci;
      }
      std::sort(before.begin(), before.end());
      before.erase(std::unique(before.begin(), before.end()), before.end());
      for (uint32_t b : before) successors[b].push_back(ci);
      waits[ci] = uint32_t(before.size());
    }
  }
  std::vector<SnapStats> curve_stats(curves.size());
  std::vector<std::vector<std::pair<uint32_t, uint32_t>>> curve_traced(curves.size());
  run_in_dependency_order(successors, waits,
                          [&](uint32_t ci) { trace_curve(ci, scratch_of.local(), curve_stats[ci], curve_traced[ci]); });
  std::vector<std::pair<uint32_t, uint32_t>> traced;
  stats.curves = curves.size();
  for (size_t ci = 0; ci < curves.size(); ++ci) {
    const SnapStats& cs = curve_stats[ci];
    stats.corners += cs.corners, stats.curves_captured += cs.curves_captured;
    stats.pieces += cs.pieces, stats.pieces_traced += cs.pieces_traced, stats.nodes_snapped += cs.nodes_snapped;
    traced.insert(traced.end(), curve_traced[ci].begin(), curve_traced[ci].end());
  }
  stats.corners_captured = corner_node.size();
  return traced;
}

}  // namespace vdbwrap::fit
