#include "fit/feature_insert.h"

#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_sort.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <initializer_list>
#include <limits>
#include <set>
#include <unordered_map>

#include "check/intersections.h"
#include "common/compressed_lists.h"
#include "common/bitwise_key.h"
#include "common/closest_point.h"
#include "common/concurrent_memo.h"
#include "common/float_round.h"
#include "common/grid_key.h"
#include "common/triangle_buckets.h"
#include "common/vec.h"

namespace vdbwrap::fit {
namespace {

// A wrap face that cuts through the input may be split onto a curve point this many stand-offs
// (`FeatureInsertParams::offset`) behind it.
constexpr double kCutDepth = 2;

using check::Corners;

// A curve point to bring the wrap to, and the curve it lies on.
struct Sample {
  Vec3 q;
  uint32_t curve;
  bool crease;  // on a curve along sharp edges
};

// A wrap edge near a curve point: how near, and where along it (0 to 1) the nearest point is.
struct Candidate {
  double distance, t;
  uint32_t a, b;
};

// What the checks decided for one curve point, on the wrap as it was when they ran.
struct Plan {
  enum Kind : uint8_t { kKeep, kMove, kSplit } kind = kKeep;
  uint32_t node = UINT32_MAX;  // kKeep: the node already at the point, if any; kMove: the node moved
  uint32_t a = 0, b = 0;       // kSplit: the edge split
  Vec3 target{0, 0, 0};
  bool missed = false;   // the wrap was farther than the tolerance
  bool refused = false;  // missed, and some change that could reach the point was refused
  Box3 read;             // everything the checks looked at: a change there makes the plan stale
  Box3 write;            // everything the change alters
};

// A triangle as a change would make it, and the area vector of the face it comes from.
struct Change {
  Tri tri;
  Corners at;
  Corners old;  // the corners of the face it replaces
};

// One thread's buffers.
struct Scratch {
  std::vector<Candidate> edges;
  std::vector<uint32_t> seen;
  uint32_t stamp = 0;
  std::vector<Box3> writes;
};

// A memo of the input's answers, shared by the planning threads: `compute` runs when the key
// is new (two threads may both run it, with the same value).
template <typename Memo, typename Compute>
auto remembered(Memo& known, const typename Memo::key_type& key, Compute&& compute) {
  typename Memo::mapped_type value;
  if (known.find(key, value)) return value;
  value = compute();
  known.insert(key, value);
  return value;
}
BitwiseKey<9> corners_key(const Corners& c) {
  return bitwise_key<9>({c[0][0], c[0][1], c[0][2], c[1][0], c[1][1], c[1][2], c[2][0], c[2][1], c[2][2]});
}

Box3 box_around(const Vec3& q, double r) {
  Box3 box;
  box.add(q - Vec3{r, r, r});
  box.add(q + Vec3{r, r, r});
  return box;
}
Box3 box_of(const Corners& c) {
  Box3 box;
  for (const Vec3& p : c) box.add(p);
  return box;
}

// The curve points are grouped by cells of a coarse grid, and the cells by the parities of their
// coordinates: cells of one class are a cell apart. A round checks, in parallel, a run of points
// of every cell of a class (read only, on the wrap as it stands; a run stops before a point whose
// checks would read what a change planned earlier in the run alters), then makes the changes in
// cell order. A point whose checks read a place that a change made earlier in the round altered
// is checked again first. So the result is that of visiting the points one by one in that
// order, whatever the number of threads.
class Inserter {
 public:
  Inserter(FittedSurface& s, const mesh::SurfaceIndex& input, const Vec3& origin, const FeatureInsertParams& prm)
      : s_(s),
        p_(s.points),
        t_(s.triangles),
        input_(input),
        origin_(origin),
        prm_(prm),
        buckets_(s.points, s.triangles, std::max(prm.max_move, 1e-300)),
        inv_change_cell_(1.0 / std::max(prm.max_move, 1e-300)) {
    vf_ = to_vectors(vertex_triangle_lists(p_.size(), t_));
    for (const auto& [a, b] : s.feature_edges) edges_.insert({std::min(a, b), std::max(a, b)});
  }

  // The curves' points, `spacing` apart, in curve order; then their cells.
  void sample(const std::vector<FeatureCurve>& curves) {
    for (uint32_t ci = 0; ci < curves.size(); ++ci) {
      const FeatureCurve& c = curves[ci];
      for (size_t i = 0; i + 1 < c.points.size(); ++i) {
        const Vec3 &a = c.points[i], &b = c.points[i + 1];
        const size_t k = std::max<size_t>(1, size_t(std::ceil(norm(b - a) / prm_.spacing)));
        for (size_t j = (i == 0 ? 0 : 1); j <= k; ++j)
          samples_.push_back({world(lerp(a, b, double(j) / double(k))), ci, c.crease});
      }
    }
    seen_.assign(samples_.size(), 0);
    group_by_cells();
  }
  size_t samples() const { return samples_.size(); }

  // One pass over the curve points. `retry` has a flag per point (in curve order): only flagged
  // points are visited, and a point stays flagged only when a reachable change was refused.
  void run(std::vector<uint8_t>& retry, bool first, FeatureInsertStats& stats) {
    std::vector<uint32_t> result(samples_.size(), UINT32_MAX);  // the node at each point visited
    std::vector<uint8_t> visited(samples_.size(), 0);
    for (std::vector<Cell>& cells : classes_) {
      for (Cell& c : cells) c.next = c.begin;
      std::vector<Cell*> active;
      for (Cell& c : cells) active.push_back(&c);
      while (!active.empty()) {
        // Each cell's next run of points is checked in parallel with the other cells' (read
        // only), then the changes are made in cell order.
        const uint64_t start = clock_;
        tbb::parallel_for(tbb::blocked_range<size_t>(0, active.size(), 1), [&](const tbb::blocked_range<size_t>& r) {
          Scratch& scratch = scratch_.local();
          for (size_t k = r.begin(); k < r.end(); ++k) plan_run(*active[k], retry, first, scratch);
        });
        for (Cell* c : active) {
          // A run's checked steps read nothing the run's planned changes write (see plan_run):
          // when the changes made earlier in this round, by other cells, reach none of their
          // reads, they stand, with one look-up instead of one per step (these look-ups are
          // serial, and were most of the applying on big assemblies).
          // An unchecked step planned here may change what the run did not plan: from then
          // on each step asks again.
          bool ask = !c->read.empty() && changed_in(c->read, start);
          for (Step& step : c->steps) {
            const uint32_t i = step.sample;
            const Vec3& q = samples_[i].q;
            if (!step.checked) {
              // Skipped as unchanged near it when the run was checked: still so?
              if (!changed_near(q, seen_[i])) continue;
              step.plan = plan(samples_[i], scratch_.local());
              ask = true;
            } else if (ask && changed_in(step.plan.read, start)) {
              step.plan = plan(samples_[i], scratch_.local());  // a change made earlier in this round was in reach
            }
            seen_[i] = clock_;
            visited[i] = 1;
            result[i] = apply(step.plan, stats);
            retry[i] = step.plan.refused;
          }
          c->steps.clear();
        }
        active.erase(std::remove_if(active.begin(), active.end(), [](const Cell* c) { return c->next == c->end; }),
                     active.end());
      }
    }
    link_along_curves(visited, result);
    s_.feature_edges.assign(edges_.begin(), edges_.end());
  }

 private:
  // A point of a run: its plan, or (unchecked) a refused point with no change near it since.
  struct Step {
    uint32_t sample;
    bool checked;
    Plan plan;
  };
  // The points of one cell, in curve order (`order_[begin, end)`), the next to visit, and the
  // current run's steps.
  struct Cell {
    uint32_t begin, end, next;
    std::vector<Step> steps;
    Box3 read;  // of the current run's checked steps
  };

  // Checks a cell's points from its next one on, on the wrap as it stands, until a point's
  // checks would read what a change planned earlier in the run writes (that point waits for
  // the next round) or 64 points were checked.
  void plan_run(Cell& c, const std::vector<uint8_t>& retry, bool first, Scratch& scratch) const {
    std::vector<Box3>& writes = scratch.writes;
    writes.clear();
    c.read = Box3{};
    size_t checked = 0;
    auto overlaps_writes = [&](const Box3& b) {
      for (const Box3& w : writes)
        if (w.overlaps(b)) return true;
      return false;
    };
    for (; c.next < c.end && checked < 64; ++c.next) {
      const uint32_t i = order_[c.next];
      if (!retry[i]) continue;
      const Vec3& q = samples_[i].q;
      // A refused point is retried only when the wrap near it changed since: else every check
      // would give what it gave before.
      if (!first && !changed_near(q, seen_[i])) {
        c.steps.push_back({i, false, Plan{}});  // a change made before it in this round may reach it
        continue;
      }
      if (overlaps_writes(box_around(q, prm_.max_move))) break;
      Plan pl = plan(samples_[i], scratch);
      if (overlaps_writes(pl.read)) break;
      ++checked;
      c.read.add(pl.read);
      if (pl.kind != Plan::kKeep) writes.push_back(pl.write);
      c.steps.push_back({i, true, std::move(pl)});
    }
  }

  // Cells a move radius and a half wide: a point's checks and change reach about a move radius
  // and an edge from it, so the points of cells a cell apart rarely meet.
  void group_by_cells() {
    const double inv = 1.0 / (1.5 * std::max(prm_.max_move, 1e-300));
    struct Entry {
      int parity;
      GridKey cell;
      uint32_t sample;
    };
    std::vector<Entry> entries(samples_.size());
    for (uint32_t i = 0; i < samples_.size(); ++i) {
      const GridKey k = grid_key(samples_[i].q, inv);
      entries[i] = {int((k.x & 1) | ((k.y & 1) << 1) | ((k.z & 1) << 2)), k, i};
    }
    tbb::parallel_sort(entries.begin(), entries.end(), [](const Entry& x, const Entry& y) {  // a total order
      if (x.parity != y.parity) return x.parity < y.parity;
      if (!(x.cell == y.cell)) return x.cell < y.cell;
      return x.sample < y.sample;
    });
    order_.resize(entries.size());
    for (uint32_t k = 0; k < entries.size(); ++k) {
      order_[k] = entries[k].sample;
      if (k == 0 || !(entries[k].cell == entries[k - 1].cell))
        classes_[size_t(entries[k].parity)].push_back({k, k, k, {}, Box3{}});
      classes_[size_t(entries[k].parity)].back().end = k + 1;
    }
  }

  // Feature edges between the nodes of successive points of a curve, when they are joined.
  void link_along_curves(const std::vector<uint8_t>& visited, const std::vector<uint32_t>& result) {
    uint32_t previous = UINT32_MAX;
    for (size_t i = 0; i < samples_.size(); ++i) {
      if (i == 0 || samples_[i].curve != samples_[i - 1].curve) previous = UINT32_MAX;
      if (!visited[i]) {
        previous = UINT32_MAX;
        continue;
      }
      const uint32_t v = result[i];
      if (v == UINT32_MAX) continue;
      if (previous != UINT32_MAX && previous != v && adjacent(previous, v)) add_feature_edge(previous, v);
      previous = v;
    }
  }

  // Has any triangle within reach of q changed after time `since`? Reach: the farthest a
  // change can be from q and still alter the checks of a change at q (the move radius plus
  // two edges: the changed triangles and the ones they are tested against).
  bool changed_near(const Vec3& q, uint64_t since) const {
    return changed_in(box_around(q, 1.5 * prm_.max_move), since);
  }
  // Change times are kept per cell of the move radius's size (for every cell a changed
  // triangle's box covers): a handful of look-ups, where scanning the triangles in reach was
  // most of the stage on large inputs. A cell may report a change a little beyond the box: a
  // wasted retry or check, never a missed one.
  bool changed_in(const Box3& box, uint64_t since) const {
    if (clock_ == since) return false;
    bool changed = false;
    for_change_cells(box.lo, box.hi, [&](const GridKey& k) {
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
  // After a change: the clock ticks, and the cells of the changed faces take its time (and
  // those of the boxes they had before, when they moved: a face leaving a point's reach changes
  // what a check there sees, as one entering it does).
  template <typename Faces>
  void mark_changed(const Faces& faces, const std::vector<Box3>& before = {}) {
    ++clock_;
    auto mark = [&](const Box3& box) {
      for_change_cells(box.lo, box.hi, [&](const GridKey& k) { changed_cells_[k] = clock_; });
    };
    for (uint32_t f : faces) mark(box_of(corners(t_[f])));
    for (const Box3& box : before) mark(box);
  }

  Vec3 world(const Vec3& local) const {
    Vec3 w = local + origin_;
    return prm_.float_coordinates ? round_to_float(w) : w;
  }
  Corners corners(const Tri& tri) const { return {p_[tri[0]], p_[tri[1]], p_[tri[2]]}; }

  // The wrap's edges within r of q (each once), and (when asked) the distance from q to the
  // nearest triangle in reach (infinite when none is or when not asked).
  double look_around(const Vec3& q, double r, Scratch& scratch, bool nearest_wanted) const {
    double nearest = std::numeric_limits<double>::infinity();
    scratch.edges.clear();
    buckets_.for_each_in_box(box_around(q, r), scratch.seen, scratch.stamp, [&](uint32_t f) {
      const Tri& tri = t_[f];
      if (nearest_wanted)
        nearest = std::min(nearest, norm(closest_on_triangle(q, p_[tri[0]], p_[tri[1]], p_[tri[2]]) - q));
      for (int e = 0; e < 3; ++e) {
        const uint32_t u = tri[e], w = tri[(e + 1) % 3];
        if (u > w) continue;  // each interior edge once (from the face that has it as u < w)
        double t;
        const double dist = norm(closest_on_segment(p_[u], p_[w], q, t) - q);
        if (dist <= r) scratch.edges.push_back({dist, t, u, w});
      }
    });
    return nearest;
  }

  // How to bring the wrap to curve point q when it misses it (read only).
  Plan plan(const Sample& sample, Scratch& scratch) const {
    const Vec3& q = sample.q;
    // The nearest six edges in reach are all that is tried. Looked for within a quarter, then
    // half of the reach first: when six are there, they are the nearest six of the whole reach
    // (every edge that near is found there), and a triangle within the tolerance is there too.
    // The whole reach holds several times more of the wrap, and its scan was most of the stage
    // where thousands of curves crowd a thin part.
    const double r = prm_.max_move;
    Plan pl;
    pl.read = box_around(q, r);
    std::vector<Candidate>& edges = scratch.edges;
    // Most points are on the wrap already: a triangle within the tolerance, and a node there if
    // one is, are found in a box of the tolerance's size (a bucket or two).
    if (look_around(q, prm_.tolerance, scratch, true) <= prm_.tolerance) {
      // Already on the wrap: report the node there, if one is.
      for (const Candidate& c : edges)
        for (uint32_t v : {c.a, c.b})
          if (norm(p_[v] - q) <= prm_.tolerance) {
            pl.node = v;
            return pl;
          }
      return pl;
    }
    // Any triangle within the tolerance was in that box: the wider looks need only the edges.
    look_around(q, 0.25 * r, scratch, false);
    if (edges.size() < 6) look_around(q, 0.5 * r, scratch, false);
    if (edges.size() < 6) look_around(q, r, scratch, false);
    pl.missed = true;
    double nearest = INFINITY;
    for (const Candidate& c : edges) nearest = std::min(nearest, c.distance);
    if (try_nearest_edges(q, -1, sample.crease, pl, scratch) || !(prm_.far_reach > r) || nearest <= 0.5 * r) return pl;
    // The wrap passes half a base cell or more from the point and no edge within max_move took
    // it: where the wrap bridges a crease (a narrow groove oblique to the lattice takes no cell
    // near it), the edges beyond, out to far_reach, are tried too.
    // They are looked for in widening boxes, as above: the far box holds several times the
    // wrap of the nearer ones, and a clump of crossing leaves sent its buried crossings here by
    // the hundred thousand.
    pl.read.add(box_around(q, prm_.far_reach));
    for (const double wide : {1.25 * r, 1.5 * r, prm_.far_reach}) {
      look_around(q, std::min(wide, prm_.far_reach), scratch, false);
      if (wide >= prm_.far_reach ||
          std::count_if(edges.begin(), edges.end(), [&](const Candidate& c) { return c.distance > r; }) >= 6)
        break;
    }
    try_nearest_edges(q, r, sample.crease, pl, scratch);
    return pl;
  }

  // Tries the six nearest of scratch.edges farther than `beyond` from q, nearest first (the
  // nearest may fold where the next one does not); true when one takes q (pl then says how).
  bool try_nearest_edges(const Vec3& q, double beyond, bool crease, Plan& pl, Scratch& scratch) const {
    std::vector<Candidate>& edges = scratch.edges;
    edges.erase(std::remove_if(edges.begin(), edges.end(), [&](const Candidate& c) { return c.distance <= beyond; }),
                edges.end());
    // A total order: the six are the same whatever order the scan found them in.
    const size_t tried = std::min<size_t>(edges.size(), 6);
    std::partial_sort(edges.begin(), edges.begin() + tried, edges.end(), [](const Candidate& x, const Candidate& y) {
      return x.distance != y.distance ? x.distance < y.distance : (x.a != y.a ? x.a < y.a : x.b < y.b);
    });
    edges.resize(tried);
    for (const Candidate& c : edges) {
      // The node stops `offset` short of the curve, on the side the wrap came from.
      const Vec3 from = lerp(p_[c.a], p_[c.b], c.t);
      const Vec3 away = from - q;
      const double d = norm(away);
      Vec3 target = d > 0 ? q + away * (std::min(prm_.offset, d) / d) : q;
      // A curve point behind the input (a buried intersection line) is out of reach.
      if (!in_view(from, q)) continue;
      pl.refused = true;
      if (prm_.float_coordinates) target = round_to_float(target);
      // Near an end of the edge, that end goes (unless it is on a curve already); else a split,
      // and failing that the nearer end.
      const uint32_t end = c.t < 0.5 ? c.a : c.b;
      const bool near_end = c.t < 0.25 || c.t > 0.75;
      Plan::Kind kind = Plan::kKeep;
      // A face through the input may be split where a crease lies deeper behind it than two
      // stand-offs: a chamfer across the crease. Shallower, the face only grazes a soup's
      // faces rounded out by a gap; along rims and where parts cross, no corner is cut off
      // (docs/pipeline.md, "A face that cuts a crease may be split").
      const bool may_cut = crease && c.distance > kCutDepth * prm_.offset;
      if (near_end && !s_.snapped[end] && can_move(end, target, pl.read, scratch, may_cut))
        kind = Plan::kMove;
      else if (can_split(c.a, c.b, target, pl.read, scratch, may_cut))
        kind = Plan::kSplit;
      else if (!near_end && !s_.snapped[end] && can_move(end, target, pl.read, scratch, may_cut))
        kind = Plan::kMove;
      if (kind == Plan::kKeep) continue;
      pl.kind = kind, pl.refused = false, pl.target = target;
      pl.node = end, pl.a = c.a, pl.b = c.b;
      // What changes: the faces of the moved node or split edge, and the new corner.
      for (uint32_t f : kind == Plan::kMove ? vf_[end] : faces_on(c.a, c.b)) pl.write.add(box_of(corners(t_[f])));
      pl.write.add(target);
      return true;
    }
    return false;
  }

  // Makes a planned change; returns the node now at the curve point, if any.
  uint32_t apply(const Plan& pl, FeatureInsertStats& stats) {
    if (pl.missed) ++stats.samples_missed;
    if (pl.kind == Plan::kMove) {
      ++stats.nodes_moved;
      std::vector<Box3> before;
      for (uint32_t f : vf_[pl.node]) before.push_back(box_of(corners(t_[f])));
      p_[pl.node] = pl.target;
      for (uint32_t f : vf_[pl.node]) buckets_.update(f);
      s_.snapped[pl.node] = 1;
      mark_changed(vf_[pl.node], before);
      return pl.node;
    }
    if (pl.kind == Plan::kSplit) {
      const uint32_t m = split(pl.a, pl.b, pl.target);
      if (m != UINT32_MAX) ++stats.nodes_inserted;
      return m;
    }
    if (pl.missed) ++(pl.refused ? stats.refused : stats.unreachable);
    return pl.node;
  }

  // The two faces on edge ab (fewer or more: a border or non-manifold edge).
  std::vector<uint32_t> faces_on(uint32_t a, uint32_t b) const {
    std::vector<uint32_t> faces;
    for (uint32_t f : vf_[a])
      for (uint32_t v : t_[f])
        if (v == b) faces.push_back(f);
    return faces;
  }
  // In face (x, y, c) with x-y the edge ab in its own order: (x, m, c) and (m, y, c).
  static std::pair<Tri, Tri> halves(const Tri& tri, uint32_t a, uint32_t b, uint32_t m) {
    int e = 0;
    while (!((tri[e] == a && tri[(e + 1) % 3] == b) || (tri[e] == b && tri[(e + 1) % 3] == a))) ++e;
    const uint32_t x = tri[e], y = tri[(e + 1) % 3], c = tri[(e + 2) % 3];
    return {Tri{x, m, c}, Tri{m, y, c}};
  }

  // Would moving node v to `to` keep the wrap valid and near the input?
  bool can_move(uint32_t v, const Vec3& to, Box3& read, Scratch& scratch, bool may_cut) const {
    const std::vector<uint32_t>& faces = vf_[v];
    auto at = [&](const Tri& tri) {
      Corners c = corners(tri);
      for (int k = 0; k < 3; ++k)
        if (tri[k] == v) c[k] = to;
      return c;
    };
    std::vector<Change> changes;
    for (uint32_t f : faces) {
      const Corners old = corners(t_[f]);
      read.add(box_of(old));
      changes.push_back({t_[f], at(t_[f]), old});
    }
    if (crowded(v, to, read, scratch)) return false;
    if (!acceptable(
            changes, [&](uint32_t g) { return std::find(faces.begin(), faces.end(), g) != faces.end(); }, read, scratch,
            may_cut))
      return false;
    return near_enough(changes, [&] {
      double d = 0;
      for (uint32_t f : faces) d = std::max(d, deviation(corners(t_[f])));
      return d;
    });
  }

  // Would splitting edge ab at a new node placed at `at` keep the wrap valid and near the input?
  bool can_split(uint32_t a, uint32_t b, const Vec3& at, Box3& read, Scratch& scratch, bool may_cut) const {
    const std::vector<uint32_t> faces = faces_on(a, b);
    if (faces.size() != 2) return false;     // a border or non-manifold edge: leave it
    const uint32_t m = uint32_t(p_.size());  // the index the new node would get
    auto place = [&](const Tri& tri) {
      Corners c;
      for (int k = 0; k < 3; ++k) c[k] = tri[k] == m ? at : p_[tri[k]];
      return c;
    };
    std::vector<Change> changes;
    for (uint32_t f : faces) {
      const Corners old = corners(t_[f]);
      read.add(box_of(old));
      const auto [h0, h1] = halves(t_[f], a, b, m);
      changes.push_back({h0, place(h0), old});
      changes.push_back({h1, place(h1), old});
    }
    if (crowded(m, at, read, scratch)) return false;
    if (!acceptable(
            changes, [&](uint32_t g) { return g == faces[0] || g == faces[1]; }, read, scratch, may_cut))
      return false;
    return near_enough(changes,
                       [&] { return std::max(deviation(corners(t_[faces[0]])), deviation(corners(t_[faces[1]]))); });
  }

  // How far a triangle strays from the input: the largest distance of its centroid and edge
  // midpoints (a node on a curve must not leave its triangles hanging away from the input).
  static std::array<Vec3, 4> probes(const Corners& c) {
    return {(c[0] + c[1] + c[2]) * (1.0 / 3.0), (c[0] + c[1]) * 0.5, (c[1] + c[2]) * 0.5, (c[2] + c[0]) * 0.5};
  }
  double deviation(const Corners& c) const {
    return remembered(deviation_known_, corners_key(c), [&] {
      double d2 = 0;
      for (const Vec3& q : probes(c)) d2 = std::max(d2, input_.squared_distance(q - origin_));
      return std::sqrt(d2);
    });
  }
  // The input's answers are kept bit for bit by their arguments: a point is planned again each
  // time the wrap near it changes, and about half of these questions (most of the stage's time)
  // had been asked before.
  bool in_view(const Vec3& from, const Vec3& q) const {
    return remembered(in_view_known_, bitwise_key<6>({from[0], from[1], from[2], q[0], q[1], q[2]}),
                      [&] { return input_.in_view(from - origin_, q - origin_, prm_.offset); });
  }
  bool touches_input(const Corners& c) const {
    return remembered(touches_known_, corners_key(c),
                      [&] { return input_.touches(c[0] - origin_, c[1] - origin_, c[2] - origin_); });
  }
  // New triangles within max_deviation of the input (cheap sphere tests), or else no farther
  // than the ones they replace (exact distances, only then: they cost most of the stage).
  template <typename OldDeviation>
  bool near_enough(const std::vector<Change>& fresh, OldDeviation&& old_deviation) const {
    bool within = prm_.max_deviation > 0;
    for (const Change& ch : fresh)
      for (const Vec3& q : probes(ch.at))
        if (within && !input_.within(q - origin_, prm_.max_deviation)) within = false;
    if (within) return true;
    double d = 0;
    for (const Change& ch : fresh) d = std::max(d, deviation(ch.at));
    return d <= std::max(prm_.max_deviation, old_deviation());
  }

  // Changed triangles: none degenerate, flipped against the face it came from, or touching the
  // input where that face did not, and none crossing another triangle (of the change, or of the
  // wrap outside it: `replaced(g)` tells the wrap's faces the change replaces). With `may_cut`,
  // a face that cuts through the input already (a chamfer across a crease the snapping missed)
  // may be split, or its corner moved onto the crease: the new faces cut less of the corner off.
  template <typename Replaced>
  bool acceptable(const std::vector<Change>& changes, Replaced&& replaced, Box3& read, Scratch& scratch,
                  bool may_cut) const {
    // One triangle at a time, cheapest test first: most refusals come early.
    for (size_t i = 0; i < changes.size(); ++i) {
      const Change& ch = changes[i];
      const Vec3 n = area_vector(ch.at[0], ch.at[1], ch.at[2]);
      if (norm(n) < prm_.min_area2 || check::triangle_is_degenerate(ch.at, ch.tri) ||
          dot(n, area_vector(ch.old[0], ch.old[1], ch.old[2])) <= 0)
        return false;
      if (touches_input(ch.at) && !(may_cut && touches_input(ch.old))) return false;
      for (size_t j = 0; j < i; ++j)
        if (check::triangle_pair_intersects(ch.at, ch.tri, changes[j].at, changes[j].tri)) return false;
      const Box3 box = box_of(ch.at);
      read.add(box);
      bool hit = false;
      buckets_.for_each_in_box(box, scratch.seen, scratch.stamp, [&](uint32_t g) {
        if (hit || replaced(g)) return;
        hit = check::triangle_pair_intersects(ch.at, ch.tri, corners(t_[g]), t_[g]);
      });
      if (hit) return false;
    }
    return true;
  }

  // Is another node within min_separation of `at` (where node v would be)?
  bool crowded(uint32_t v, const Vec3& at, Box3& read, Scratch& scratch) const {
    const double sep = prm_.min_separation;
    const Box3 box = box_around(at, sep);
    read.add(box);
    bool close = false;
    buckets_.for_each_in_box(box, scratch.seen, scratch.stamp, [&](uint32_t f) {
      if (close) return;
      for (uint32_t w : t_[f])
        if (w != v && norm2(p_[w] - at) < sep * sep) close = true;
    });
    return close;
  }

  // Splits edge ab at a new node placed at `at`; the two triangles on the edge become four.
  uint32_t split(uint32_t a, uint32_t b, const Vec3& at) {
    const std::vector<uint32_t> faces = faces_on(a, b);
    if (faces.size() != 2) return UINT32_MAX;  // not what was checked: never split blind
    const uint32_t m = uint32_t(p_.size());
    p_.push_back(at);
    vf_.emplace_back();
    const auto [h00, h01] = halves(t_[faces[0]], a, b, m);
    const auto [h10, h11] = halves(t_[faces[1]], a, b, m);
    const uint32_t f2 = uint32_t(t_.size()), f3 = f2 + 1;
    t_[faces[0]] = h00;
    t_[faces[1]] = h10;
    t_.push_back(h01);
    t_.push_back(h11);
    for (uint32_t f : {faces[0], faces[1], f2, f3}) buckets_.update(f);
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
  const mesh::SurfaceIndex& input_;
  mutable ConcurrentMemo<BitwiseKey<6>, bool, BitwiseKeyHash> in_view_known_;
  mutable ConcurrentMemo<BitwiseKey<9>, bool, BitwiseKeyHash> touches_known_;
  mutable ConcurrentMemo<BitwiseKey<9>, double, BitwiseKeyHash> deviation_known_;
  Vec3 origin_;
  FeatureInsertParams prm_;
  TriangleBuckets buckets_;
  std::vector<std::vector<uint32_t>> vf_;
  std::set<std::pair<uint32_t, uint32_t>> edges_;
  std::vector<Sample> samples_;
  std::vector<uint32_t> order_;               // points by cell
  std::array<std::vector<Cell>, 8> classes_;  // cells by parity class
  tbb::enumerable_thread_specific<Scratch> scratch_;
  // Change times: a counter that ticks with every change made, the time each cell last saw a
  // change, and the time each curve point was last checked.
  double inv_change_cell_;
  uint64_t clock_ = 0;
  std::unordered_map<GridKey, uint64_t, GridKeyHash> changed_cells_;
  std::vector<uint64_t> seen_;
};

}  // namespace

FeatureInsertStats insert_feature_nodes(FittedSurface& surface, const std::vector<FeatureCurve>& curves,
                                        const mesh::SurfaceIndex& input, const Vec3& origin,
                                        const FeatureInsertParams& params) {
  FeatureInsertStats stats;
  if (curves.empty() || surface.triangles.empty() || !(params.spacing > 0)) return stats;
  Inserter inserter(surface, input, origin, params);
  inserter.sample(curves);
  // More passes while they place nodes: the nodes of one pass give the points it refused new
  // edges to split. The missed count is the first pass's; a refused point is retried only
  // when the wrap near it changed.
  std::vector<uint8_t> retry(inserter.samples(), 1);
  inserter.run(retry, true, stats);
  for (int pass = 1; pass < 4; ++pass) {
    FeatureInsertStats more;
    inserter.run(retry, false, more);
    stats.nodes_inserted += more.nodes_inserted;
    stats.nodes_moved += more.nodes_moved;
    if (more.nodes_inserted + more.nodes_moved == 0) break;
  }
  // Refused: points still missed where some change in reach was refused (skipped ones too).
  stats.refused = size_t(std::count(retry.begin(), retry.end(), 1));
  return stats;
}

}  // namespace vdbwrap::fit
