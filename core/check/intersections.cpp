// One of the few translation units that include CGAL's heavy headers.
#include "check/intersections.h"
#include "common/compressed_lists.h"
#include "common/edge_triangles.h"
#include "common/dense_numbers.h"
#include "common/fill_vector.h"
#include "common/radix_sort.h"
#include "common/vec.h"

#include <CGAL/Exact_predicates_exact_constructions_kernel.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Polygon_mesh_processing/orientation.h>
#include <CGAL/Polygon_mesh_processing/self_intersections.h>
#include <CGAL/Surface_mesh.h>
#include <CGAL/box_intersection_d.h>
#include <CGAL/intersections.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_invoke.h>
#include <tbb/parallel_sort.h>

#include <algorithm>
#include <cmath>
#include <array>
#include <initializer_list>
#include <limits>
#include <mutex>

namespace vdbwrap::check {
namespace {

using K = CGAL::Exact_predicates_inexact_constructions_kernel;
using P3 = K::Point_3;
using T3 = K::Triangle_3;
using S3 = K::Segment_3;
using Box = CGAL::Box_intersection_d::Box_with_handle_d<double, 3, size_t, CGAL::Box_intersection_d::ID_EXPLICIT>;

P3 to_point(const Vec3& v) { return P3(v[0], v[1], v[2]); }

bool is_degenerate(const std::vector<P3>& p, const Tri& t) {
  return t[0] == t[1] || t[1] == t[2] || t[0] == t[2] || CGAL::collinear(p[t[0]], p[t[1]], p[t[2]]);
}

// Proofs in the plane. Projected along an axis, triangles that meet only at their shared
// vertices (or not at all) in 2D meet only there in 3D too: a common point would project to a
// common point. Projected along the dominant axis of one triangle's normal, this settles the
// nearly coplanar pairs (flat regions of a wrap, where the exact predicates are slow because
// the points are exactly coplanar) in doubles. Every test keeps a relative margin; anything
// close gives no proof and goes to the exact predicates.
struct Plane2 {
  int u = 0, v = 1;
  double err = 0;  // bound on the rounding of a coordinate difference: the points' magnitude
  Plane2(const P3& a, const P3& b, const P3& c) {
    const double n[3] = {(b.y() - a.y()) * (c.z() - a.z()) - (b.z() - a.z()) * (c.y() - a.y()),
                         (b.z() - a.z()) * (c.x() - a.x()) - (b.x() - a.x()) * (c.z() - a.z()),
                         (b.x() - a.x()) * (c.y() - a.y()) - (b.y() - a.y()) * (c.x() - a.x())};
    int drop = 0;
    for (int k = 1; k < 3; ++k)
      if (std::fabs(n[k]) > std::fabs(n[drop])) drop = k;
    u = (drop + 1) % 3, v = (drop + 2) % 3;
  }
  std::array<double, 2> operator()(const P3& q, const P3& origin) const { return {q[u] - origin[u], q[v] - origin[v]}; }
  void covers(std::initializer_list<const P3*> points) {
    double m = 0;
    for (const P3* q : points) m = std::max({m, std::fabs((*q)[u]), std::fabs((*q)[v])});
    err = 8 * std::numeric_limits<double>::epsilon() * m;
  }
};
using V2 = std::array<double, 2>;
constexpr double kMargin = 1e-9;
double cross2(const V2& p, const V2& q) { return p[0] * q[1] - p[1] * q[0]; }
double len2(const V2& p) { return std::sqrt(p[0] * p[0] + p[1] * p[1]); }
// The side of p relative to the line along `dir` through the origin: +1 / -1 when clearly off
// it, 0 when too close to tell.
int side(const V2& dir, const V2& p, double err) {
  const double ld = len2(dir), lp = len2(p);
  const double c = cross2(dir, p), m = kMargin * ld * lp + err * (ld + lp + err);
  return c > m ? 1 : c < -m ? -1 : 0;
}
// A vector in the plane with its length, for the proofs below that test each vector against
// several lines: each length is taken once (the same answers as side(); its square roots were
// a third of the proofs' time on flat wraps).
struct Dir2 {
  V2 v;
  double len;
  explicit Dir2(const V2& p) : v(p), len(len2(p)) {}
};
int side(const Dir2& dir, const Dir2& p, double err) {
  const double c = cross2(dir.v, p.v), m = kMargin * dir.len * p.len + err * (dir.len + p.len + err);
  return c > m ? 1 : c < -m ? -1 : 0;
}

// Is q nearly in the plane of (o, a, b)? (Doubles, generous: it only picks which test runs
// first.) The proofs in the plane pay off for nearly coplanar pairs; for the others CGAL's
// filtered predicates decide at once, and the plane tests would be wasted work.
bool nearly_coplanar(const P3& o, const P3& a, const P3& b, const P3& q) {
  const double u[3] = {a.x() - o.x(), a.y() - o.y(), a.z() - o.z()};
  const double v[3] = {b.x() - o.x(), b.y() - o.y(), b.z() - o.z()};
  const double w[3] = {q.x() - o.x(), q.y() - o.y(), q.z() - o.z()};
  const double n[3] = {u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]};
  const double d = n[0] * w[0] + n[1] * w[1] + n[2] * w[2];
  const double nn = n[0] * n[0] + n[1] * n[1] + n[2] * n[2], ww = w[0] * w[0] + w[1] * w[1] + w[2] * w[2];
  return d * d <= 1e-12 * nn * ww;
}

// Triangles (c, a, b) and (c, d, e), sharing only vertex c, meet only there: the two angular
// sectors at c are disjoint when a line through c along one of their four sides leaves the
// other sector strictly on its far side.
bool apart_at_shared_vertex_2d(const P3& c, const P3& a, const P3& b, const P3& d, const P3& e) {
  Plane2 pl(c, a, b);
  pl.covers({&c, &a, &b, &d, &e});
  const Dir2 va(pl(a, c)), vb(pl(b, c)), vd(pl(d, c)), ve(pl(e, c));
  auto separates = [&](const Dir2& side_dir, const Dir2& other, const Dir2& p, const Dir2& q) {
    const int inside = side(side_dir, other, pl.err);
    return inside != 0 && side(side_dir, p, pl.err) == -inside && side(side_dir, q, pl.err) == -inside;
  };
  return separates(va, vb, vd, ve) || separates(vb, va, vd, ve) || separates(vd, ve, va, vb) || separates(ve, vd, va, vb);
}

// Triangles (s, t, a) and (t, s, b) sharing edge s-t meet only there when a and b lie clearly
// on opposite sides of it.
bool apart_at_shared_edge_2d(const P3& s, const P3& t, const P3& a, const P3& b) {
  Plane2 pl(s, t, a);
  pl.covers({&s, &t, &a, &b});
  const Dir2 dir(pl(t, s));
  const int sa = side(dir, Dir2(pl(a, s)), pl.err), sb = side(dir, Dir2(pl(b, s)), pl.err);
  return sa != 0 && sb == -sa;
}

// Triangles with no shared vertex are apart when a line along one of their six edges leaves
// the other triangle clearly on the far side.
bool apart_2d(const std::array<P3, 3>& x, const std::array<P3, 3>& y) {
  Plane2 pl(x[0], x[1], x[2]);
  pl.covers({&x[0], &x[1], &x[2], &y[0], &y[1], &y[2]});
  auto splits = [&](const std::array<P3, 3>& own, const std::array<P3, 3>& other) {
    for (int i = 0; i < 3; ++i) {
      const P3& o = own[i];
      const Dir2 dir(pl(own[(i + 1) % 3], o));
      const int inside = side(dir, Dir2(pl(own[(i + 2) % 3], o)), pl.err);
      if (inside == 0) continue;
      bool all = true;
      for (int k = 0; k < 3 && all; ++k) all = side(dir, Dir2(pl(other[k], o)), pl.err) == -inside;
      if (all) return true;
    }
    return false;
  };
  return splits(x, y) || splits(y, x);
}

// Fast proof that triangles (c, a, b) and (c, d, e), sharing only vertex c, meet only there
// (false: no proof, run the exact tests). Fans of triangles around one vertex (cylinder caps,
// cone tips) make such pairs by the hundred million, nearly all far apart.
bool apart_at_shared_vertex(const P3& c, const P3& a, const P3& b, const P3& d, const P3& e) {
  const bool flat = nearly_coplanar(c, a, b, d) && nearly_coplanar(c, a, b, e);
  if (flat && apart_at_shared_vertex_2d(c, a, b, d, e)) return true;
  // d and e strictly on one side of plane (c, a, b): the second triangle meets that plane at c
  // only (and the same the other way round). Filtered predicates: fast when not coplanar.
  const CGAL::Orientation od = CGAL::orientation(c, a, b, d);
  if (od != CGAL::COPLANAR && od == CGAL::orientation(c, a, b, e)) return true;
  const CGAL::Orientation oa = CGAL::orientation(c, d, e, a);
  if (oa != CGAL::COPLANAR && oa == CGAL::orientation(c, d, e, b)) return true;
  return !flat && apart_at_shared_vertex_2d(c, a, b, d, e);
}

// Triangles intersect when they share points other than their common vertices/edge.
// `p`: any container of points indexed by the triangles' vertices.
template <typename Points>
bool triangles_intersect(const Points& p, const Tri& x, const Tri& y, bool use_proofs_2d = true) {
  int shared = 0;
  int xi[3], yi[3];  // positions of shared vertices
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j)
      if (x[i] == y[j]) {
        xi[shared] = i;
        yi[shared] = j;
        ++shared;
      }
  if (shared == 0) {
    const bool flat = nearly_coplanar(p[x[0]], p[x[1]], p[x[2]], p[y[0]]) && nearly_coplanar(p[x[0]], p[x[1]], p[x[2]], p[y[1]]) &&
                      nearly_coplanar(p[x[0]], p[x[1]], p[x[2]], p[y[2]]);
    if (use_proofs_2d && flat && apart_2d({p[x[0]], p[x[1]], p[x[2]]}, {p[y[0]], p[y[1]], p[y[2]]})) return false;
    return CGAL::do_intersect(T3(p[x[0]], p[x[1]], p[x[2]]), T3(p[y[0]], p[y[1]], p[y[2]]));
  }
  if (shared == 3) return true;  // the same triangle twice
  if (shared == 1) {
    int i = xi[0], j = yi[0];
    const P3 &c = p[x[i]], &a = p[x[(i + 1) % 3]], &b = p[x[(i + 2) % 3]], &d = p[y[(j + 1) % 3]], &e = p[y[(j + 2) % 3]];
    if (use_proofs_2d && apart_at_shared_vertex(c, a, b, d, e)) return false;
    // A crossing that starts at the common vertex leaves one triangle through its opposite edge.
    S3 opp_x(a, b);
    S3 opp_y(d, e);
    return CGAL::do_intersect(opp_x, T3(p[y[0]], p[y[1]], p[y[2]])) ||
           CGAL::do_intersect(opp_y, T3(p[x[0]], p[x[1]], p[x[2]]));
  }
  // Common edge: they intersect only when folded flat onto the same side of it.
  const P3& s = p[x[xi[0]]];
  const P3& t = p[x[xi[1]]];
  const P3& a = p[x[3 - xi[0] - xi[1]]];
  const P3& b = p[y[3 - yi[0] - yi[1]]];
  if (use_proofs_2d && nearly_coplanar(s, t, a, b) && apart_at_shared_edge_2d(s, t, a, b)) return false;
  if (!CGAL::coplanar(s, t, a, b)) return false;
  return CGAL::coplanar_orientation(s, t, a, b) == CGAL::POSITIVE;
}

}  // namespace

namespace {
// The pair test on corners given by `corner(triangle, k)`: only the six points involved are
// converted (on the stack: this runs millions of times in a wrap, and a heap buffer each time
// showed in profiles); the index map keeps the shared-vertex logic.
template <typename Corner>
bool pair_intersects(const Tri& a, const Tri& b, Corner&& corner, bool use_proofs_2d) {
  std::array<P3, 6> p;
  Tri la, lb;
  std::array<uint32_t, 6> ids;
  size_t count = 0;
  auto local = [&](uint32_t v, const Vec3& at) {
    for (size_t i = 0; i < count; ++i)
      if (ids[i] == v) return uint32_t(i);
    ids[count] = v;
    p[count] = to_point(at);
    return uint32_t(count++);
  };
  for (int k = 0; k < 3; ++k) la[k] = local(a[k], corner(0, k));
  for (int k = 0; k < 3; ++k) lb[k] = local(b[k], corner(1, k));
  return triangles_intersect(p, la, lb, use_proofs_2d);
}
}  // namespace

bool triangle_pair_intersects(const std::vector<Vec3>& points, const Tri& a, const Tri& b, bool use_proofs_2d) {
  return pair_intersects(a, b, [&](int t, int k) -> const Vec3& { return points[(t == 0 ? a : b)[k]]; }, use_proofs_2d);
}

bool triangle_pair_intersects(const Corners& a_at, const Tri& a, const Corners& b_at, const Tri& b, bool use_proofs_2d) {
  return pair_intersects(a, b, [&](int t, int k) -> const Vec3& { return (t == 0 ? a_at : b_at)[k]; }, use_proofs_2d);
}

bool triangle_is_degenerate(const std::vector<Vec3>& points, const Tri& t) {
  return triangle_is_degenerate(Corners{points[t[0]], points[t[1]], points[t[2]]}, t);
}

bool triangle_is_degenerate(const Corners& at, const Tri& t) {
  return t[0] == t[1] || t[1] == t[2] || t[0] == t[2] || CGAL::collinear(to_point(at[0]), to_point(at[1]), to_point(at[2]));
}

namespace {

// A box as the pair search keeps it: plain doubles, so that millions of them are filled in
// parallel without constructing CGAL boxes (each takes a number from a shared counter).
struct Bounds {
  double lo[3], hi[3];
  double min_coord(int axis) const { return lo[axis]; }
  double max_coord(int axis) const { return hi[axis]; }
  CGAL::Bbox_3 bbox() const { return CGAL::Bbox_3(lo[0], lo[1], lo[2], hi[0], hi[1], hi[2]); }
  bool overlaps(const Bounds& o) const {
    return lo[0] <= o.hi[0] && o.lo[0] <= hi[0] && lo[1] <= o.hi[1] && o.lo[1] <= hi[1] && lo[2] <= o.hi[2] && o.lo[2] <= hi[2];
  }
  static Bounds of(const CGAL::Bbox_3& b) { return {{b.xmin(), b.ymin(), b.zmin()}, {b.xmax(), b.ymax(), b.zmax()}}; }
};

// Candidate pairs by a uniform grid. Most triangle sets checked here are wraps: triangles of a
// few sizes, spread over a surface. With cells about twice the typical triangle, a cell holds a
// handful of triangles, and sorting (cell, box) entries is cheaper than CGAL's box
// intersection, which sorts and scans all boxes along each axis at each level of its segment
// tree (measured: 1.7 s against 0.3 s for 260k wrap triangles). A pair is tested only in the
// cell holding the low corner of the two boxes' overlap, so once. Boxes spanning many cells go
// to CGAL's box intersection instead.
struct GridEntry {
  uint64_t cell;
  uint32_t group;  // boxes of one group are never paired (kNoGroup: paired with all)
  uint32_t box;
};
constexpr uint32_t kNoGroup = UINT32_MAX;

// `group` (per box): pairs within one group are left out (see star_shaped_pieces).
template <typename Test>
void grid_candidate_pairs(const FillVector<Bounds>& boxes, const std::vector<uint32_t>& group, Test&& test) {
  if (boxes.size() < 2) return;
  std::vector<double> extents;
  extents.reserve(boxes.size());
  CGAL::Bbox_3 all;
  for (const Bounds& b : boxes) {
    extents.push_back(std::max({b.max_coord(0) - b.min_coord(0), b.max_coord(1) - b.min_coord(1), b.max_coord(2) - b.min_coord(2)}));
    all += b.bbox();
  }
  std::nth_element(extents.begin(), extents.begin() + extents.size() / 2, extents.end());
  double cell = 2 * extents[extents.size() / 2];
  const double span = std::max({all.xmax() - all.xmin(), all.ymax() - all.ymin(), all.zmax() - all.zmin()});
  cell = std::max(cell, span / double(1 << 20));  // 21 bits per axis in a cell key
  if (!(cell > 0) || !std::isfinite(cell)) {
    std::vector<Box> all_boxes;
    for (size_t n = 0; n < boxes.size(); ++n) all_boxes.emplace_back(boxes[n].bbox(), n);
    CGAL::box_self_intersection_d<CGAL::Parallel_if_available_tag>(all_boxes.begin(), all_boxes.end(), [&](const Box& a, const Box& b) {
      test(uint32_t(a.handle()), uint32_t(b.handle()));
    });
    return;
  }
  const double inv = 1.0 / cell;
  auto index = [&](double x, int axis) { return int64_t((x - all.min(axis)) * inv); };  // >= 0: truncation is floor
  std::array<uint64_t, 3> cells_along;
  for (int a = 0; a < 3; ++a) cells_along[a] = uint64_t(index(all.max(a), a)) + 1;
  const DenseNumbers numbers({0, 0, 0}, cells_along);
  auto key = [&](int64_t i, int64_t j, int64_t k) { return numbers.number(i, j, k); };
  constexpr int64_t max_cells = 27;  // more, and the triangle goes to the box intersection
  auto cell_range = [&](const Bounds& b, int64_t lo[3], int64_t hi[3]) {
    for (int a = 0; a < 3; ++a) lo[a] = index(b.min_coord(a), a), hi[a] = index(b.max_coord(a), a);
    const int64_t cells = (hi[0] - lo[0] + 1) * (hi[1] - lo[1] + 1) * (hi[2] - lo[2] + 1);
    return cells > max_cells ? 0 : size_t(cells);  // 0: a large box
  };
  // The (cell, triangle) entries in parallel, in chunks of boxes joined in order, then sorted
  // by (cell, group) with a stable radix sort, so each run of one group keeps its boxes in
  // order (the order the pair loop needs; the same on any number of threads). A comparison
  // sort of the 2.37M assembly's entries took 2.2 s of a core per check.
  constexpr size_t kChunk = 4096;
  const size_t chunks = (boxes.size() + kChunk - 1) / kChunk;
  std::vector<std::vector<GridEntry>> chunk_entries(chunks);
  std::vector<uint8_t> is_large(boxes.size(), 0);
  uint32_t groups = 0;  // one more than the largest group other than kNoGroup
  for (uint32_t g : group)
    if (g != kNoGroup) groups = std::max(groups, g + 1);
  tbb::parallel_for(size_t(0), chunks, [&](size_t chunk) {
    int64_t lo[3], hi[3];
    for (size_t n = chunk * kChunk; n < std::min(boxes.size(), (chunk + 1) * kChunk); ++n) {
      if (cell_range(boxes[n], lo, hi) == 0) {
        is_large[n] = 1;
        continue;
      }
      for (int64_t i = lo[0]; i <= hi[0]; ++i)
        for (int64_t j = lo[1]; j <= hi[1]; ++j)
          for (int64_t k = lo[2]; k <= hi[2]; ++k) chunk_entries[chunk].push_back({key(i, j, k), group[n], uint32_t(n)});
    }
  });
  std::vector<Box> large;
  for (size_t n = 0; n < boxes.size(); ++n)
    if (is_large[n]) large.emplace_back(boxes[n].bbox(), n);
  // kNoGroup sorts after every group, as its number does.
  const int group_bits = bits_for(uint64_t(groups) + 1), cell_bits = bits_for(numbers.count);
  const uint64_t no_group = (uint64_t(1) << group_bits) - 1;
  FillVector<GridEntry> entries;
  if (group_bits + cell_bits <= 64) {
    entries = radix_sort_joined(
        chunk_entries, [&](const GridEntry& e) { return (e.cell << group_bits) | (e.group == kNoGroup ? no_group : uint64_t(e.group)); },
        group_bits + cell_bits);
  } else {  // a key too wide for one word
    size_t total = 0;
    for (const auto& c : chunk_entries) total += c.size();
    entries = FillVector<GridEntry>(total);
    size_t e = 0;
    for (auto& c : chunk_entries) {
      for (const GridEntry& x : c) entries[e++] = x;
      std::vector<GridEntry>().swap(c);
    }
    tbb::parallel_sort(entries.begin(), entries.end(), [](const GridEntry& x, const GridEntry& y) {
      return x.cell != y.cell ? x.cell < y.cell : x.group != y.group ? x.group < y.group : x.box < y.box;
    });
  }
  std::vector<size_t> starts;
  for (size_t e = 0; e < entries.size(); ++e)
    if (e == 0 || entries[e].cell != entries[e - 1].cell) starts.push_back(e);
  starts.push_back(entries.size());
  tbb::parallel_for(tbb::blocked_range<size_t>(0, starts.size() - 1, 64), [&](const tbb::blocked_range<size_t>& r) {
    for (size_t c = r.begin(); c != r.end(); ++c) {
      const uint64_t here = entries[starts[c]].cell;
      size_t group_end = starts[c];  // end of x's run of one group in the cell
      for (size_t x = starts[c]; x < starts[c + 1]; ++x) {
        if (x == group_end)
          while (group_end < starts[c + 1] && entries[group_end].group == entries[x].group) ++group_end;
        for (size_t y = entries[x].group == kNoGroup ? x + 1 : group_end; y < starts[c + 1]; ++y) {
          const Bounds &a = boxes[entries[x].box], &b = boxes[entries[y].box];
          if (!a.overlaps(b)) continue;
          const double cx = std::max(a.min_coord(0), b.min_coord(0)), cy = std::max(a.min_coord(1), b.min_coord(1)),
                       cz = std::max(a.min_coord(2), b.min_coord(2));
          if (key(index(cx, 0), index(cy, 1), index(cz, 2)) != here) continue;  // tested in that cell
          test(entries[x].box, entries[y].box);
        }
      }
    }
  });
  if (large.empty()) return;
  // A few large boxes (a wrap's coarse triangles: 14 among the 2.85M of the 2.37M assembly's
  // wrap) are tested against every box directly, in parallel. CGAL's box intersection would
  // sort all the small boxes for them: 4.6 s of that check's 6.5.
  constexpr size_t few = 64;
  if (large.size() <= few) {
    std::vector<uint32_t> large_ids;
    for (const Box& b : large) large_ids.push_back(uint32_t(b.handle()));
    for (size_t i = 0; i < large_ids.size(); ++i)
      for (size_t j = i + 1; j < large_ids.size(); ++j)
        if (boxes[large_ids[i]].overlaps(boxes[large_ids[j]])) test(large_ids[i], large_ids[j]);
    tbb::parallel_for(tbb::blocked_range<size_t>(0, boxes.size(), 4096), [&](const tbb::blocked_range<size_t>& r) {
      for (size_t n = r.begin(); n != r.end(); ++n) {
        if (is_large[n]) continue;
        for (uint32_t l : large_ids)
          if (boxes[l].overlaps(boxes[n])) test(l, uint32_t(n));
      }
    });
    return;
  }
  std::vector<Box> small;
  small.reserve(boxes.size() - large.size());
  for (size_t n = 0; n < boxes.size(); ++n)
    if (!is_large[n]) small.emplace_back(boxes[n].bbox(), n);
  auto report = [&](const Box& a, const Box& b) { test(uint32_t(a.handle()), uint32_t(b.handle())); };
  // Below this many boxes CGAL's segment tree scans instead of splitting further. Its default
  // (10) splits the long triangles of CAD cylinders, which share their ends' coordinates, over
  // and over (its sorting was a third of the search); measured on the 590k and 2.4M
  // assemblies: 100 and 1000 about as good, 4000 worse, 20000 twice as slow.
  constexpr std::ptrdiff_t cutoff = 300;
  CGAL::box_self_intersection_d<CGAL::Parallel_if_available_tag>(large.begin(), large.end(), report, cutoff);
  CGAL::box_intersection_d<CGAL::Parallel_if_available_tag>(large.begin(), large.end(), small.begin(), small.end(), report, cutoff);
}

// The usable triangles around each vertex, in increasing order: items[first[v] .. first[v + 1]).
using VertexStars = CompressedLists;

VertexStars vertex_stars(size_t points, const std::vector<Tri>& triangles, const std::vector<uint8_t>& usable) {
  return compressed_lists(points, [&](auto&& emit) {
    for (uint32_t t = 0; t < triangles.size(); ++t)
      if (usable[t])
        for (uint32_t v : triangles[t]) emit(v, t);
  });
}

// Vertices whose triangles form an unfolded fan: seen along the axis nearest to their common
// normal, each covers an angular sector at the vertex turning the same way, and sorted by
// angle the sectors follow one another without overlap, once round. Two such triangles that
// share only that vertex cover disjoint sectors there, so they meet only at it (a common
// point would be common in the projection too). CAD caps are such fans with thousands of
// spokes whose boxes all overlap: the caps of a 2.4M-triangle assembly gave 576 million such
// pairs, most of a minute of exact tests. Gaps between sectors (a missing spoke) are allowed;
// only vertices with many triangles are looked at.
std::vector<uint8_t> unfolded_fan_vertices(const std::vector<P3>& p, const std::vector<Tri>& triangles, const VertexStars& stars) {
  constexpr uint32_t min_fan = 16;
  const std::vector<uint32_t>& first = stars.first;
  const auto& star = stars.items;
  std::vector<uint8_t> fan(p.size(), 0);
  tbb::parallel_for(tbb::blocked_range<size_t>(0, p.size(), 4096), [&](const tbb::blocked_range<size_t>& r) {
    struct Sector {
      uint32_t a, b;     // the triangle (c, a, b) in its own order
      V2 da, db;         // a - c and b - c, projected
      double start, width;
    };
    std::vector<Sector> sectors;
    for (size_t c = r.begin(); c != r.end(); ++c) {
      if (first[c + 1] - first[c] < min_fan) continue;
      sectors.clear();
      const P3& o = p[c];
      double normal[3] = {0, 0, 0};
      for (uint32_t k = first[c]; k < first[c + 1]; ++k) {
        const Tri& t = triangles[star[k]];
        int i = 0;
        while (t[i] != c) ++i;
        const P3 &pa = p[t[(i + 1) % 3]], &pb = p[t[(i + 2) % 3]];
        const double u[3] = {pa.x() - o.x(), pa.y() - o.y(), pa.z() - o.z()}, v[3] = {pb.x() - o.x(), pb.y() - o.y(), pb.z() - o.z()};
        normal[0] += u[1] * v[2] - u[2] * v[1], normal[1] += u[2] * v[0] - u[0] * v[2], normal[2] += u[0] * v[1] - u[1] * v[0];
        sectors.push_back({t[(i + 1) % 3], t[(i + 2) % 3], {}, {}, 0, 0});
      }
      int drop = 0;
      for (int k = 1; k < 3; ++k)
        if (std::fabs(normal[k]) > std::fabs(normal[drop])) drop = k;
      const int u = (drop + 1) % 3, v = (drop + 2) % 3;
      const double mirror = normal[drop] > 0 ? 1.0 : -1.0;  // so that the fan turns counter-clockwise
      double magnitude = std::max(std::fabs(o[u]), std::fabs(o[v]));
      for (const Sector& q : sectors) magnitude = std::max({magnitude, std::fabs(p[q.a][u]), std::fabs(p[q.a][v]), std::fabs(p[q.b][u]), std::fabs(p[q.b][v])});
      const double err = 8 * std::numeric_limits<double>::epsilon() * magnitude;
      bool ok = true;
      for (Sector& q : sectors) {
        q.da = {mirror * (p[q.a][u] - o[u]), p[q.a][v] - o[v]};
        q.db = {mirror * (p[q.b][u] - o[u]), p[q.b][v] - o[v]};
        ok = ok && side(q.da, q.db, err) > 0;  // clearly turning forwards, by less than half a turn
        q.start = std::atan2(q.da[1], q.da[0]);
        q.width = std::atan2(cross2(q.da, q.db), q.da[0] * q.db[0] + q.da[1] * q.db[1]);
      }
      if (!ok) continue;
      // A repeated triangle covers the same sector twice: it is apart from the others as its
      // first copy is (the copies themselves share all three vertices and are not skipped).
      std::sort(sectors.begin(), sectors.end(), [](const Sector& x, const Sector& y) { return x.a != y.a ? x.a < y.a : x.b < y.b; });
      sectors.erase(std::unique(sectors.begin(), sectors.end(), [](const Sector& x, const Sector& y) { return x.a == y.a && x.b == y.b; }),
                    sectors.end());
      std::sort(sectors.begin(), sectors.end(), [](const Sector& x, const Sector& y) { return x.start < y.start; });
      // Each sector must end where the next one starts (the same vertex) or clearly before it.
      double total = 0;
      for (size_t k = 0; k < sectors.size() && ok; ++k) {
        const Sector &x = sectors[k], &y = sectors[(k + 1) % sectors.size()];
        double gap = 0;
        if (x.b != y.a) {
          gap = y.start - x.start - x.width + (k + 1 == sectors.size() ? 2 * M_PI : 0.0);
          ok = side(x.db, y.da, err) > 0 || gap > 0.1;
        }
        total += x.width + gap;
      }
      // Round once: sorted sectors that overlap or wind twice sum to more.
      if (ok && std::fabs(total - 2 * M_PI) < 0.5) fan[c] = 1;
    }
  });
  return fan;
}

// Vertices whose triangles close one unfolded fan round them (see closed_fan_unfolded): every
// vertex of a wrap nearly, where unfolded_fan_vertices looks only at large fans. Two triangles
// with such a corner meet only where they share, so a wrap's neighbouring pairs, most of its
// candidate pairs, need no test.
std::vector<uint8_t> closed_fan_vertices(const std::vector<Vec3>& points, const std::vector<Tri>& triangles, const VertexStars& stars) {
  std::vector<uint8_t> fan(points.size(), 0);
  tbb::parallel_for(tbb::blocked_range<size_t>(0, points.size(), 4096), [&](const tbb::blocked_range<size_t>& r) {
    std::vector<std::array<uint32_t, 2>> corners;
    for (size_t c = r.begin(); c != r.end(); ++c) {
      corners.clear();
      for (uint32_t t : stars[c]) {
        const Tri& tri = triangles[t];
        const int k = tri[0] == c ? 0 : tri[1] == c ? 1 : 2;
        corners.push_back({tri[(k + 1) % 3], tri[(k + 2) % 3]});
      }
      fan[c] = closed_fan_unfolded(points, uint32_t(c), corners.data(), corners.size());
    }
  });
  return fan;
}

// Star-shaped pieces: the triangles of each such piece get its number, the others none. Two
// triangles of such a piece meet only at their common vertices and edge, so their pairs need
// no test. A CAD assembly is mostly such pieces (cylinders, pins, boxes, spheres), and their
// long thin side triangles are what makes the pair search slow: the boxes of a tilted
// cylinder's sides nearly all overlap, half a billion pairs on the 2.4M assembly.
//
// The proof: take a point O (the piece's mean vertex) and project the piece from O onto a
// sphere around it. If that projection is one-to-one near every point of a closed piece, it
// is a covering of the sphere, and a connected covering of a sphere is one-to-one: no two
// points of the piece lie on one ray from O, so no two triangles meet but at what they share.
// Checked, on the piece with its holes closed (below):
// - closed and connected: every side of every triangle has exactly one neighbour, which runs
//   it the other way;
// - every triangle sees O strictly from the same side (CGAL's exact orientation predicate):
//   each projects one-to-one, and two triangles across an edge project to opposite sides of
//   it (their far corners lie on opposite sides of the plane through O and the edge);
// - around every vertex, the projected triangles turn once round, not twice (a sum of angles
//   in doubles: it is a whole number of turns, so a loose bound decides).
// Holes (an STL's dropped triangles) are closed first by a fan around each hole's centroid,
// for these checks only: if the closed-up piece is one-to-one, so is any part of it. Anything
// unclear leaves the piece unlabelled, and its pairs are tested as before.
constexpr uint32_t kNoPiece = kNoGroup;  // pieces are the pair search's groups

// Per triangle side (3 t + e, from corner e to corner e + 1): the triangle across it when the
// edge has exactly these two usable triangles and they run it opposite ways, and whether it is
// open (the edge's only usable triangle).
struct SideLinks {
  std::vector<uint32_t> across;
  std::vector<uint8_t> open;
};

// `known`: the edges of all the triangles, used when all are usable (the same listing).
SideLinks side_links(const std::vector<Tri>& triangles, const std::vector<uint8_t>& usable, const EdgeTriangles* known) {
  EdgeTriangles made;
  const bool all_usable = std::all_of(usable.begin(), usable.end(), [](uint8_t u) { return u != 0; });
  const EdgeTriangles& edges = known && all_usable ? *known : (made = edge_triangles(triangles, &usable));
  SideLinks out{std::vector<uint32_t>(3 * triangles.size(), kNoPiece), std::vector<uint8_t>(3 * triangles.size(), 0)};
  tbb::parallel_for(tbb::blocked_range<size_t>(0, edges.edges(), 4096), [&](const tbb::blocked_range<size_t>& r) {
    for (size_t i = r.begin(); i != r.end(); ++i) {
      const uint32_t x = edges.begin(i)[0];
      uint32_t a = uint32_t(edges.keys[i] >> 32), b = uint32_t(edges.keys[i] & 0xffffffffu);
      int ex = directed_side(triangles[x], a, b);
      if (ex < 0) std::swap(a, b), ex = directed_side(triangles[x], a, b);
      if (ex < 0) continue;  // a repeated corner
      if (edges.size(i) == 1) {
        out.open[3 * x + ex] = 1;
        continue;
      }
      if (edges.size(i) != 2) continue;
      const uint32_t y = edges.begin(i)[1];
      const int ey = directed_side(triangles[y], b, a);
      if (ey < 0) continue;  // both run it the same way
      out.across[3 * x + ex] = y;
      out.across[3 * y + ey] = x;
    }
  });
  return out;
}

// The usable triangles with every hole closed by a fan of triangles around its centroid (a
// new point). A hole is followed side by side, turning round each corner through the
// triangles there. Holes that cannot be followed (non-manifold edges on the way) stay open.
// Their side links follow from the walk: a fan triangle's first side lies across the open
// side it closes, its other two across its neighbours in the fan (no second edge sort).
struct ClosedUp {
  std::vector<P3> points;
  std::vector<Tri> triangles;  // the given ones first, at their own indexes
  std::vector<uint8_t> usable;
  std::vector<uint32_t> across;  // as SideLinks::across, for all of them
};

ClosedUp close_holes(const std::vector<P3>& p, const std::vector<Tri>& triangles, const std::vector<uint8_t>& usable,
                     const EdgeTriangles* edges) {
  ClosedUp out{p, triangles, usable, {}};
  SideLinks links = side_links(triangles, usable, edges);
  // The open side after side (t, e), which runs a -> b with a = t[e]: the hole runs b -> a and
  // goes on from a along the next open side met turning round a.
  constexpr uint32_t none = UINT32_MAX;
  auto next_open = [&](uint32_t t, int e) -> uint32_t {
    const uint32_t a = triangles[t][e];
    for (int guard = 0; guard < 1 << 20; ++guard) {
      const int s = (e + 2) % 3;  // t's side that ends at a
      if (links.open[3 * t + s]) return 3 * t + uint32_t(s);
      const uint32_t nb = links.across[3 * t + s];
      if (nb == kNoPiece) return none;
      e = directed_side(triangles[nb], a, triangles[t][s]);
      t = nb;
    }
    return none;
  };
  // A hole side: its first corner, and the open triangle side it runs back along.
  struct HoleSide {
    uint32_t corner, open_side;
  };
  std::vector<uint32_t>& across = links.across;  // grows with the fans
  auto close_with_fan = [&](const HoleSide* sides, size_t count) {
    if (count < 3) return;
    double m[3] = {0, 0, 0};
    for (size_t k = 0; k < count; ++k)
      for (int i = 0; i < 3; ++i) m[i] += p[sides[k].corner][i] / double(count);
    const uint32_t centre = uint32_t(out.points.size());
    out.points.emplace_back(m[0], m[1], m[2]);
    const uint32_t first = uint32_t(out.triangles.size());
    for (size_t k = 0; k < count; ++k) {
      const uint32_t f = first + uint32_t(k), next = first + uint32_t((k + 1) % count), prev = first + uint32_t((k + count - 1) % count);
      out.triangles.push_back({sides[k].corner, sides[(k + 1) % count].corner, centre});
      out.usable.push_back(1);
      across.insert(across.end(), {sides[k].open_side / 3, next, prev});
      across[sides[k].open_side] = f;
    }
  };
  std::vector<uint8_t> visited(links.open.size(), 0);
  std::vector<HoleSide> loop, stack;  // a walk round holes, in order
  std::vector<uint32_t> stack_at(p.size(), none);
  for (uint32_t start = 0; start < links.open.size(); ++start) {
    if (!links.open[start] || visited[start]) continue;
    loop.clear();
    uint32_t side = start;
    while (side != none && !visited[side]) {
      visited[side] = 1;
      loop.push_back({triangles[side / 3][(side % 3 + 1) % 3], side});  // the hole side's first corner, b
      side = next_open(side / 3, int(side % 3));
    }
    if (side != start) continue;  // not followed back round to its start
    // Where the walk comes back to a corner it passed (a cap's centre between two of its
    // dropped triangles), the stretch since then is a hole of its own: the walk turns into the
    // next hole at that corner, because a hole cannot be crossed to find its own other side.
    for (const HoleSide& h : loop) {
      const uint32_t w = h.corner;
      if (stack_at[w] == none) {
        stack_at[w] = uint32_t(stack.size());
        stack.push_back(h);
        continue;
      }
      close_with_fan(stack.data() + stack_at[w], stack.size() - stack_at[w]);
      for (size_t k = stack_at[w] + 1; k < stack.size(); ++k) stack_at[stack[k].corner] = none;
      stack.resize(stack_at[w]);
      stack.push_back(h);  // w goes on, now with the side leaving it
    }
    close_with_fan(stack.data(), stack.size());
    for (const HoleSide& h : stack) stack_at[h.corner] = none;
    stack.clear();
  }
  out.across = std::move(across);
  return out;
}

// Seen from `o`, do the triangles around vertex c turn once round it? (Their orientation
// towards o is checked exactly elsewhere; here only the number of turns.) Each angle must be
// well clear of 0 and of a half turn, so that its rounding cannot matter; a nearly edge-on
// view (a flat piece seen from its own plane) gives no answer.
bool turns_once(const std::vector<P3>& p, const std::vector<Tri>& triangles, const VertexStars& stars, uint32_t c, const P3& o) {
  const Vec3 w = normalized(Vec3{p[c].x() - o.x(), p[c].y() - o.y(), p[c].z() - o.z()});
  auto flat = [&](const P3& q) {  // q - c, with its part along the ray from o taken out
    const Vec3 d{q.x() - p[c].x(), q.y() - p[c].y(), q.z() - p[c].z()};
    return d - w * dot(d, w);
  };
  constexpr double clear = 1e-7;  // sine of the smallest angle trusted
  double turn = 0;
  for (uint32_t k = stars.first[c]; k < stars.first[c + 1]; ++k) {
    const Tri& t = triangles[stars.items[k]];
    int i = 0;
    while (t[i] != c) ++i;
    const Vec3 a = flat(p[t[(i + 1) % 3]]), b = flat(p[t[(i + 2) % 3]]);
    const double sine = dot(cross(a, b), w), scale = norm(a) * norm(b);
    if (!(std::fabs(sine) > clear * scale)) return false;
    turn += std::fabs(std::atan2(sine, dot(a, b)));
  }
  return std::fabs(turn - 2 * M_PI) < 1.0;
}

std::vector<uint32_t> star_shaped_pieces(const std::vector<P3>& given_points, const std::vector<Tri>& given_triangles,
                                         const std::vector<uint8_t>& given_usable, const EdgeTriangles* edges = nullptr) {
  const ClosedUp closed = close_holes(given_points, given_triangles, given_usable, edges);
  const std::vector<P3>& p = closed.points;
  const std::vector<Tri>& triangles = closed.triangles;
  const std::vector<uint8_t>& usable = closed.usable;
  const size_t n = triangles.size();
  const std::vector<uint32_t>& across = closed.across;
  // Pieces: triangles joined across such sides (a serial walk; cheap beside the rest), and
  // each piece's mean vertex (of its triangles' corners).
  std::vector<uint32_t> piece(n, kNoPiece);
  std::vector<uint8_t> ok;  // per piece
  std::vector<P3> centre;
  std::vector<uint32_t> queue;
  for (uint32_t seed = 0; seed < n; ++seed) {
    if (!usable[seed] || piece[seed] != kNoPiece) continue;
    const uint32_t id = uint32_t(ok.size());
    ok.push_back(1);
    piece[seed] = id;
    queue.assign(1, seed);
    double sum[3] = {0, 0, 0};
    for (size_t q = 0; q < queue.size(); ++q) {
      for (uint32_t v : triangles[queue[q]])
        for (int k = 0; k < 3; ++k) sum[k] += p[v][k];
      for (int e = 0; e < 3; ++e) {
        const uint32_t nb = across[3 * queue[q] + e];
        if (nb == kNoPiece) {
          ok[id] = 0;  // open, non-manifold, inconsistently oriented or beside a degenerate triangle
        } else if (piece[nb] == kNoPiece) {
          piece[nb] = id;
          queue.push_back(nb);
        }
      }
    }
    const double corners = 3.0 * double(queue.size());
    centre.emplace_back(sum[0] / corners, sum[1] / corners, sum[2] / corners);
  }
  // Triangles: each sees its piece's centre strictly from one side, the same for the piece.
  std::vector<int8_t> facing(n, 0);
  tbb::parallel_for(tbb::blocked_range<size_t>(0, n, 4096), [&](const tbb::blocked_range<size_t>& r) {
    for (size_t t = r.begin(); t != r.end(); ++t) {
      if (piece[t] == kNoPiece || !ok[piece[t]]) continue;
      const Tri& tri = triangles[t];
      facing[t] = int8_t(CGAL::orientation(p[tri[0]], p[tri[1]], p[tri[2]], centre[piece[t]]));
    }
  });
  std::vector<int8_t> piece_facing(ok.size(), 0);
  for (size_t t = 0; t < n; ++t) {
    const uint32_t id = piece[t];
    if (id == kNoPiece || !ok[id]) continue;
    if (facing[t] == 0 || (piece_facing[id] != 0 && facing[t] != piece_facing[id])) ok[id] = 0;
    piece_facing[id] = facing[t];
  }
  // Vertices: all their triangles in one piece, turning once round.
  const VertexStars stars = vertex_stars(p.size(), triangles, usable);
  std::vector<uint8_t> vertex_ok(p.size(), 1);
  tbb::parallel_for(tbb::blocked_range<size_t>(0, p.size(), 4096), [&](const tbb::blocked_range<size_t>& r) {
    for (size_t c = r.begin(); c != r.end(); ++c) {
      if (stars[c].empty()) continue;
      const uint32_t id = piece[stars.items[stars.first[c]]];
      if (!ok[id]) continue;
      bool one_piece = true;
      for (uint32_t k = stars.first[c]; k < stars.first[c + 1] && one_piece; ++k) one_piece = piece[stars.items[k]] == id;
      vertex_ok[c] = one_piece && turns_once(p, triangles, stars, uint32_t(c), centre[id]);
    }
  });
  for (size_t c = 0; c < p.size(); ++c)
    if (!vertex_ok[c])
      for (uint32_t k = stars.first[c]; k < stars.first[c + 1]; ++k) ok[piece[stars.items[k]]] = 0;
  piece.resize(given_triangles.size());  // the fans were for the checks only
  tbb::parallel_for(tbb::blocked_range<size_t>(0, piece.size(), 4096), [&](const tbb::blocked_range<size_t>& r) {
    for (size_t t = r.begin(); t != r.end(); ++t)
      if (piece[t] != kNoPiece && !ok[piece[t]]) piece[t] = kNoPiece;
  });
  return piece;
}

// Long triangles cut into slabs for the pair search. A CAD cylinder's side triangle runs its
// whole length and is a thousandth as wide; tilted, its box holds a large part of every
// neighbouring part, and it met millions of their triangles there. Cut across its longest axis
// into slabs about a grid cell thick, each slab's part of it has a box of about a cell, and
// the search meets only what is near it. A pair of triangles is then met once per pair of
// their boxes that overlap; it is tested at the first such pair (met_earlier).
struct SlabBoxes {
  FillVector<Bounds> boxes;
  std::vector<uint32_t> owner;  // triangle of each box
  std::vector<uint32_t> first;  // boxes of triangle t: first[t] .. first[t + 1] (none if unusable)

  uint32_t count(uint32_t t) const { return first[t + 1] - first[t]; }
};

CGAL::Bbox_3 triangle_box(const std::vector<P3>& p, const Tri& t) { return p[t[0]].bbox() + p[t[1]].bbox() + p[t[2]].bbox(); }
int longest_axis(const CGAL::Bbox_3& b) {
  int axis = 0;
  for (int k = 1; k < 3; ++k)
    if (b.max(k) - b.min(k) > b.max(axis) - b.min(axis)) axis = k;
  return axis;
}

// The box of the part of triangle v with coordinate `axis` in [s0, s1], widened by `pad` so
// that rounding leaves none of it out: the corners inside the slab and where the sides cross
// its two planes.
CGAL::Bbox_3 slab_part_box(const std::array<const P3*, 3>& v, int axis, double s0, double s1, double pad) {
  double lo[3] = {HUGE_VAL, HUGE_VAL, HUGE_VAL}, hi[3] = {-HUGE_VAL, -HUGE_VAL, -HUGE_VAL};
  auto add = [&](double x, double y, double z) {
    const double q[3] = {x, y, z};
    for (int k = 0; k < 3; ++k) lo[k] = std::min(lo[k], q[k]), hi[k] = std::max(hi[k], q[k]);
  };
  for (int e = 0; e < 3; ++e) {
    const P3 &a = *v[e], &b = *v[(e + 1) % 3];
    if (a[axis] >= s0 && a[axis] <= s1) add(a.x(), a.y(), a.z());
    for (double s : {s0, s1})
      if ((a[axis] - s) * (b[axis] - s) < 0) {
        const double t = (s - a[axis]) / (b[axis] - a[axis]);
        add(a.x() + t * (b.x() - a.x()), a.y() + t * (b.y() - a.y()), a.z() + t * (b.z() - a.z()));
      }
  }
  lo[axis] = std::max(lo[axis], s0), hi[axis] = std::min(hi[axis], s1);
  return CGAL::Bbox_3(lo[0] - pad, lo[1] - pad, lo[2] - pad, hi[0] + pad, hi[1] + pad, hi[2] + pad);
}

// Slab k of a triangle cut into `count` along the longest axis of its box b: [s0, s1].
std::pair<double, double> slab_range(const CGAL::Bbox_3& b, int axis, uint32_t k, uint32_t count) {
  const double width = (b.max(axis) - b.min(axis)) / count;
  return {k == 0 ? b.min(axis) : b.min(axis) + k * width, k + 1 == count ? b.max(axis) : b.min(axis) + (k + 1) * width};
}

SlabBoxes slab_boxes(const std::vector<P3>& p, const std::vector<Tri>& triangles, const std::vector<uint8_t>& usable) {
  const size_t n = triangles.size();
  SlabBoxes out;
  out.first.assign(n + 1, 0);
  std::vector<double> extents(n, -1);
  tbb::parallel_for(tbb::blocked_range<size_t>(0, n, 4096), [&](const tbb::blocked_range<size_t>& r) {
    for (size_t t = r.begin(); t != r.end(); ++t)
      if (usable[t]) {
        const CGAL::Bbox_3 b = triangle_box(p, triangles[t]);
        extents[t] = b.max(longest_axis(b)) - b.min(longest_axis(b));
      }
  });
  std::vector<double> sizes;
  for (double e : extents)
    if (e >= 0) sizes.push_back(e);
  if (sizes.empty()) return out;
  std::nth_element(sizes.begin(), sizes.begin() + sizes.size() / 2, sizes.end());
  // About the grid's cell (grid_candidate_pairs); at most 16 slabs (measured on the 2.4M
  // assembly: 8, 16 and 32 as fast; more slabs, more boxes to sort).
  const double slab = 2 * sizes[sizes.size() / 2];
  constexpr double most_slabs = 16;
  for (size_t t = 0; t < n; ++t) {
    const double length = extents[t];
    const uint32_t slabs = length < 0 ? 0 : slab > 0 && length > 4 * slab ? uint32_t(std::min(most_slabs, std::ceil(length / slab))) : 1;
    out.first[t + 1] = out.first[t] + slabs;
  }
  out.boxes.resize(out.first[n]);  // filled below, in parallel
  out.owner.resize(out.first[n]);
  const double eps = std::numeric_limits<double>::epsilon();
  tbb::parallel_for(tbb::blocked_range<size_t>(0, n, 1024), [&](const tbb::blocked_range<size_t>& r) {
    for (size_t t = r.begin(); t != r.end(); ++t) {
      const uint32_t count = out.count(uint32_t(t));
      for (uint32_t k = 0; k < count; ++k) out.owner[out.first[t] + k] = uint32_t(t);
      if (count == 0) continue;
      const CGAL::Bbox_3 b = triangle_box(p, triangles[t]);
      if (count == 1) {
        out.boxes[out.first[t]] = Bounds::of(b);
        continue;
      }
      const Tri& tri = triangles[t];
      const std::array<const P3*, 3> v{&p[tri[0]], &p[tri[1]], &p[tri[2]]};
      const int axis = longest_axis(b);
      const double magnitude = std::max({std::fabs(b.xmin()), std::fabs(b.xmax()), std::fabs(b.ymin()), std::fabs(b.ymax()),
                                         std::fabs(b.zmin()), std::fabs(b.zmax())});
      const double pad = 1e-9 * (b.max(axis) - b.min(axis)) + 64 * eps * magnitude;
      for (uint32_t k = 0; k < count; ++k) {
        const auto [s0, s1] = slab_range(b, axis, k, count);
        out.boxes[out.first[t] + k] = Bounds::of(slab_part_box(v, axis, s0, s1, pad));
      }
    }
  });
  return out;
}

// Boxes a of triangle x and b of triangle y overlap: did an earlier pair of their boxes (in the
// order of (a, b)) overlap too? Then that pair was the one to test. Only boxes that can reach
// the other triangle along the cut axis are looked at.
bool met_earlier(const SlabBoxes& s, const std::vector<P3>& p, const std::vector<Tri>& triangles, uint32_t x, uint32_t a,
                 uint32_t y, uint32_t b) {
  if (s.count(x) == 1 && s.count(y) == 1) return false;
  const CGAL::Bbox_3 bx = triangle_box(p, triangles[x]), by = triangle_box(p, triangles[y]);
  auto reaching = [&](uint32_t t, const CGAL::Bbox_3& own, const CGAL::Bbox_3& other) -> std::pair<uint32_t, uint32_t> {
    const uint32_t count = s.count(t);
    if (count == 1) return {s.first[t], s.first[t] + 1};
    const int axis = longest_axis(own);
    const double width = (own.max(axis) - own.min(axis)) / count;
    const double lo = std::floor((other.min(axis) - own.min(axis)) / width) - 1, hi = std::floor((other.max(axis) - own.min(axis)) / width) + 2;
    return {s.first[t] + uint32_t(std::clamp(lo, 0.0, double(count))), s.first[t] + uint32_t(std::clamp(hi, 0.0, double(count)))};
  };
  const auto [x0, x1] = reaching(x, bx, by);
  const auto [y0, y1] = reaching(y, by, bx);
  for (uint32_t i = x0; i <= a && i < x1; ++i)
    for (uint32_t j = y0; j < y1 && (i < a || j < b); ++j)
      if (s.boxes[i].overlaps(s.boxes[j])) return true;
  return false;
}

// A triangle's plane in doubles with a bound on its error, for a cheap first test of the
// candidate pairs: on a CAD cylinder the long side triangles' boxes nearly all overlap, a
// billion pairs on a 2.4M-triangle assembly, and the exact predicates were most of the search.
struct PlaneBound {
  Vec3 normal{0, 0, 0};  // unit
  double slope = -1;     // error of the normal's direction (radians); < 0: no plane
};

std::vector<PlaneBound> plane_bounds(const std::vector<Vec3>& points, const std::vector<Tri>& triangles,
                                     const std::vector<uint8_t>& usable) {
  double magnitude = 0;
  for (const Vec3& q : points) magnitude = std::max({magnitude, std::fabs(q[0]), std::fabs(q[1]), std::fabs(q[2])});
  const double eps = std::numeric_limits<double>::epsilon();
  std::vector<PlaneBound> out(triangles.size());
  tbb::parallel_for(tbb::blocked_range<size_t>(0, triangles.size(), 4096), [&](const tbb::blocked_range<size_t>& r) {
    for (size_t t = r.begin(); t != r.end(); ++t) {
      if (!usable[t]) continue;
      const Vec3 &a = points[triangles[t][0]], &b = points[triangles[t][1]], &c = points[triangles[t][2]];
      const Vec3 e1 = b - a, e2 = c - a, n = cross(e1, e2);
      const double len = norm(n), l1 = norm(e1), l2 = norm(e2);
      if (!(len > 0)) continue;
      // Each edge is off by up to eps * magnitude per coordinate, and the cross product's own
      // rounding is a few eps of |e1| |e2|; the direction is off by their sum over |n|.
      out[t].normal = n * (1.0 / len);
      out[t].slope = 16 * eps * (l1 * l2 + 2 * magnitude * (l1 + l2)) / len + 8 * eps;
    }
  });
  return out;
}

// Are the vertices of `other` not in `own` all clearly on one side of own's plane? Then the
// triangles meet at most at their shared vertex: apart. Vertices on the plane within the error
// give no answer.
bool clearly_beside(const std::vector<Vec3>& points, const PlaneBound& plane, const Tri& own, const Tri& other) {
  if (plane.slope < 0 || plane.slope > 1e-3) return false;
  const Vec3& a = points[own[0]];
  int side = 0;
  for (uint32_t v : other) {
    if (v == own[0] || v == own[1] || v == own[2]) continue;
    const Vec3 d = points[v] - a;
    const double distance = dot(plane.normal, d);
    const double error = plane.slope * (std::fabs(d[0]) + std::fabs(d[1]) + std::fabs(d[2])) +
                         16 * std::numeric_limits<double>::epsilon() * (std::fabs(points[v][0]) + std::fabs(points[v][1]) + std::fabs(points[v][2]) +
                                                                         std::fabs(a[0]) + std::fabs(a[1]) + std::fabs(a[2]));
    const int s = distance > error ? 1 : distance < -error ? -1 : 0;
    if (s == 0 || (side != 0 && s != side)) return false;
    side = s;
  }
  return side != 0;
}

// The points as CGAL points, and which triangles are not degenerate (the others take part in
// no pair).
struct ExactInput {
  std::vector<P3> p;
  std::vector<uint8_t> usable;
};
ExactInput exact_input(const std::vector<Vec3>& points, const std::vector<Tri>& triangles) {
  ExactInput in{std::vector<P3>(points.size()), std::vector<uint8_t>(triangles.size(), 0)};
  tbb::parallel_for(tbb::blocked_range<size_t>(0, points.size(), 8192), [&](const tbb::blocked_range<size_t>& r) {
    for (size_t i = r.begin(); i != r.end(); ++i) in.p[i] = to_point(points[i]);
  });
  tbb::parallel_for(tbb::blocked_range<size_t>(0, triangles.size(), 4096), [&](const tbb::blocked_range<size_t>& r) {
    for (size_t t = r.begin(); t != r.end(); ++t) in.usable[t] = !is_degenerate(in.p, triangles[t]);
  });
  return in;
}

}  // namespace

std::vector<TrianglePair> find_intersecting_pairs(const std::vector<Vec3>& points, const std::vector<Tri>& triangles, SoupKind kind,
                                                  const EdgeTriangles* edges) {
  const ExactInput in = exact_input(points, triangles);
  const std::vector<P3>& p = in.p;
  const std::vector<uint8_t>& usable = in.usable;
  // The input's star-shaped pieces are found beside the rest: their walk is serial (1M-triangle
  // smooth body: 55 ms on one core while the others waited).
  SlabBoxes slabs;
  std::vector<uint8_t> fan, closed_fan;
  std::vector<uint32_t> piece;
  std::vector<PlaneBound> planes;
  tbb::parallel_invoke(
      [&] {
        piece = kind == SoupKind::kInput ? star_shaped_pieces(p, triangles, usable, edges)
                                         : std::vector<uint32_t>(triangles.size(), kNoPiece);
      },
      [&] {
        slabs = slab_boxes(p, triangles, usable);
        const VertexStars stars = vertex_stars(p.size(), triangles, usable);
        fan = unfolded_fan_vertices(p, triangles, stars);
        if (kind == SoupKind::kWrap) closed_fan = closed_fan_vertices(points, triangles, stars);
        planes = plane_bounds(points, triangles, usable);
      });
  // Exact tests inside the (parallel) candidate callback: fans and long thin CAD triangles give
  // hundreds of millions of overlapping boxes, too many to store as candidates first.
  tbb::enumerable_thread_specific<std::vector<TrianglePair>> found;
  std::vector<uint32_t> box_piece(slabs.boxes.size());
  for (size_t k = 0; k < box_piece.size(); ++k) box_piece[k] = piece[slabs.owner[k]];
  grid_candidate_pairs(slabs.boxes, box_piece, [&](uint32_t box_x, uint32_t box_y) {
    uint32_t x = slabs.owner[box_x], y = slabs.owner[box_y];
    if (x == y) return;  // two slabs of one triangle
    if (piece[x] != kNoPiece && piece[x] == piece[y]) return;  // see star_shaped_pieces
    if (x > y) std::swap(x, y), std::swap(box_x, box_y);
    const Tri &tx = triangles[x], &ty = triangles[y];
    int shared = 0;
    uint32_t common = 0;
    bool in_closed_fan = false;
    for (uint32_t a : tx)
      for (uint32_t b : ty)
        if (a == b) ++shared, common = a, in_closed_fan = in_closed_fan || (!closed_fan.empty() && closed_fan[a]);
    if (shared == 1 && fan[common]) return;  // apart: see unfolded_fan_vertices
    if (in_closed_fan && shared < 3) return;  // they meet only where they share: see closed_fan_vertices
    if (shared <= 1 && (clearly_beside(points, planes[x], tx, ty) || clearly_beside(points, planes[y], ty, tx))) return;
    // The cheap proofs above may run once per pair of slabs that meet; the exact test, once.
    if (met_earlier(slabs, p, triangles, x, box_x, y, box_y)) return;
    if (triangles_intersect(p, tx, ty)) found.local().push_back({x, y});
  });
  std::vector<TrianglePair> out;
  for (const auto& local : found) out.insert(out.end(), local.begin(), local.end());
  std::sort(out.begin(), out.end(), [](const TrianglePair& u, const TrianglePair& v) { return u.a != v.a ? u.a < v.a : u.b < v.b; });
  return out;
}

bool closed_fan_unfolded(const std::vector<Vec3>& points, uint32_t c, const std::array<uint32_t, 2>* corners, size_t count) {
  constexpr size_t kMost = 64;
  if (count < 3 || count > kMost) return false;
  // Closed: each triangle's second corner is the first corner of exactly one triangle, and
  // the first corners differ (so the triangles link into cycles; the turn count below allows
  // only one).
  std::array<uint8_t, kMost> next;
  for (size_t i = 0; i < count; ++i) {
    size_t as_first = 0, as_second = 0;
    for (size_t j = 0; j < count; ++j) {
      as_first += corners[j][0] == corners[i][0];
      if (corners[j][0] == corners[i][1]) ++as_second, next[i] = uint8_t(j);
    }
    if (as_first != 1 || as_second != 1) return false;
  }
  const Vec3& o = points[c];
  Vec3 normal{0, 0, 0};
  for (size_t i = 0; i < count; ++i) normal = normal + cross(points[corners[i][0]] - o, points[corners[i][1]] - o);
  if (!(norm2(normal) > 0)) return false;
  // Any two independent axes across the normal give a linear map to the plane; the proof is
  // for that map, so they need not be exactly orthonormal.
  const Vec3 n = normalized(normal);
  const Vec3 least = std::fabs(n[0]) <= std::fabs(n[1]) && std::fabs(n[0]) <= std::fabs(n[2]) ? Vec3{1, 0, 0}
                     : std::fabs(n[1]) <= std::fabs(n[2])                                   ? Vec3{0, 1, 0}
                                                                                          : Vec3{0, 0, 1};
  const Vec3 e1 = normalized(cross(n, least)), e2 = cross(n, e1);
  // Each spoke projected once, so that a spoke two sectors share is the same numbers in both.
  std::array<std::array<double, 2>, kMost> ray;
  std::array<double, kMost> length2;
  for (size_t i = 0; i < count; ++i) {
    const Vec3 d = points[corners[i][0]] - o;
    ray[i] = {dot(e1, d), dot(e2, d)};
    length2[i] = norm2(d);
  }
  // Each sector must turn forwards by clearly more than the rounding (the differences to c
  // are exact to a relative epsilon, the projections to a few more): then its exact
  // projection turns forwards too, and each spoke's direction is off by under a millionth of
  // a radian, so the exact sectors wind as often as the computed ones. Winding: the sectors
  // that cross the first axis upwards (half-open on the computed numbers, so once each).
  int turns = 0;
  for (size_t i = 0; i < count; ++i) {
    const auto &ra = ray[i], &rb = ray[next[i]];
    const double turn = ra[0] * rb[1] - ra[1] * rb[0];
    if (!(turn > 0 && turn * turn > 1e-18 * length2[i] * length2[next[i]])) return false;
    turns += ra[1] <= 0 && rb[1] > 0;
  }
  return turns == 1;
}

std::vector<uint32_t> star_shaped_pieces(const std::vector<Vec3>& points, const std::vector<Tri>& triangles) {
  const ExactInput in = exact_input(points, triangles);
  return star_shaped_pieces(in.p, triangles, in.usable);
}

std::vector<uint32_t> intersecting_triangles(const std::vector<Vec3>& points, const std::vector<Tri>& triangles, SoupKind kind) {
  std::vector<uint32_t> out;
  for (const TrianglePair& p : find_intersecting_pairs(points, triangles, kind)) out.push_back(p.a), out.push_back(p.b);
  std::vector<uint8_t> degenerate(triangles.size(), 0);
  tbb::parallel_for(tbb::blocked_range<size_t>(0, triangles.size(), 4096), [&](const tbb::blocked_range<size_t>& r) {
    for (size_t f = r.begin(); f != r.end(); ++f) degenerate[f] = triangle_is_degenerate(points, triangles[f]);
  });
  for (uint32_t f = 0; f < triangles.size(); ++f)
    if (degenerate[f]) out.push_back(f);
  std::sort(out.begin(), out.end());
  out.erase(std::unique(out.begin(), out.end()), out.end());
  return out;
}

std::vector<TrianglePair> find_intersecting_pairs_with(const std::vector<Vec3>& points, const std::vector<Tri>& triangles,
                                                       const std::vector<uint32_t>& subset) {
  std::vector<TrianglePair> out;
  if (subset.empty()) return out;
  auto point = [&](uint32_t v) { return to_point(points[v]); };
  auto box_of = [&](uint32_t t) {
    const Tri& tri = triangles[t];
    return point(tri[0]).bbox() + point(tri[1]).bbox() + point(tri[2]).bbox();
  };
  std::vector<Box> all, some;
  all.reserve(triangles.size());
  for (uint32_t t = 0; t < triangles.size(); ++t) all.emplace_back(box_of(t), t);
  std::vector<P3> p;  // only the points the tests touch are converted, lazily through a copy
  p.reserve(points.size());
  for (const Vec3& v : points) p.push_back(to_point(v));
  for (uint32_t t : subset) {
    if (is_degenerate(p, triangles[t])) {
      out.push_back({t, t});
      continue;
    }
    some.emplace_back(box_of(t), t);
  }
  tbb::enumerable_thread_specific<std::vector<TrianglePair>> found;
  CGAL::box_intersection_d<CGAL::Parallel_if_available_tag>(some.begin(), some.end(), all.begin(), all.end(), [&](const Box& a, const Box& b) {
    const uint32_t x = uint32_t(a.handle()), y = uint32_t(b.handle());
    if (x == y || is_degenerate(p, triangles[y])) return;
    if (triangles_intersect(p, triangles[x], triangles[y])) found.local().push_back({std::min(x, y), std::max(x, y)});
  });
  for (const auto& local : found) out.insert(out.end(), local.begin(), local.end());
  std::sort(out.begin(), out.end(), [](const TrianglePair& u, const TrianglePair& v) { return u.a != v.a ? u.a < v.a : u.b < v.b; });
  out.erase(std::unique(out.begin(), out.end(), [](const TrianglePair& u, const TrianglePair& v) { return u.a == v.a && u.b == v.b; }),
            out.end());
  return out;
}

// The segments are constructed in the exact kernel. CGAL's construction in doubles is not safe
// on real inputs: where the line of the two planes runs along an edge of one triangle (a
// vertex on the other's plane, frequent on CAD grids and in CSG exports), or the planes are
// nearly parallel, or the coordinates are large (it raises them to high powers), a constructed
// point comes out non-finite and the filtered predicate that CGAL runs on it next converts it
// to a rational, which raises SIGFPE. A pair that holds a degenerate triangle (listed as a
// pair with itself), and a coplanar pair (duplicates, overlaps: they meet in an area or along
// their own edges), has no intersection line; both are settled by exact predicates first.
std::vector<Segment> intersection_segments(const std::vector<Vec3>& points, const std::vector<Tri>& triangles,
                                           const std::vector<TrianglePair>& pairs) {
  using EK = CGAL::Exact_predicates_exact_constructions_kernel;
  auto exact = [&](uint32_t v) { return EK::Point_3(points[v][0], points[v][1], points[v][2]); };
  std::vector<Segment> out;
  std::mutex lock;
  tbb::parallel_for(tbb::blocked_range<size_t>(0, pairs.size(), 64), [&](const tbb::blocked_range<size_t>& r) {
    std::vector<Segment> local;
    for (size_t i = r.begin(); i != r.end(); ++i) {
      if (pairs[i].a == pairs[i].b) continue;
      const Tri& x = triangles[pairs[i].a];
      const Tri& y = triangles[pairs[i].b];
      const P3 px[3] = {to_point(points[x[0]]), to_point(points[x[1]]), to_point(points[x[2]])};
      const P3 py[3] = {to_point(points[y[0]]), to_point(points[y[1]]), to_point(points[y[2]])};
      if (CGAL::collinear(px[0], px[1], px[2]) || CGAL::collinear(py[0], py[1], py[2])) continue;
      if (CGAL::coplanar(px[0], px[1], px[2], py[0]) && CGAL::coplanar(px[0], px[1], px[2], py[1]) &&
          CGAL::coplanar(px[0], px[1], px[2], py[2]))
        continue;
      const EK::Triangle_3 tx(exact(x[0]), exact(x[1]), exact(x[2]));
      const EK::Triangle_3 ty(exact(y[0]), exact(y[1]), exact(y[2]));
      const auto result = CGAL::intersection(tx, ty);
      const EK::Segment_3* s = result ? boost::get<EK::Segment_3>(&*result) : nullptr;
      if (!s) continue;  // a point
      const Vec3 a{CGAL::to_double(s->source().x()), CGAL::to_double(s->source().y()), CGAL::to_double(s->source().z())};
      const Vec3 b{CGAL::to_double(s->target().x()), CGAL::to_double(s->target().y()), CGAL::to_double(s->target().z())};
      if (a == b) continue;  // shorter than the doubles can tell apart
      local.push_back({a, b, pairs[i].a, pairs[i].b});
    }
    std::lock_guard<std::mutex> g(lock);
    out.insert(out.end(), local.begin(), local.end());
  });
  std::sort(out.begin(), out.end(), [](const Segment& u, const Segment& v) {
    return u.tri_a != v.tri_a ? u.tri_a < v.tri_a : u.tri_b < v.tri_b;
  });
  return out;
}

namespace {
using SurfaceMesh = CGAL::Surface_mesh<P3>;

bool build_surface_mesh(const std::vector<Vec3>& points, const std::vector<Tri>& triangles, SurfaceMesh& mesh) {
  std::vector<SurfaceMesh::Vertex_index> v(points.size());
  for (size_t i = 0; i < points.size(); ++i) v[i] = mesh.add_vertex(to_point(points[i]));
  for (const Tri& t : triangles)
    if (mesh.add_face(v[t[0]], v[t[1]], v[t[2]]) == SurfaceMesh::null_face()) return false;
  return true;
}
}  // namespace

std::vector<uint32_t> mesh_self_intersecting_faces(const std::vector<Vec3>& points, const std::vector<Tri>& triangles) {
  SurfaceMesh mesh;
  if (!build_surface_mesh(points, triangles, mesh)) throw std::logic_error("mesh_self_intersecting_faces: not a manifold mesh");
  std::vector<std::pair<SurfaceMesh::Face_index, SurfaceMesh::Face_index>> pairs;
  CGAL::Polygon_mesh_processing::self_intersections<CGAL::Parallel_if_available_tag>(mesh, std::back_inserter(pairs));
  std::vector<uint32_t> out;
  out.reserve(pairs.size() * 2);
  for (const auto& [f, g] : pairs) {
    out.push_back(uint32_t(f.idx()));
    out.push_back(uint32_t(g.idx()));
  }
  std::sort(out.begin(), out.end());
  out.erase(std::unique(out.begin(), out.end()), out.end());
  return out;
}

CgalVerdict cgal_verdict(const std::vector<Vec3>& points, const std::vector<Tri>& triangles) {
  CgalVerdict verdict;
  // A non-finite point would reach the exact predicates' rational conversion (SIGFPE): such a
  // surface is invalid without asking CGAL.
  for (const Vec3& p : points)
    if (!std::isfinite(p[0]) || !std::isfinite(p[1]) || !std::isfinite(p[2])) return verdict;
  for (const Tri& t : triangles)
    if (t[0] >= points.size() || t[1] >= points.size() || t[2] >= points.size()) return verdict;
  SurfaceMesh mesh;
  if (!build_surface_mesh(points, triangles, mesh)) return verdict;
  verdict.valid_polygon_mesh = CGAL::is_valid_polygon_mesh(mesh);
  verdict.closed = CGAL::is_closed(mesh);
  if (!verdict.valid_polygon_mesh || !verdict.closed) return verdict;
  verdict.self_intersects = CGAL::Polygon_mesh_processing::does_self_intersect<CGAL::Parallel_if_available_tag>(mesh);
  if (!verdict.self_intersects) verdict.outward = CGAL::Polygon_mesh_processing::is_outward_oriented(mesh);
  return verdict;
}

}  // namespace vdbwrap::check
