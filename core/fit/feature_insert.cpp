#include "fit/feature_insert.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <initializer_list>
#include <limits>
#include <set>
#include <unordered_map>

#include "check/intersections.h"
#include "common/closest_point.h"
#include "common/float_round.h"
#include "common/grid_key.h"
#include "common/triangle_buckets.h"
#include "common/vec.h"

namespace vdbwrap::fit {
namespace {


class Inserter {
 public:
  Inserter(FittedSurface& s, const SurfaceIndex& input, const Vec3& origin, const FeatureInsertParams& prm)
      : s_(s), p_(s.points), t_(s.triangles), input_(input), origin_(origin), prm_(prm),
        buckets_(s.points, s.triangles, std::max(prm.max_move, 1e-300)),
        inv_change_cell_(1.0 / std::max(prm.max_move, 1e-300)) {
    vf_.resize(p_.size());
    for (uint32_t f = 0; f < t_.size(); ++f)
      for (uint32_t v : t_[f]) vf_[v].push_back(f);
    for (const auto& [a, b] : s.feature_edges) edges_.insert({std::min(a, b), std::max(a, b)});
  }

  // One pass over the curves. `retry` has a flag per sample (in curve order): only flagged
  // samples are visited, and a sample stays flagged only when a reachable change was refused.
  void run(const std::vector<FeatureCurve>& curves, std::vector<uint8_t>& retry, FeatureInsertStats& stats) {
    const bool first = retry.empty();
    size_t index = 0;
    for (const FeatureCurve& c : curves) {
      uint32_t previous = UINT32_MAX;  // the last node put on this curve: their edge is a feature edge
      for (size_t i = 0; i + 1 < c.points.size(); ++i) {
        const Vec3 &a = c.points[i], &b = c.points[i + 1];
        const size_t k = std::max<size_t>(1, size_t(std::ceil(norm(b - a) / prm_.spacing)));
        for (size_t j = (i == 0 ? 0 : 1); j <= k; ++j, ++index) {
          if (first) retry.push_back(1), seen_.push_back(0);
          const Vec3 q = world(lerp(a, b, double(j) / double(k)));
          // A refused point is retried only when the wrap near it changed since: else every
          // check would give what it gave before.
          if (!retry[index] || (!first && !changed_near(q, seen_[index]))) {
            previous = UINT32_MAX;
            continue;
          }
          bool again = false;
          seen_[index] = clock_;
          const uint32_t v = visit(q, again, stats);
          retry[index] = again;
          if (v == UINT32_MAX) continue;
          if (previous != UINT32_MAX && previous != v && adjacent(previous, v)) add_feature_edge(previous, v);
          previous = v;
        }
      }
    }
    s_.feature_edges.assign(edges_.begin(), edges_.end());
  }

 private:
  // Has any triangle within reach of q changed after time `since`? Reach: the farthest a
  // change can be from q and still alter the checks of a change at q (the move radius plus
  // two edges: the changed triangles and the ones they are tested against).
  // Change times are kept per cell of the reach's size (for every cell a changed triangle's box
  // covers): a handful of look-ups, where scanning the triangles in reach was most of the stage
  // on large inputs. A cell may report a change a little beyond the reach: a wasted retry, never
  // a missed one.
  bool changed_near(const Vec3& q, uint64_t since) const {
    const double r = 1.5 * prm_.max_move;
    bool changed = false;
    for_change_cells(q - Vec3{r, r, r}, q + Vec3{r, r, r}, [&](const GridKey& k) {
      if (changed) return;
      auto it = changed_cells_.find(k);
      changed = it != changed_cells_.end() && it->second > since;
    });
    return changed;
  }
  template <typename F>
  void for_change_cells(const Vec3& lo, const Vec3& hi, F&& fn) const {
    const GridKey a = grid_key(lo, inv_change_cell_), b = grid_key(hi, inv_change_cell_);
    for (int64_t x = a.x; x <= b.x; ++x)
      for (int64_t y = a.y; y <= b.y; ++y)
        for (int64_t z = a.z; z <= b.z; ++z) fn(GridKey{x, y, z});
  }
  // After an accepted change: the clock ticks, and the cells of the changed faces take its time
  // (and those of the boxes they had before, when they moved: a face leaving a point's reach
  // changes what a check there sees, as one entering it does).
  template <typename Faces>
  void mark_changed(const Faces& faces, const std::vector<Box3>& before = {}) {
    ++clock_;
    auto mark = [&](const Box3& box) { for_change_cells(box.lo, box.hi, [&](const GridKey& k) { changed_cells_[k] = clock_; }); };
    for (uint32_t f : faces) mark(face_box(f));
    for (const Box3& box : before) mark(box);
  }
  Box3 face_box(uint32_t f) const {
    Box3 box;
    for (uint32_t v : t_[f]) box.add(p_[v]);
    return box;
  }

  Vec3 world(const Vec3& local) const {
    Vec3 w = local + origin_;
    return prm_.float_coordinates ? round_to_float(w) : w;
  }

  // A wrap edge near a curve point: how near, and where along it (0 to 1) the nearest point is.
  struct Candidate {
    double distance, t;
    uint32_t a, b;
  };
  // The wrap's edges within r of q (each once), and the distance from q to the nearest triangle
  // in reach (infinite when none is).
  double look_around(const Vec3& q, double r, std::vector<Candidate>& edges) {
    Box3 box;
    box.add(q - Vec3{r, r, r});
    box.add(q + Vec3{r, r, r});
    double nearest = std::numeric_limits<double>::infinity();
    edges.clear();
    buckets_.for_each_in_box(box, [&](uint32_t f) {
      if (f >= t_.size()) return;  // a stale entry of an undone split
      const Tri& tri = t_[f];
      nearest = std::min(nearest, norm(closest_on_triangle(q, p_[tri[0]], p_[tri[1]], p_[tri[2]]) - q));
      for (int e = 0; e < 3; ++e) {
        const uint32_t u = tri[e], w = tri[(e + 1) % 3];
        if (u > w) continue;  // each interior edge once (from the face that has it as u < w)
        double t;
        const double dist = norm(closest_on_segment(p_[u], p_[w], q, t) - q);
        if (dist <= r) edges.push_back({dist, t, u, w});
      }
    });
    return nearest;
  }

  // Brings the wrap to curve point q when it misses it; returns the node now at q, if any.
  // `refused`: q was missed and some change that could reach it was refused.
  uint32_t visit(const Vec3& q, bool& refused, FeatureInsertStats& stats) {
    // The nearest six edges in reach are all that is tried. Looked for within a quarter of the
    // reach first: when six are there, they are the nearest six of the whole reach, and a
    // triangle within the tolerance is there too.
    const double r = prm_.max_move;
    std::vector<Candidate>& edges = candidates_;
    double nearest = look_around(q, 0.25 * r, edges);
    if (edges.size() < 6 && nearest > prm_.tolerance) nearest = look_around(q, r, edges);
    if (nearest <= prm_.tolerance) {
      // Already on the wrap: report the node there, if one is.
      for (const Candidate& c : edges)
        for (uint32_t v : {c.a, c.b})
          if (norm(p_[v] - q) <= prm_.tolerance) return v;
      return UINT32_MAX;
    }
    ++stats.samples_missed;
    // The nearest edges first: the nearest may fold where the next one does not.
    std::sort(edges.begin(), edges.end(), [](const Candidate& x, const Candidate& y) {
      return x.distance != y.distance ? x.distance < y.distance : (x.a != y.a ? x.a < y.a : x.b < y.b);
    });
    const size_t tries = std::min<size_t>(edges.size(), 6);
    for (size_t k = 0; k < tries; ++k) {
      const Candidate& c = edges[k];
      // The node stops `offset` short of the curve, on the side the wrap came from.
      const Vec3 from = lerp(p_[c.a], p_[c.b], c.t);
      const Vec3 away = from - q;
      const double d = norm(away);
      Vec3 target = d > 0 ? q + away * (std::min(prm_.offset, d) / d) : q;
      // A curve point behind the input (a buried intersection line) is out of reach.
      if (!input_.in_view(from - origin_, q - origin_, prm_.offset)) continue;
      refused = true;
      if (prm_.float_coordinates) target = round_to_float(target);
      // Near an end of the edge, that end goes (unless it is on a curve already); else a split,
      // and failing that the nearer end.
      const uint32_t end = c.t < 0.5 ? c.a : c.b;
      const bool near_end = c.t < 0.25 || c.t > 0.75;
      if (near_end && !s_.snapped[end] && move(end, target)) {
        refused = false;
        ++stats.nodes_moved;
        return end;
      }
      const uint32_t m = split(c.a, c.b, target);
      if (m != UINT32_MAX) {
        refused = false;
        ++stats.nodes_inserted;
        return m;
      }
      if (!near_end && !s_.snapped[end] && move(end, target)) {
        refused = false;
        ++stats.nodes_moved;
        return end;
      }
    }
    if (refused)
      ++stats.refused;
    else
      ++stats.unreachable;
    return UINT32_MAX;
  }

  bool move(uint32_t v, const Vec3& to) {
    const Vec3 from = p_[v];
    std::vector<Vec3> before;
    std::vector<Tri> old_faces;
    std::vector<Box3> old_boxes;
    for (uint32_t f : vf_[v]) before.push_back(normal_of(t_[f])), old_faces.push_back(t_[f]), old_boxes.push_back(face_box(f));
    p_[v] = to;
    for (uint32_t f : vf_[v]) buckets_.update(f);
    bool ok = !crowded(v);
    for (size_t k = 0; ok && k < vf_[v].size(); ++k) ok = acceptable(vf_[v][k], before[k]);
    if (ok) {
      std::vector<Tri> fresh;
      for (uint32_t f : vf_[v]) fresh.push_back(t_[f]);
      // The old faces' deviation is measured with v back where it was.
      ok = near_enough(fresh, [&] {
        p_[v] = from;
        const double d = max_deviation(old_faces);
        p_[v] = to;
        return d;
      });
    }
    if (!ok) {
      p_[v] = from;
      for (uint32_t f : vf_[v]) buckets_.update(f);
      return false;
    }
    s_.snapped[v] = 1;
    mark_changed(vf_[v], old_boxes);
    return true;
  }

  // Splits edge ab at a new node placed at `at`; the two triangles on the edge become four.
  uint32_t split(uint32_t a, uint32_t b, const Vec3& at) {
    std::vector<uint32_t> faces;
    for (uint32_t f : vf_[a])
      for (uint32_t v : t_[f])
        if (v == b) faces.push_back(f);
    if (faces.size() != 2) return UINT32_MAX;  // a border or non-manifold edge: leave it
    const uint32_t m = uint32_t(p_.size());
    p_.push_back(at);
    vf_.emplace_back();
    const Tri old0 = t_[faces[0]], old1 = t_[faces[1]];
    const Vec3 n0 = normal_of(old0), n1 = normal_of(old1);
    // In each face (x, y, c) with x-y the edge in its own order: (x, m, c) and (m, y, c).
    auto halves = [&](const Tri& tri) {
      int e = 0;
      while (!((tri[e] == a && tri[(e + 1) % 3] == b) || (tri[e] == b && tri[(e + 1) % 3] == a))) ++e;
      const uint32_t x = tri[e], y = tri[(e + 1) % 3], c = tri[(e + 2) % 3];
      return std::pair<Tri, Tri>{Tri{x, m, c}, Tri{m, y, c}};
    };
    const auto [h00, h01] = halves(old0);
    const auto [h10, h11] = halves(old1);
    const uint32_t f2 = uint32_t(t_.size()), f3 = f2 + 1;
    t_[faces[0]] = h00;
    t_[faces[1]] = h10;
    t_.push_back(h01);
    t_.push_back(h11);
    for (uint32_t f : {faces[0], faces[1], f2, f3}) buckets_.update(f);
    const bool ok = !crowded(m) && acceptable(faces[0], n0) && acceptable(f2, n0) && acceptable(faces[1], n1) &&
                    acceptable(f3, n1) &&
                    near_enough({t_[faces[0]], t_[f2], t_[faces[1]], t_[f3]}, [&] { return max_deviation({old0, old1}); });
    if (!ok) {
      t_[faces[0]] = old0;
      t_[faces[1]] = old1;
      t_.pop_back();
      t_.pop_back();
      p_.pop_back();
      vf_.pop_back();
      buckets_.update(faces[0]);
      buckets_.update(faces[1]);
      return UINT32_MAX;
    }
    // Incidences: m is in all four; y of each face moved to its new half; c is in both halves.
    vf_[m] = {faces[0], faces[1], f2, f3};
    for (const auto& [face, half] : {std::pair{faces[0], f2}, std::pair{faces[1], f3}}) {
      const Tri& h = t_[half];
      auto& ly = vf_[h[1]];
      std::replace(ly.begin(), ly.end(), face, half);
      vf_[h[2]].push_back(half);
    }
    mark_changed(std::array<uint32_t, 4>{faces[0], faces[1], f2, f3});
    s_.snapped.push_back(1);
    s_.cell_size.push_back(std::min(s_.cell_size[a], s_.cell_size[b]));
    if (edges_.erase({std::min(a, b), std::max(a, b)})) add_feature_edge(a, m), add_feature_edge(m, b);
    return m;
  }

  Vec3 normal_of(const Tri& tri) const { return area_vector(p_[tri[0]], p_[tri[1]], p_[tri[2]]); }

  // How far triangles stray from the input: the largest distance of their centroids and edge
  // midpoints (a node on a curve must not leave its triangles hanging away from the input).
  std::array<Vec3, 4> probes(const Tri& tri) const {
    const Vec3 &a = p_[tri[0]], &b = p_[tri[1]], &c = p_[tri[2]];
    return {(a + b + c) * (1.0 / 3.0), (a + b) * 0.5, (b + c) * 0.5, (c + a) * 0.5};
  }
  double max_deviation(const std::vector<Tri>& tris) const {
    double d2 = 0;
    for (const Tri& tri : tris)
      for (const Vec3& q : probes(tri)) d2 = std::max(d2, input_.squared_distance(q - origin_));
    return std::sqrt(d2);
  }
  // New triangles within max_deviation of the input (cheap sphere tests), or else no farther
  // than the ones they replace (exact distances, only then: they cost most of the stage).
  template <typename OldDeviation>
  bool near_enough(const std::vector<Tri>& fresh, OldDeviation&& old_deviation) const {
    bool within = prm_.max_deviation > 0;
    for (const Tri& tri : fresh)
      for (const Vec3& q : probes(tri))
        if (within && !input_.within(q - origin_, prm_.max_deviation)) within = false;
    if (within) return true;
    return max_deviation(fresh) <= std::max(prm_.max_deviation, old_deviation());
  }

  // A changed triangle: not degenerate, not flipped against the face it came from, clear of the
  // input, and crossing no other triangle.
  bool acceptable(uint32_t f, const Vec3& was) {
    const Tri& tri = t_[f];
    const Vec3 n = normal_of(tri);
    if (norm(n) < prm_.min_area2 || check::triangle_is_degenerate(p_, tri) || dot(n, was) <= 0) return false;
    if (input_.touches(p_[tri[0]] - origin_, p_[tri[1]] - origin_, p_[tri[2]] - origin_)) return false;
    bool hit = false;
    buckets_.for_each_candidate(f, [&](uint32_t g) {
      if (hit || g >= t_.size()) return;
      hit = check::triangle_pair_intersects(p_, tri, t_[g]);
    });
    return !hit;
  }

  bool crowded(uint32_t v) {
    const double sep = prm_.min_separation;
    Box3 box;
    box.add(p_[v] - Vec3{sep, sep, sep});
    box.add(p_[v] + Vec3{sep, sep, sep});
    bool close = false;
    buckets_.for_each_in_box(box, [&](uint32_t f) {
      if (close || f >= t_.size()) return;
      for (uint32_t w : t_[f])
        if (w != v && norm2(p_[w] - p_[v]) < sep * sep) close = true;
    });
    return close;
  }

  bool adjacent(uint32_t a, uint32_t b) const {
    for (uint32_t f : vf_[a])
      for (uint32_t v : t_[f])
        if (v == b) return true;
    return false;
  }
  void add_feature_edge(uint32_t a, uint32_t b) { edges_.insert({std::min(a, b), std::max(a, b)}); }

  FittedSurface& s_;
  std::vector<Vec3>& p_;
  std::vector<Tri>& t_;
  const SurfaceIndex& input_;
  Vec3 origin_;
  FeatureInsertParams prm_;
  TriangleBuckets buckets_;
  std::vector<std::vector<uint32_t>> vf_;
  std::set<std::pair<uint32_t, uint32_t>> edges_;
  std::vector<Candidate> candidates_;
  // Change times: a counter that ticks with every accepted change, the time each cell last
  // saw a change, and the time each curve point was last visited.
  double inv_change_cell_;
  uint64_t clock_ = 0;
  std::unordered_map<GridKey, uint64_t, GridKeyHash> changed_cells_;
  std::vector<uint64_t> seen_;
};

}  // namespace

FeatureInsertStats insert_feature_nodes(FittedSurface& surface, const std::vector<FeatureCurve>& curves, const SurfaceIndex& input,
                                        const Vec3& origin, const FeatureInsertParams& params) {
  FeatureInsertStats stats;
  if (curves.empty() || surface.triangles.empty() || !(params.spacing > 0)) return stats;
  Inserter inserter(surface, input, origin, params);
  // More passes while they place nodes: the nodes of one pass give the points it refused new
  // edges to split. The missed count is the first pass's; a refused point is retried only
  // when the wrap near it changed.
  std::vector<uint8_t> retry;
  inserter.run(curves, retry, stats);
  for (int pass = 1; pass < 4; ++pass) {
    FeatureInsertStats more;
    inserter.run(curves, retry, more);
    stats.nodes_inserted += more.nodes_inserted;
    stats.nodes_moved += more.nodes_moved;
    if (more.nodes_inserted + more.nodes_moved == 0) break;
  }
  // Refused: points still missed where some change in reach was refused (skipped ones too).
  stats.refused = size_t(std::count(retry.begin(), retry.end(), 1));
  return stats;
}

}  // namespace vdbwrap::fit
