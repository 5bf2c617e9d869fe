// CGAL AABB tree behind a small interface, so its headers stay in this file.
#include "fit/surface_index.h"

#include <CGAL/AABB_traits.h>
#include <CGAL/AABB_tree.h>
#include <CGAL/Simple_cartesian.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>

#include "common/closest_point.h"
#include "common/vec.h"

namespace vdbwrap::fit {
namespace {
// Closest-point constructions need no exactness; Simple_cartesian<double> is the fast choice.
using K = CGAL::Simple_cartesian<double>;
using Triangle = K::Triangle_3;

// The tree holds pieces of triangles, not triangles. A long thin triangle (a CAD cylinder's side,
// a fan cap's spoke) has a box far larger than itself, and every query near that box had to test
// it: on a CAD assembly a nearest-point query tested 140 triangles. Each piece has the box of one
// part of its triangle (the parts cover the triangle), while its datum stays the whole triangle,
// so every answer is the same as with whole triangles.
struct Piece {
  uint32_t triangle;
  CGAL::Bbox_3 box;
};

class PiecePrimitive {
 public:
  using Id = const Piece*;
  using Datum = Triangle;
  using Datum_reference = const Triangle&;
  using Point = K::Point_3;
  using Point_reference = K::Point_3;  // the centre of the part's box, for the tree's splits
  PiecePrimitive() = default;
  PiecePrimitive(std::vector<Piece>::const_iterator it, const std::vector<Triangle>* triangles)
      : piece_(&*it), triangles_(triangles) {}
  Id id() const { return piece_; }
  Datum_reference datum() const { return (*triangles_)[piece_->triangle]; }
  Point_reference reference_point() const {
    const CGAL::Bbox_3& b = piece_->box;
    return {0.5 * (b.xmin() + b.xmax()), 0.5 * (b.ymin() + b.ymax()), 0.5 * (b.zmin() + b.zmax())};
  }

 private:
  const Piece* piece_ = nullptr;
  const std::vector<Triangle>* triangles_ = nullptr;
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
double diagonal(const CGAL::Bbox_3& b) {
  return std::sqrt(std::pow(b.xmax() - b.xmin(), 2) + std::pow(b.ymax() - b.ymin(), 2) + std::pow(b.zmax() - b.zmin(), 2));
}

// Parts of triangle abc by halving the longest edge, until a part's box is no longer than
// `size` across (at most 2^depth parts).
void add_pieces(uint32_t triangle, const Vec3& a, const Vec3& b, const Vec3& c, double size, int depth, std::vector<Piece>& out) {
  const CGAL::Bbox_3 box = box_of(a, b, c);
  if (depth == 0 || diagonal(box) <= size) {
    out.push_back({triangle, box});
    return;
  }
  const double ab = norm2(b - a), bc = norm2(c - b), ca = norm2(a - c);
  if (ab >= bc && ab >= ca) {
    const Vec3 m = (a + b) * 0.5;
    add_pieces(triangle, a, m, c, size, depth - 1, out), add_pieces(triangle, m, b, c, size, depth - 1, out);
  } else if (bc >= ca) {
    const Vec3 m = (b + c) * 0.5;
    add_pieces(triangle, a, b, m, size, depth - 1, out), add_pieces(triangle, a, m, c, size, depth - 1, out);
  } else {
    const Vec3 m = (c + a) * 0.5;
    add_pieces(triangle, a, b, m, size, depth - 1, out), add_pieces(triangle, m, b, c, size, depth - 1, out);
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

// Nearest triangle to a point, for CGAL's traversal_with_priority: the nearer child box first,
// a box only while it may hold something as near, and Ericson's closest point on a triangle
// (CGAL's Construct_projected_point_3 and its sphere-against-box tests cost more).
// The answer is canonical: the nearest triangle, and among equally near ones the lowest index.
// It therefore depends on the query alone, not on the traversal order nor on the start (a
// triangle near the last query's answer, see closest()), so it is the same on any thread.
class NearestTraits {
 public:
  using Priority = double;
  explicit NearestTraits(const Vec3& q) : q_(q) {}
  bool go_further() const { return true; }
  void consider(uint32_t triangle, const Triangle& t) {
    Vec3 nearest;
    const double d2 = squared_distance_to(q_, t, nearest);
    if (d2 < best_d2 || (d2 == best_d2 && triangle < best)) best_d2 = d2, best_point = nearest, best = triangle;
  }
  void intersection(const K::Point_3&, const PiecePrimitive& primitive) { consider(primitive.id()->triangle, primitive.datum()); }
  // A box as near as the best is still opened: it may hold an equally near, lower triangle.
  bool do_intersect(const K::Point_3&, const Node& node) const { return squared_distance_to_box(q_, node.bbox()) <= best_d2; }
  std::pair<bool, Priority> do_intersect_with_priority(const K::Point_3&, const Node& node) const {
    const double d2 = squared_distance_to_box(q_, node.bbox());
    return {d2 <= best_d2, -d2};
  }
  double best_d2 = std::numeric_limits<double>::infinity();
  Vec3 best_point{0, 0, 0};
  uint32_t best = UINT32_MAX;

 private:
  Vec3 q_;
};

// Is any triangle within a radius of a point? Stops at the first one.
class WithinTraits {
 public:
  WithinTraits(const Vec3& q, double radius) : q_(q), r2_(radius * radius) {}
  bool go_further() const { return !found; }
  void intersection(const K::Point_3&, const PiecePrimitive& primitive) {
    Vec3 nearest;
    if (squared_distance_to(q_, primitive.datum(), nearest) <= r2_) found = true, triangle = primitive.id()->triangle;
  }
  bool do_intersect(const K::Point_3&, const Node& node) const { return squared_distance_to_box(q_, node.bbox()) <= r2_; }
  bool found = false;
  uint32_t triangle = UINT32_MAX;

 private:
  Vec3 q_;
  double r2_;
};
}  // namespace

struct SurfaceIndex::Impl {
  std::vector<Triangle> triangles;
  std::vector<Piece> pieces;
  Tree tree;
};

SurfaceIndex::SurfaceIndex(const std::vector<Vec3>& points, const std::vector<Tri>& triangles) : impl_(new Impl) {
  impl_->triangles.reserve(triangles.size());
  std::vector<double> sizes;
  sizes.reserve(triangles.size());
  for (const Tri& t : triangles) {
    const Vec3 &a = points[t[0]], &b = points[t[1]], &c = points[t[2]];
    impl_->triangles.emplace_back(point(a), point(b), point(c));
    sizes.push_back(diagonal(box_of(a, b, c)));
  }
  if (triangles.empty()) return;
  // Parts no larger than twice the typical triangle: the typical one stays whole, and a sliver
  // becomes a chain of parts of about that size, at most 16 (measured on a CAD assembly: 16
  // parts as fast as 64, with 30 MB less; 8 slower).
  std::nth_element(sizes.begin(), sizes.begin() + sizes.size() / 2, sizes.end());
  const double size = 2 * sizes[sizes.size() / 2];
  impl_->pieces.reserve(triangles.size() + triangles.size() / 4);
  for (uint32_t f = 0; f < triangles.size(); ++f) {
    const Tri& t = triangles[f];
    add_pieces(f, points[t[0]], points[t[1]], points[t[2]], size, 4, impl_->pieces);
  }
  impl_->tree.insert(impl_->pieces.cbegin(), impl_->pieces.cend(), &impl_->triangles);
  impl_->tree.build();
}

SurfaceIndex::~SurfaceIndex() = default;

SurfaceIndex::Hit SurfaceIndex::closest(const Vec3& q) const {
  // Start from the triangle this thread found last on this index: queries come in runs along
  // a surface, so it is usually near, and a near start prunes most of the tree. The answer
  // does not depend on it (see NearestTraits).
  thread_local const Impl* last_index = nullptr;
  thread_local uint32_t last_triangle = UINT32_MAX;
  NearestTraits traits(q);
  if (last_index == impl_.get() && last_triangle < impl_->triangles.size())
    traits.consider(last_triangle, impl_->triangles[last_triangle]);
  impl_->tree.traversal_with_priority(point(q), traits);
  last_index = impl_.get(), last_triangle = traits.best;
  Hit hit;
  if (traits.best == UINT32_MAX) {  // no input triangles
    hit.point = q, hit.triangle = UINT32_MAX, hit.squared_distance = traits.best_d2, hit.normal = {0, 0, 0};
    return hit;
  }
  hit.point = traits.best_point;
  hit.triangle = traits.best;
  hit.squared_distance = traits.best_d2;
  const Triangle& t = impl_->triangles[traits.best];
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
  if (last_index == impl_.get() && last_triangle < impl_->triangles.size()) {
    Vec3 nearest;
    if (squared_distance_to(q, impl_->triangles[last_triangle], nearest) <= radius * radius) return true;
  }
  WithinTraits traits(q, radius);
  impl_->tree.traversal(point(q), traits);
  if (traits.found) last_index = impl_.get(), last_triangle = traits.triangle;
  return traits.found;
}

bool SurfaceIndex::touches(const Vec3& a, const Vec3& b, const Vec3& c) const {
  const Triangle t(point(a), point(b), point(c));
  if (t.is_degenerate()) return true;
  return impl_->tree.do_intersect(t);
}

bool SurfaceIndex::in_view(const Vec3& from, const Vec3& on, double near) const {
  const double dx = from[0] - on[0], dy = from[1] - on[1], dz = from[2] - on[2];
  const double len = std::sqrt(dx * dx + dy * dy + dz * dz);
  if (len <= near) return true;
  const double k = 0.5 * near / len;  // stop short: the segment's end lies on the input
  const K::Segment_3 s(point(from), K::Point_3(on[0] + dx * k, on[1] + dy * k, on[2] + dz * k));
  return !impl_->tree.do_intersect(s);
}

}  // namespace vdbwrap::fit
