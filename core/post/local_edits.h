// Stage 4's local edits of the wrap: flips, collapses, moves and splits, each weighed as a
// Change before it is made. The engine keeps the surface's adjacency and a bucketed index of
// its triangles current, answers the distance and sharp-edge questions the checks ask, and
// applies or refuses; sliver removal and proximity refinement decide what to try.
// The surface stays closed, manifold and oriented: every change replaces a closed fan.
#pragma once
#include <algorithm>
#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include "check/intersections.h"
#include "common/cell_lists.h"
#include "common/triangle_buckets.h"
#include "post/remesh.h"

namespace vdbwrap::post {

// A change weighed before it is made: triangle slots get new corners (or die), new triangles
// are appended (slot kNoSlot), at most one point moves and at most one is added.
struct Change {
  static constexpr uint32_t kNoSlot = UINT32_MAX;
  std::vector<uint32_t> slots;
  std::vector<Tri> tris;      // tris[i] replaces slots[i], or is appended
  std::vector<uint8_t> dies;  // slot i is removed
  uint32_t moved = UINT32_MAX;
  Vec3 to{0, 0, 0};
  uint32_t added = UINT32_MAX;  // the new point's index (the next free one)
  Vec3 added_at{0, 0, 0};
  double added_cell = 0;  // its local cell size
  void clear() { slots.clear(), tris.clear(), dies.clear(), moved = UINT32_MAX, added = UINT32_MAX; }
  void add(uint32_t slot, const Tri& t, bool die = false) {
    slots.push_back(slot), tris.push_back(t), dies.push_back(die);
  }
};

// What every edit is held to, in model units.
struct LocalEditBounds {
  double offset = 0;               // nodes placed on the input sit this far off it
  double feature_tolerance = 0;    // the input's sharp edges may come this much farther from the wrap
  bool float_coordinates = false;  // placed nodes rounded to float (binary STL output)
};

// The bounds from a pass's parameters, which name them alike.
template <typename Params>
LocalEditBounds edit_bounds(const Params& p) {
  LocalEditBounds b;
  b.offset = p.offset, b.feature_tolerance = p.feature_tolerance, b.float_coordinates = p.float_coordinates;
  return b;
}

class LocalEdits {
 public:
  LocalEdits(PostSurface& s, const QualityReference& ref, const LocalEditBounds& bounds);
  const std::map<std::string, size_t>& refusals() const { return refusals_; }

 protected:
  static constexpr uint32_t kNone = UINT32_MAX;

  bool refuse(const std::string& why) {
    ++refusals_[why];
    return false;
  }

  // A node that must not move or vanish: snapped onto a feature curve, or on a traced feature edge.
  bool fixed(uint32_t v) const { return s_.locked[v] || !feature_[v].empty(); }
  bool feature_edge(uint32_t a, uint32_t b) const;
  bool is_edge(uint32_t a, uint32_t b) const;
  void neighbours(uint32_t v, std::vector<uint32_t>& out) const;
  // The two triangles on edge (a, b): the one with a -> b first. False unless there are exactly two.
  bool edge_triangles(uint32_t a, uint32_t b, uint32_t& ab, uint32_t& ba) const;
  static uint32_t third(const Tri& t, uint32_t a, uint32_t b);

  // Where point v is once change c is made.
  Vec3 at(uint32_t v, const Change& c) const { return v == c.moved ? c.to : v == c.added ? c.added_at : s_.points[v]; }
  double min_angle(uint32_t f) const;
  Vec3 stored(const Vec3& x) const;  // as the output will hold it

  // The input's nearest point to q (output frame), the node placed the wrap's offset off it on
  // q's side; q itself when the input is not within half a cell (a bridge over a gap stays a
  // bridge). onto_input_anywhere: however far the input is.
  Vec3 onto_input(const Vec3& q, double cell) const;
  Vec3 onto_input_anywhere(const Vec3& q) const;
  double distance_to_input(const Vec3& q) const;

  // Distances to the input: the largest, and the mean over the patch's area (a sliver, with
  // hardly any area, hardly counts: removing one that lies on the input's edge does not make
  // the rest look farther). Without any area, the plain mean.
  struct Spread {
    double worst = 0, sum = 0, area = 0, plain_sum = 0;
    size_t n = 0;
    double mean() const { return area > 0 ? sum / area : n ? plain_sum / double(n) : 0.0; }
    void add(const Spread& o) {
      worst = std::max(worst, o.worst), sum += o.sum, area += o.area, plain_sum += o.plain_sum, n += o.n;
    }
  };
  // Distances to the input of a triangle's centroid and edge midpoints.
  void sample(const Vec3& a, const Vec3& b, const Vec3& c, Spread& s) const;
  // Distances to the input of ten points of a triangle, corners included: the barycentric grid
  // of step 1/3. A moved node can be its triangles' farthest point, and the centroid and edge
  // midpoints alone miss the far parts of long triangles (as along a concave crease).
  void sample_grid(const Vec3& a, const Vec3& b, const Vec3& c, Spread& s) const;

  // The input's sharp edges near the change stay as near the surface as they were (or within
  // `tolerance`, the bounds' feature tolerance when negative).
  bool keeps_sharp_edges(const Change& c, const std::vector<check::Corners>& made_at, double tolerance = -1) const;
  // Why the made triangles would break the surface: "folds" (they meet each other),
  // "intersects" (they meet a triangle the change keeps), or null.
  const char* breaks_surface(const Change& c, const std::vector<Tri>& made, const std::vector<check::Corners>& made_at);

  // change_ made the move of node v to x (its triangles keep their corners).
  void propose_move(uint32_t v, const Vec3& x) {
    change_.clear();
    change_.moved = v;
    change_.to = x;
    for (uint32_t g : vt_[v]) change_.add(g, s_.triangles[g]);
  }
  // change_ made the split of edge (a, b) at a new node x: its two triangles become four.
  // False where the edge does not have two triangles with different third corners.
  bool propose_split(uint32_t a, uint32_t b, const Vec3& x);
  // Why the collapse of edge (u, v) would pinch the surface ("link": u and v share more
  // neighbours than the two across the edge; "valence": those would be left with under three
  // edges), "" where (u, v) is no edge between two triangles, or null when it may be made.
  const char* collapse_blocked(uint32_t u, uint32_t v) const;
  // change_ made the collapse of edge (u, v) into u, placed at x: the two triangles on the
  // edge die and v's others take u. Only where collapse_blocked(u, v) is null.
  void propose_collapse(uint32_t u, uint32_t v, const Vec3& x);
  void apply(const Change& c);
  // After a collapse of v into u is applied: v is gone, and its traced feature edges run
  // through u.
  void hand_over(uint32_t u, uint32_t v);
  // Did node v or a neighbour change in this round or the one before?
  bool changed_near(uint32_t v) const;
  // Live triangles and the points they use, with their data (after triangles died).
  void compact();

  PostSurface& s_;
  const QualityReference& ref_;
  LocalEditBounds bounds_;
  TriangleBuckets buckets_;
  std::vector<uint8_t> alive_;
  std::vector<std::vector<uint32_t>> vt_;       // live triangles at each node
  std::vector<std::vector<uint32_t>> feature_;  // traced feature edges at each node
  int round_ = 0;
  std::vector<int> touched_;  // per node: the last round that changed a triangle at it
  CellLists<> samples_;       // the input's sharp-edge samples
  Change change_;

 private:
  std::map<std::string, size_t> refusals_;
};

}  // namespace vdbwrap::post
