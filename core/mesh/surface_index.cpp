// CGAL AABB tree behind a small interface, so its headers stay in this file.
#include "mesh/surface_index.h"

#include <CGAL/AABB_traits.h>
#include <CGAL/AABB_tree.h>
#include <CGAL/Simple_cartesian.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <type_traits>
#include <utility>

#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>

#include "common/box_overlap.h"
#include "common/closest_point.h"
#include "common/dense_numbers.h"
#include "common/fill_vector.h"
#include "common/radix_sort.h"
#include "common/vec.h"

namespace vdbwrap::mesh {
namespace {
// Closest-point constructions need no exactness; Simple_cartesian<double> is the fast choice.
using K = CGAL::Simple_cartesian<double>;
using Triangle = K::Triangle_3;

// The tree holds pieces, not triangles. A long thin triangle (a CAD cylinder's side, a fan
// cap's spoke) has a box far larger than itself, and every query near that box had to test it.
// Triangles no larger than about the typical one are a piece each. A longer one is cut by a
// grid of cells of about the typical triangle's size: each cell it passes through is a piece
// holding every long triangle that passes through it, with the cell's box clipped to theirs.
// Pieces only bound where a triangle may be; a query always tests whole triangles, so every
// answer is the same as with whole triangles.
//
// Why cells and not parts of each triangle: side by side slivers of width w are each split
// into parts whose boxes overlap their neighbours' parts, so a query tested (part length / w)
// triangles, and the part length is fixed by the triangle's length. Finer tessellation of the
// same cylinder made w smaller, so the cost per query grew with the square of the
// tessellation, and the tree held many parts per sliver (gigabytes on big assemblies). A
// cell holds (cell size / w) slivers and each sliver is in (length / cell size) cells.
constexpr uint32_t kNoLane = UINT32_MAX;
struct Piece {
  uint32_t first, count;  // its triangles: Store::ids[first .. first + count)
  CGAL::Bbox_3 box;
  uint32_t lane = kNoLane;  // Store::lanes[lane] when its triangles are sorted along a line
};

// A crowded cell's triangles sorted along one direction: a query visits them nearest first
// along it and stops where even the nearest remaining one is farther than its best. In a cell
// of side by side slivers (a CAD cylinder's side crosses a cell in a hundred of them), the
// direction across the first sliver orders them side by side; a query then looks at the few
// beside it instead of all. Each triangle lies within `reach` of its key along `axis`, and
// the piece within [low, high] along `normal` (the first triangle's normal; a cylinder's arc
// is nearly flat across a cell): a query's distances along the two add up (as squares), so
// the slivers it looks at are those within about sqrt(best^2 - height^2) beside it, not
// within its whole distance.
struct Lane {
  Vec3 axis, normal;        // unit, perpendicular (to float precision: see triangle_gap2)
  double centre, level;     // keys and heights are measured from these
  double reach, low, high;  // the largest half extent along the axis (and the keys' float
                            // rounding); the piece's extent along the normal
  double slack;             // rounding of the projections: 1e-10 of the coordinates' size
  // The margin for a query's projections onto the axes: the piece's own rounding and that of
  // a query whose coordinates sum (in absolute value) to `coordinates`.
  double slack_at(double coordinates) const { return slack + 1e-10 * coordinates; }
};

// A triangle's own box: three orthonormal axes (along its longest edge, across it in its
// plane, along its normal) and its extent along each from its first vertex, so flat along the
// normal. The distance from a point to this box bounds its distance to the triangle from
// below, and tightly for a sliver: an axis-aligned box is fat around a sliver lying
// diagonally, and a sliver's plane passes near every point beside a convex surface. On
// finely tessellated assemblies most triangles a query looks at pass the axis-box and plane
// tests, and each then costs a closest-point computation.
// Floats: the extents are rounded outward, so the triangle stays inside whatever the axes'
// rounding; the axes are orthonormal to float precision, allowed for in triangle_gap2.
struct Frame {
  std::array<std::array<float, 3>, 3> axis;
  std::array<std::array<float, 2>, 3> extent;  // [low, high] along each axis, from vertex 0
};

struct Store {
  std::vector<Triangle> triangles;
  std::vector<Frame> frames;
  std::vector<uint32_t> ids;
  std::vector<float> keys;  // beside ids: a sorted piece's keys along its lane's axis
  std::vector<Lane> lanes;
};

// What a run of cells adds to the store (its pieces' first and lane are local to it).
struct PieceList {
  std::vector<Piece> pieces;
  std::vector<uint32_t> ids;
  std::vector<float> keys;
  std::vector<Lane> lanes;
};

Frame frame_of(const Vec3& a, const Vec3& b, const Vec3& c) {
  const Vec3 ab = b - a, bc = c - b, ca = a - c;
  const double lab = norm2(ab), lbc = norm2(bc), lca = norm2(ca);
  Vec3 e = lab >= lbc && lab >= lca ? ab : (lbc >= lca ? bc : ca);
  const double le = norm(e);
  e = le > 0 ? e * (1.0 / le) : Vec3{1, 0, 0};
  // The normal made exactly perpendicular to e; any perpendicular when the triangle has none
  // to speak of (the bound holds for any orthonormal axes: the extents come from the vertices).
  const Vec3 n0 = cross(ab, c - a);
  Vec3 n = n0 - e * dot(n0, e);
  double ln = norm(n);
  if (!(ln > 1e-6 * norm(n0))) {
    const Vec3 least = std::fabs(e[0]) <= std::fabs(e[1]) && std::fabs(e[0]) <= std::fabs(e[2]) ? Vec3{1, 0, 0}
                       : std::fabs(e[1]) <= std::fabs(e[2])                                     ? Vec3{0, 1, 0}
                                                                                                : Vec3{0, 0, 1};
    n = cross(e, least);
    ln = norm(n);
  }
  n = n * (1.0 / ln);
  const Vec3 m = cross(n, e);
  Frame f;
  const Vec3 axes[3] = {e, m, n};
  for (int k = 0; k < 3; ++k) {
    for (int j = 0; j < 3; ++j) f.axis[k][j] = float(axes[k][j]);
    const Vec3 u{f.axis[k][0], f.axis[k][1], f.axis[k][2]};  // the axis as stored
    const double sb = dot(u, ab), sc = dot(u, c - a);
    f.extent[k][0] = std::nextafter(float(std::min({0.0, sb, sc})), -INFINITY);
    f.extent[k][1] = std::nextafter(float(std::max({0.0, sb, sc})), INFINITY);
  }
  return f;
}

// A lower bound on the squared distance from q to triangle t (with frame f), less margins for
// rounding: each gap less 1e-10 of the coordinates' and the triangle's size (the dot products'
// rounding and the closest point's, so that a triangle it dismisses is also farther by the
// closest point's own arithmetic), and the sum less 1e-5 for the float axes' orthonormality.
double triangle_gap2(const Vec3& q, const Triangle& t, const Frame& f) {
  const double dx = q[0] - t.vertex(0).x(), dy = q[1] - t.vertex(0).y(), dz = q[2] - t.vertex(0).z();
  const double size = std::fabs(q[0]) + std::fabs(q[1]) + std::fabs(q[2]) + std::fabs(dx) + std::fabs(dy) +
                      std::fabs(dz) + double(f.extent[0][1] - f.extent[0][0]) + double(f.extent[1][1] - f.extent[1][0]);
  const double slack = 1e-10 * size;
  double sum = 0;
  for (int k = 0; k < 3; ++k) {
    const double s = double(f.axis[k][0]) * dx + double(f.axis[k][1]) * dy + double(f.axis[k][2]) * dz;
    const double gap = std::max(double(f.extent[k][0]) - s, s - double(f.extent[k][1])) - slack;
    if (gap > 0) sum += gap * gap;
  }
  return sum * (1 - 1e-5);
}

class PiecePrimitive {
 public:
  using Id = const Piece*;
  using Datum = Triangle;  // the first triangle; the tree's own queries are not used
  using Datum_reference = const Triangle&;
  using Point = K::Point_3;
  using Point_reference = K::Point_3;  // the centre of the piece's box, for the tree's splits
  PiecePrimitive() = default;
  PiecePrimitive(std::vector<Piece>::const_iterator it, const Store* store) : piece_(&*it), store_(store) {}
  Id id() const { return piece_; }
  Datum_reference datum() const { return store_->triangles[store_->ids[piece_->first]]; }
  Point_reference reference_point() const {
    const CGAL::Bbox_3& b = piece_->box;
    return {0.5 * (b.xmin() + b.xmax()), 0.5 * (b.ymin() + b.ymax()), 0.5 * (b.zmin() + b.zmax())};
  }

 private:
  const Piece* piece_ = nullptr;
  const Store* store_ = nullptr;
};

struct PieceBox {
  friend CGAL::Bbox_3 get(const PieceBox&, const Piece* piece) { return piece->box; }
};

using Traits = CGAL::AABB_traits<K, PiecePrimitive, PieceBox>;
using Tree = CGAL::AABB_tree<Traits>;
using Node = CGAL::AABB_node<Traits>;

Vec3 vec(const K::Point_3& p) { return {p.x(), p.y(), p.z()}; }
K::Point_3 point(const Vec3& p) { return {p[0], p[1], p[2]}; }

CGAL::Bbox_3 box_of(const Vec3& a, const Vec3& b, const Vec3& c) {
  return {std::min({a[0], b[0], c[0]}), std::min({a[1], b[1], c[1]}), std::min({a[2], b[2], c[2]}),
          std::max({a[0], b[0], c[0]}), std::max({a[1], b[1], c[1]}), std::max({a[2], b[2], c[2]})};
}
// The median (the upper one for an even count); reorders `v`.
double median(std::vector<double>& v) {
  std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
  return v[v.size() / 2];
}
double diagonal(const CGAL::Bbox_3& b) {
  return std::sqrt(std::pow(b.xmax() - b.xmin(), 2) + std::pow(b.ymax() - b.ymin(), 2) +
                   std::pow(b.zmax() - b.zmin(), 2));
}

// Calls split(x, y, z) on the two halves of triangle abc cut at the midpoint of its longest edge.
template <typename Split>
void halve_longest_edge(const Vec3& a, const Vec3& b, const Vec3& c, Split&& split) {
  const double ab = norm2(b - a), bc = norm2(c - b), ca = norm2(a - c);
  if (ab >= bc && ab >= ca) {
    const Vec3 m = (a + b) * 0.5;
    split(a, m, c), split(m, b, c);
  } else if (bc >= ca) {
    const Vec3 m = (b + c) * 0.5;
    split(a, b, m), split(a, m, c);
  } else {
    const Vec3 m = (c + a) * 0.5;
    split(a, b, m), split(m, b, c);
  }
}

// Parts of triangle abc by halving the longest edge, until a part's box is no longer than
// `size` across (at most 2^depth parts). For a triangle too large for the cell grid.
void add_parts(const Vec3& a, const Vec3& b, const Vec3& c, double size, int depth, std::vector<CGAL::Bbox_3>& out) {
  const CGAL::Bbox_3 box = box_of(a, b, c);
  if (depth == 0 || diagonal(box) <= size) {
    out.push_back(box);
    return;
  }
  halve_longest_edge(a, b, c,
                     [&](const Vec3& x, const Vec3& y, const Vec3& z) { add_parts(x, y, z, size, depth - 1, out); });
}

// The cell grid that cuts long triangles: cubes of side `cell` from `origin`, keyed by 21 bits
// per axis.
struct CellGrid {
  Vec3 origin;
  double cell;
  // Cells from -1 (a test's padding reaches below the origin) to past the far side, numbered
  // densely: a cell's key.
  DenseNumbers numbers;
  CellGrid(const Vec3& low, const Vec3& high, double size) : origin(low), cell(size) {
    std::array<uint64_t, 3> n;
    for (int a = 0; a < 3; ++a) n[a] = uint64_t(std::floor((high[a] - low[a]) / cell)) + 3;
    numbers = DenseNumbers({-1, -1, -1}, n);
  }
  int64_t index(double x, int axis) const { return int64_t(std::floor((x - origin[axis]) / cell)); }
  uint64_t key(int64_t i, int64_t j, int64_t k) const { return numbers.number(i, j, k); }
  // How far every cell test and cell box is enlarged: far beyond the rounding of the overlap
  // test and of the halving below, so that a cell a triangle touches is never missed.
  double pad() const { return 1e-6 * cell; }
  Vec3 corner(uint64_t key) const {  // the cell's low corner
    const auto c = numbers.point(key);
    return {origin[0] + double(c[0]) * cell, origin[1] + double(c[1]) * cell, origin[2] + double(c[2]) * cell};
  }
};

// The cells triangle abc passes through (keys), found by testing blocks of cells and opening
// those it meets (see for_cells_overlapping), each cell grown by the grid's pad.
void cells_of(const Vec3& a, const Vec3& b, const Vec3& c, const CellGrid& grid, std::vector<uint64_t>& out) {
  int lo[3], hi[3];
  for (int k = 0; k < 3; ++k) {
    lo[k] = int(grid.index(std::min({a[k], b[k], c[k]}) - grid.pad(), k));
    hi[k] = int(grid.index(std::max({a[k], b[k], c[k]}) + grid.pad(), k));
  }
  for_cells_overlapping(TriangleBoxTester(a, b, c), grid.origin, grid.cell, 0.5 * grid.cell + grid.pad(), lo, hi,
                        [&](int i, int j, int k) { out.push_back(grid.key(i, j, k)); });
}

// A cell's long triangles as pieces: one piece when they are few, else the cell is cut into
// eighths (`depth` times at most), each a piece with the triangles passing through it. Side
// by side slivers crowd a cell, and a fan cap's spokes all meet in the one at its centre:
// cutting crowded cells once cuts the triangles a nearest query tests by about three, and
// deeper cuts cost more in the index build and memory than they save in queries (the
// measurements: bench/results/archive, the nearest-index speed runs).
// A crowded cell whose triangles lie side by side (spread across the first one by less than
// kTightLane of the cell) stays one piece: its lane (below) already visits only the few beside
// a query, and cutting such cells was a third of the index build. Fans and crossing slivers
// are still cut.
// `lo` and `side`: the cell without padding; `pad` enlarges every test and box (see CellGrid).
constexpr size_t kPieceTriangles = 32;
constexpr int kCellCuts = 1;
// Pieces of more triangles than this are sorted along a lane.
constexpr size_t kLaneAbove = 8;

// Appends a piece of triangles `tris`, sorted along a lane when they are many: the direction
// across the first one in its plane (see Lane). `mid`: about the piece's centre.
void add_piece(const Store& store, const CGAL::Bbox_3& box, const Vec3& mid, const std::vector<uint32_t>& tris,
               PieceList& out) {
  Piece piece{uint32_t(out.ids.size()), uint32_t(tris.size()), box};
  auto add_unsorted = [&] {
    out.pieces.push_back(piece);
    out.ids.insert(out.ids.end(), tris.begin(), tris.end());
    out.keys.resize(out.ids.size(), 0.0f);
  };
  if (tris.size() <= kLaneAbove) return add_unsorted();
  const auto& m = store.frames[tris[0]].axis[1];
  const auto& n = store.frames[tris[0]].axis[2];
  const Vec3 across{m[0], m[1], m[2]}, normal{n[0], n[1], n[2]};
  Lane lane;
  lane.axis = across * (1.0 / norm(across));
  lane.normal = normal * (1.0 / norm(normal));
  lane.centre = dot(lane.axis, mid);
  lane.level = dot(lane.normal, mid);
  lane.low = INFINITY, lane.high = -INFINITY;
  double reach = 0, farthest = 0, size = 0;
  std::vector<std::pair<float, uint32_t>> keyed;
  keyed.reserve(tris.size());
  for (uint32_t f : tris) {
    const Triangle& t = store.triangles[f];
    double low = INFINITY, high = -INFINITY;
    for (int v = 0; v < 3; ++v) {
      const Vec3 p = vec(t.vertex(v));
      const double s = dot(lane.axis, p) - lane.centre;
      low = std::min(low, s), high = std::max(high, s);
      const double h = dot(lane.normal, p) - lane.level;
      lane.low = std::min(lane.low, h), lane.high = std::max(lane.high, h);
      size = std::max(size, std::fabs(p[0]) + std::fabs(p[1]) + std::fabs(p[2]));
    }
    const double key = 0.5 * (low + high);
    reach = std::max(reach, 0.5 * (high - low));
    farthest = std::max(farthest, std::fabs(key));
    keyed.push_back({float(key), f});
  }
  // Coordinates so large that the projections overflow (or their float keys would): no order
  // to rely on, nor to sort by.
  if (!std::isfinite(reach + farthest + lane.low + lane.high + size) || farthest > 1e30) return add_unsorted();
  std::sort(keyed.begin(), keyed.end());
  lane.reach = reach + 2.4e-7 * farthest;  // a float key is within 2^-23 of its double
  lane.slack = 1e-10 * (size + std::fabs(lane.centre));
  piece.lane = uint32_t(out.lanes.size());
  out.lanes.push_back(lane);
  out.pieces.push_back(piece);
  for (const auto& [key, f] : keyed) out.ids.push_back(f), out.keys.push_back(key);
}

// The largest half extent of the triangles along the direction across the first one (the
// axis a lane would sort them on): small when they lie side by side like it, large when they
// cross it (a fan's spokes).
double spread_across(const Store& store, const std::vector<uint32_t>& tris) {
  const auto& m = store.frames[tris[0]].axis[1];
  const Vec3 across{m[0], m[1], m[2]};
  double reach = 0;
  for (uint32_t f : tris) {
    const Triangle& t = store.triangles[f];
    const double a = dot(across, vec(t.vertex(0))), b = dot(across, vec(t.vertex(1))),
                 c = dot(across, vec(t.vertex(2)));
    reach = std::max(reach, 0.5 * (std::max({a, b, c}) - std::min({a, b, c})));
  }
  return reach;
}
constexpr double kTightLane = 0.125;

void add_cell_pieces(const Store& store, const Vec3& lo, double side, double pad, const std::vector<uint32_t>& tris,
                     int depth, PieceList& out) {
  if (tris.size() <= kPieceTriangles || depth == 0 || spread_across(store, tris) < kTightLane * side) {
    CGAL::Bbox_3 box;
    for (uint32_t f : tris) box += store.triangles[f].bbox();
    box = {std::max(box.xmin(), lo[0] - pad),        std::max(box.ymin(), lo[1] - pad),
           std::max(box.zmin(), lo[2] - pad),        std::min(box.xmax(), lo[0] + side + pad),
           std::min(box.ymax(), lo[1] + side + pad), std::min(box.zmax(), lo[2] + side + pad)};
    add_piece(store, box, lo + Vec3{0.5 * side, 0.5 * side, 0.5 * side}, tris, out);
    return;
  }
  const double half = 0.5 * side;
  const Vec3 centre = lo + Vec3{half, half, half};
  std::array<std::vector<uint32_t>, 8> inside;
  for (uint32_t f : tris) {
    const Triangle& t = store.triangles[f];
    const uint8_t in =
        octants_overlapped(vec(t.vertex(0)), vec(t.vertex(1)), vec(t.vertex(2)), centre, 0.5 * half, 0.5 * half + pad);
    for (int octant = 0; octant < 8; ++octant)
      if (in & (1 << octant)) inside[octant].push_back(f);
  }
  for (int octant = 0; octant < 8; ++octant) {
    const Vec3 child{lo[0] + (octant & 1 ? half : 0), lo[1] + (octant & 2 ? half : 0), lo[2] + (octant & 4 ? half : 0)};
    if (!inside[octant].empty()) add_cell_pieces(store, child, half, pad, inside[octant], depth - 1, out);
  }
}

double squared_distance_to_box(const Vec3& q, const CGAL::Bbox_3& b) {
  double d2 = 0;
  for (int k = 0; k < 3; ++k) {
    const double below = b.min(k) - q[k], above = q[k] - b.max(k);
    const double d = below > 0 ? below : (above > 0 ? above : 0.0);
    d2 += d * d;
  }
  return d2;
}

double squared_distance_to(const Vec3& q, const Triangle& t, Vec3& nearest) {
  nearest = closest_on_triangle(q, vec(t.vertex(0)), vec(t.vertex(1)), vec(t.vertex(2)));
  return norm2(nearest - q);
}

// Calls visit(triangle) on the piece's triangles that may lie within sqrt(bound) of q (all of
// them, or for a sorted piece those near enough along its lane, nearest first), until visit
// returns true. `bound` is read again after each visit: a nearest query shrinks it.
template <typename Visit>
void scan_piece(const Store& store, const Piece& piece, const Vec3& q, const double& bound, Visit&& visit) {
  const uint32_t* ids = store.ids.data() + piece.first;
  const int64_t count = piece.count;
  if (piece.lane == kNoLane) {
    for (int64_t k = 0; k < count; ++k)
      if (visit(ids[k])) return;
    return;
  }
  const Lane& lane = store.lanes[piece.lane];
  const float* keys = store.keys.data() + piece.first;
  const double at = dot(lane.axis, q) - lane.centre;
  const double slack = lane.slack_at(std::fabs(q[0]) + std::fabs(q[1]) + std::fabs(q[2]));
  const double reach = lane.reach + slack;
  const double at_height = dot(lane.normal, q) - lane.level;
  const double height = std::max(lane.low - at_height, at_height - lane.high) - slack;
  const double height2 = height > 0 ? height * height : 0.0;
  // Both sums less 1e-5 for the axes' float orthonormality, as in triangle_gap2.
  if (height2 * (1 - 1e-5) > bound) return;
  int64_t above = std::lower_bound(keys, keys + count, at, [](float key, double x) { return double(key) < x; }) - keys;
  int64_t below = above - 1;
  while (below >= 0 || above < count) {
    const double down = below >= 0 ? at - double(keys[below]) : INFINITY;
    const double up = above < count ? double(keys[above]) - at : INFINITY;
    // The nearer of the two: when it is too far, so is everything left on both sides.
    const double gap = std::min(down, up) - reach;
    if (gap > 0 && (gap * gap + height2) * (1 - 1e-5) > bound) return;
    if (visit(ids[up < down ? above++ : below--])) return;
  }
}

// Nearest triangle to a point, for CGAL's traversal_with_priority: the nearer child box first,
// a box only while it may hold something as near, and Ericson's closest point on a triangle
// (CGAL's Construct_projected_point_3 and its sphere-against-box tests cost more).
// The answer is canonical: the nearest triangle, and among equally near ones the lowest index.
// It therefore depends on the query alone, not on the traversal order nor on the start (a
// triangle near the last query's answer, see closest()), so it is the same on any thread.
class NearestTraits {
 public:
  using Priority = double;
  NearestTraits(const Vec3& q, const Store& store) : q_(q), store_(store) {}
  bool go_further() const { return true; }
  void consider(uint32_t triangle) {
    const Triangle& t = store_.triangles[triangle];
    if (triangle_gap2(q_, t, store_.frames[triangle]) > best_d2) return;  // farther than the best
    Vec3 nearest;
    const double d2 = squared_distance_to(q_, t, nearest);
    if (d2 < best_d2 || (d2 == best_d2 && triangle < best)) best_d2 = d2, best_point = nearest, best = triangle;
  }
  void intersection(const K::Point_3&, const PiecePrimitive& primitive) {
    const Piece& piece = *primitive.id();
    if (squared_distance_to_box(q_, piece.box) > best_d2) return;
    scan_piece(store_, piece, q_, best_d2, [&](uint32_t triangle) {
      consider(triangle);
      return false;
    });
  }
  // A box as near as the best is still opened: it may hold an equally near, lower triangle.
  bool do_intersect(const K::Point_3&, const Node& node) const {
    return squared_distance_to_box(q_, node.bbox()) <= best_d2;
  }
  std::pair<bool, Priority> do_intersect_with_priority(const K::Point_3&, const Node& node) const {
    const double d2 = squared_distance_to_box(q_, node.bbox());
    return {d2 <= best_d2, -d2};
  }
  double best_d2 = std::numeric_limits<double>::infinity();
  Vec3 best_point{0, 0, 0};
  uint32_t best = UINT32_MAX;

 private:
  Vec3 q_;
  const Store& store_;
};

// Is any triangle within a radius of a point? Stops at the first one.
class WithinTraits {
 public:
  WithinTraits(const Vec3& q, double radius, const Store& store) : q_(q), r2_(radius * radius), store_(store) {}
  bool go_further() const { return !found; }
  void intersection(const K::Point_3&, const PiecePrimitive& primitive) {
    const Piece& piece = *primitive.id();
    if (squared_distance_to_box(q_, piece.box) > r2_) return;
    scan_piece(store_, piece, q_, r2_, [&](uint32_t f) {
      const Triangle& t = store_.triangles[f];
      if (triangle_gap2(q_, t, store_.frames[f]) > r2_) return false;
      Vec3 nearest;
      if (squared_distance_to(q_, t, nearest) <= r2_) found = true, triangle = f;
      return found;
    });
  }
  bool do_intersect(const K::Point_3&, const Node& node) const {
    return squared_distance_to_box(q_, node.bbox()) <= r2_;
  }
  bool found = false;
  uint32_t triangle = UINT32_MAX;

 private:
  Vec3 q_;
  double r2_;
  const Store& store_;
};

// Does a query object (a triangle or a segment) meet any triangle? Stops at the first one.
template <typename Query>
class MeetsTraits {
 public:
  MeetsTraits(const Query& query, const Store& store) : box_(query.bbox()), store_(store) {
    constexpr int n = std::is_same_v<Query, Triangle> ? 3 : 2;
    corners_ = n;
    for (int v = 0; v < n; ++v) {
      corner_[v] = vec(query.vertex(v));
      size_ = std::max(size_, std::fabs(corner_[v][0]) + std::fabs(corner_[v][1]) + std::fabs(corner_[v][2]));
    }
  }
  bool go_further() const { return !found; }
  void intersection(const Query& query, const PiecePrimitive& primitive) {
    const Piece& piece = *primitive.id();
    if (!CGAL::do_overlap(box_, piece.box)) return;
    uint32_t k = piece.first, end = piece.first + piece.count;
    if (piece.lane != kNoLane && !lane_range(piece, k, end)) return;
    for (; k < end && !found; ++k) {
      const Triangle& t = store_.triangles[store_.ids[k]];
      if (CGAL::do_overlap(box_, t.bbox()) && CGAL::do_intersect(query, t)) found = true;
    }
  }
  bool do_intersect(const Query& query, const Node& node) const {
    return CGAL::do_overlap(box_, node.bbox()) && CGAL::do_intersect(query, node.bbox());
  }
  bool found = false;

 private:
  // A sorted piece (see Lane): a triangle meets the query only where their extents along the
  // lane's axis overlap, and along its normal the query must reach the piece's extent. So only
  // the triangles whose keys lie within the lane's reach of the query's extent need a test
  // ([k, end) narrowed to them; false when none can meet).
  bool lane_range(const Piece& piece, uint32_t& k, uint32_t& end) const {
    const Lane& lane = store_.lanes[piece.lane];
    double low = INFINITY, high = -INFINITY, below = INFINITY, above = -INFINITY;
    for (int v = 0; v < corners_; ++v) {
      const double at = dot(lane.axis, corner_[v]) - lane.centre, height = dot(lane.normal, corner_[v]) - lane.level;
      low = std::min(low, at), high = std::max(high, at), below = std::min(below, height),
      above = std::max(above, height);
    }
    const double slack = lane.slack_at(size_);
    if (above < lane.low - slack || below > lane.high + slack) return false;
    const double reach = lane.reach + slack;
    const float* keys = store_.keys.data();
    k = uint32_t(
        std::lower_bound(keys + k, keys + end, low - reach, [](float key, double x) { return double(key) < x; }) -
        keys);
    end = uint32_t(
        std::upper_bound(keys + k, keys + end, high + reach, [](double x, float key) { return x < double(key); }) -
        keys);
    return k < end;
  }
  CGAL::Bbox_3 box_;
  const Store& store_;
  std::array<Vec3, 3> corner_;
  int corners_ = 0;
  double size_ = 0;
};
}  // namespace

struct SurfaceIndex::Impl {
  Store store;
  std::vector<Piece> pieces;
  Tree tree;
};

SurfaceIndex::SurfaceIndex(const std::vector<Vec3>& points, const std::vector<Tri>& triangles) : impl_(new Impl) {
  Store& store = impl_->store;
  store.triangles.resize(triangles.size());
  store.frames.resize(triangles.size());
  std::vector<double> sizes(triangles.size()), widths(triangles.size());
  const CGAL::Bbox_3 all = tbb::parallel_reduce(
      tbb::blocked_range<size_t>(0, triangles.size(), 4096), CGAL::Bbox_3(),
      [&](const tbb::blocked_range<size_t>& r, CGAL::Bbox_3 part) {
        for (size_t f = r.begin(); f != r.end(); ++f) {
          const Vec3 &a = points[triangles[f][0]], &b = points[triangles[f][1]], &c = points[triangles[f][2]];
          store.triangles[f] = Triangle(point(a), point(b), point(c));
          store.frames[f] = frame_of(a, b, c);
          const CGAL::Bbox_3 box = box_of(a, b, c);
          sizes[f] = diagonal(box);
          widths[f] = std::sqrt(norm(area_vector(a, b, c)));
          part += box;
        }
        return part;
      },
      [](const CGAL::Bbox_3& x, const CGAL::Bbox_3& y) { return x + y; });
  if (triangles.empty()) return;
  // Pieces about twice the typical triangle: the typical one stays whole. Where most triangles
  // are needles (a long part tessellated by a few rings), the typical box is a needle's length
  // and nothing would be cut: each needle's box covers the part's width over its length, and a
  // query near the part tested them all. The size is then set by the triangles' areas (the
  // side of a square of twice the area: a well-shaped triangle's box diagonal is less than
  // twice that, so meshes of such triangles keep the size of their boxes). Not below a 64th of
  // the typical box, so that flat triangles cannot shrink the cells to nothing.
  const double typical = median(sizes);
  const double size = 2 * std::max(std::min(typical, 2 * median(widths)), typical / 64);
  const double span = std::max({all.xmax() - all.xmin(), all.ymax() - all.ymin(), all.zmax() - all.zmin()});
  const CellGrid grid({all.xmin(), all.ymin(), all.zmin()}, {all.xmax(), all.ymax(), all.zmax()},
                      std::max(size, span / double(1 << 20)));
  // A triangle over this many cells is cut into at most 16 parts instead (a huge flat triangle
  // among tiny ones would otherwise fill the grid).
  constexpr double max_cells = 4096;

  // Long triangles: (cell, triangle) entries, found in parallel in chunks of triangles joined
  // in order, then sorted by cell, stably: each cell's triangles stay in order.
  struct Entry {
    uint64_t cell;
    uint32_t triangle;
  };
  constexpr uint32_t kChunk = 4096;
  const size_t chunks = (triangles.size() + kChunk - 1) / kChunk;
  std::vector<std::vector<Entry>> chunk_entries(chunks);
  std::vector<std::vector<std::pair<uint32_t, CGAL::Bbox_3>>> chunk_parts(chunks);
  tbb::parallel_for(size_t(0), chunks, [&](size_t chunk) {
    std::vector<uint64_t> cells;
    std::vector<CGAL::Bbox_3> boxes;
    const uint32_t first = uint32_t(chunk * kChunk), last = uint32_t(std::min(triangles.size(), (chunk + 1) * kChunk));
    for (uint32_t f = first; f != last; ++f) {
      const Tri& t = triangles[f];
      const Vec3 &a = points[t[0]], &b = points[t[1]], &c = points[t[2]];
      if (diagonal(box_of(a, b, c)) <= size) continue;
      const double cell = grid.cell;
      const double estimate =
          norm(area_vector(a, b, c)) / (cell * cell) + (norm(b - a) + norm(c - b) + norm(a - c)) / cell;
      if (estimate > max_cells) {
        boxes.clear();
        add_parts(a, b, c, size, 4, boxes);
        for (const CGAL::Bbox_3& box : boxes) chunk_parts[chunk].push_back({f, box});
        continue;
      }
      cells.clear();
      cells_of(a, b, c, grid, cells);  // each once: (cell, triangle) entries are distinct
      for (uint64_t key : cells) chunk_entries[chunk].push_back({key, f});
    }
  });
  const FillVector<Entry> cut = radix_sort_joined(
      chunk_entries, [](const Entry& e) { return e.cell; }, bits_for(grid.numbers.count));
  std::vector<std::pair<uint32_t, CGAL::Bbox_3>> large;  // by triangle
  for (const auto& part : chunk_parts) large.insert(large.end(), part.begin(), part.end());

  // Pieces: each short triangle, each part of a huge one, and each cell with its long ones.
  impl_->pieces.reserve(triangles.size());
  store.ids.reserve(triangles.size() + cut.size());
  for (uint32_t f = 0; f < triangles.size(); ++f) {
    const CGAL::Bbox_3 box = store.triangles[f].bbox();
    if (diagonal(box) > size) continue;
    impl_->pieces.push_back({uint32_t(store.ids.size()), 1, box});
    store.ids.push_back(f);
  }
  for (const auto& [f, box] : large) {
    impl_->pieces.push_back({uint32_t(store.ids.size()), 1, box});
    store.ids.push_back(f);
  }
  store.keys.resize(store.ids.size(), 0.0f);
  // The cells' pieces in parallel, in runs of cells, then appended in cell order.
  const std::vector<size_t> cell_starts = run_starts(cut, [](const auto& c) { return c.cell; });
  constexpr size_t kCellsPerRun = 256;
  const size_t cells = cell_starts.size() - 1, runs = (cells + kCellsPerRun - 1) / kCellsPerRun;
  std::vector<PieceList> run_lists(runs);
  tbb::parallel_for(size_t(0), runs, [&](size_t run) {
    std::vector<uint32_t> in_cell;
    for (size_t c = run * kCellsPerRun; c < std::min(cells, (run + 1) * kCellsPerRun); ++c) {
      in_cell.clear();
      for (size_t e = cell_starts[c]; e < cell_starts[c + 1]; ++e) in_cell.push_back(cut[e].triangle);
      add_cell_pieces(store, grid.corner(cut[cell_starts[c]].cell), grid.cell, grid.pad(), in_cell, kCellCuts,
                      run_lists[run]);
    }
  });
  for (PieceList& list : run_lists) {
    const uint32_t offset = uint32_t(store.ids.size()), lanes = uint32_t(store.lanes.size());
    for (Piece piece : list.pieces) {
      piece.first += offset;
      if (piece.lane != kNoLane) piece.lane += lanes;
      impl_->pieces.push_back(piece);
    }
    store.ids.insert(store.ids.end(), list.ids.begin(), list.ids.end());
    store.keys.insert(store.keys.end(), list.keys.begin(), list.keys.end());
    store.lanes.insert(store.lanes.end(), list.lanes.begin(), list.lanes.end());
    list = PieceList();  // its memory back now
  }
  impl_->tree.insert(impl_->pieces.cbegin(), impl_->pieces.cend(), &store);
  impl_->tree.build();
}

SurfaceIndex::~SurfaceIndex() = default;

namespace {
// Start from the triangle this thread found last on this index: queries come in runs along
// a surface, so it is usually near, and a near start prunes most of the tree. The answer
// does not depend on it (see NearestTraits). A traversal starting at best_d2 = r^2 finds the
// same nearest triangle when one is within r (a triangle exactly at r is still taken).
thread_local const void* last_closest_index = nullptr;
thread_local uint32_t last_closest_triangle = UINT32_MAX;
}  // namespace

SurfaceIndex::Hit SurfaceIndex::closest(const Vec3& q, uint32_t hint) const {
  Hit hit;
  if (!closest_within(q, std::numeric_limits<double>::infinity(), hit, hint)) {  // no input triangles
    hit.point = q, hit.triangle = UINT32_MAX, hit.squared_distance = std::numeric_limits<double>::infinity(),
    hit.normal = {0, 0, 0};
  }
  return hit;
}

bool SurfaceIndex::closest_within(const Vec3& q, double radius, Hit& hit, uint32_t hint) const {
  const Store& store = impl_->store;
  NearestTraits traits(q, store);
  traits.best_d2 = radius * radius;
  if (hint < store.triangles.size()) traits.consider(hint);
  if (last_closest_index == impl_.get() && last_closest_triangle < store.triangles.size() &&
      last_closest_triangle != hint)
    traits.consider(last_closest_triangle);
  impl_->tree.traversal_with_priority(point(q), traits);
  if (traits.best == UINT32_MAX) return false;
  last_closest_index = impl_.get(), last_closest_triangle = traits.best;
  hit = hit_on(q, traits.best);  // the traversal's point and distance, computed the same way
  return true;
}

SurfaceIndex::Hit SurfaceIndex::hit_on(const Vec3& q, uint32_t triangle) const {
  const Triangle& t = impl_->store.triangles[triangle];
  Hit hit;
  hit.triangle = triangle;
  hit.squared_distance = squared_distance_to(q, t, hit.point);
  K::Vector_3 n = CGAL::cross_product(t.vertex(1) - t.vertex(0), t.vertex(2) - t.vertex(0));
  double len = std::sqrt(n.squared_length());
  hit.normal = len > 0 ? Vec3{n.x() / len, n.y() / len, n.z() / len} : Vec3{0, 0, 0};
  return hit;
}

bool SurfaceIndex::within(const Vec3& q, double radius) const {
  // The triangle that answered this thread's last query on this index is tried first: queries
  // come in runs along a surface. (A yes or no does not depend on which triangle says it.)
  thread_local const Impl* last_index = nullptr;
  thread_local uint32_t last_triangle = UINT32_MAX;
  const uint32_t hint = last_index == impl_.get() ? last_triangle : UINT32_MAX;
  uint32_t found = UINT32_MAX;
  const bool yes = within(q, radius, &hint, 1, &found);
  if (found != UINT32_MAX) last_index = impl_.get(), last_triangle = found;
  return yes;
}

bool SurfaceIndex::within(const Vec3& q, double radius, const uint32_t* hints, size_t count, uint32_t* found) const {
  const Store& store = impl_->store;
  Vec3 nearest;
  for (size_t k = 0; k < count; ++k)
    if (hints[k] < store.triangles.size() &&
        squared_distance_to(q, store.triangles[hints[k]], nearest) <= radius * radius)
      return true;
  WithinTraits traits(q, radius, store);
  impl_->tree.traversal(point(q), traits);
  if (traits.found && found) *found = traits.triangle;
  return traits.found;
}

bool SurfaceIndex::touches(const Vec3& a, const Vec3& b, const Vec3& c) const {
  const Triangle t(point(a), point(b), point(c));
  if (t.is_degenerate()) return true;
  if (impl_->pieces.empty()) return false;
  MeetsTraits<Triangle> traits(t, impl_->store);
  impl_->tree.traversal(t, traits);
  return traits.found;
}

bool SurfaceIndex::in_view(const Vec3& from, const Vec3& on, double near) const {
  const double dx = from[0] - on[0], dy = from[1] - on[1], dz = from[2] - on[2];
  const double len = std::sqrt(dx * dx + dy * dy + dz * dz);
  if (len <= near) return true;
  if (impl_->pieces.empty()) return true;
  const double k = 0.5 * near / len;  // stop short: the segment's end lies on the input
  const K::Segment_3 s(point(from), K::Point_3(on[0] + dx * k, on[1] + dy * k, on[2] + dz * k));
  MeetsTraits<K::Segment_3> traits(s, impl_->store);
  impl_->tree.traversal(s, traits);
  return !traits.found;
}

}  // namespace vdbwrap::mesh
