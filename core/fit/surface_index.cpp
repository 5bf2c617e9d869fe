// CGAL AABB tree behind a small interface, so its headers stay in this file.
#include "fit/surface_index.h"

#include <CGAL/AABB_traits.h>
#include <CGAL/AABB_tree.h>
#include <CGAL/AABB_triangle_primitive.h>
#include <CGAL/Simple_cartesian.h>

#include <algorithm>
#include <cmath>

namespace vdbwrap::fit {
namespace {
// Closest-point constructions need no exactness; Simple_cartesian<double> is the fast choice.
using K = CGAL::Simple_cartesian<double>;
using Triangle = K::Triangle_3;
using Iterator = std::vector<Triangle>::const_iterator;
using Primitive = CGAL::AABB_triangle_primitive<K, Iterator>;
using Tree = CGAL::AABB_tree<CGAL::AABB_traits<K, Primitive>>;
}  // namespace

struct SurfaceIndex::Impl {
  std::vector<Triangle> triangles;
  Tree tree;
};

SurfaceIndex::SurfaceIndex(const std::vector<Vec3>& points, const std::vector<Tri>& triangles) : impl_(new Impl) {
  impl_->triangles.reserve(triangles.size());
  for (const Tri& t : triangles) {
    const Vec3 &a = points[t[0]], &b = points[t[1]], &c = points[t[2]];
    impl_->triangles.emplace_back(K::Point_3(a[0], a[1], a[2]), K::Point_3(b[0], b[1], b[2]), K::Point_3(c[0], c[1], c[2]));
  }
  impl_->tree.insert(impl_->triangles.cbegin(), impl_->triangles.cend());
  impl_->tree.build();
  impl_->tree.accelerate_distance_queries();
}

SurfaceIndex::~SurfaceIndex() = default;

SurfaceIndex::Hit SurfaceIndex::closest(const Vec3& q) const {
  K::Point_3 query(q[0], q[1], q[2]);
  // CGAL's own start (its kd-tree hint) only: the answer is a function of the query, so that
  // where two triangles are equally near the same one wins on every run and thread count.
  // (Starting from the triangle this thread found last saved 6 % on a large assembly, but
  // ties then went either way.)
  auto [point, it] = impl_->tree.closest_point_and_primitive(query);
  Hit hit;
  hit.point = {point.x(), point.y(), point.z()};
  hit.triangle = uint32_t(it - impl_->triangles.cbegin());
  hit.squared_distance = CGAL::squared_distance(query, point);
  K::Vector_3 n = CGAL::cross_product(it->vertex(1) - it->vertex(0), it->vertex(2) - it->vertex(0));
  double len = std::sqrt(n.squared_length());
  hit.normal = len > 0 ? Vec3{n.x() / len, n.y() / len, n.z() / len} : Vec3{0, 0, 0};
  return hit;
}

bool SurfaceIndex::within(const Vec3& q, double radius) const {
  return impl_->tree.do_intersect(K::Sphere_3(K::Point_3(q[0], q[1], q[2]), radius * radius));
}

bool SurfaceIndex::touches(const Vec3& a, const Vec3& b, const Vec3& c) const {
  const Triangle t(K::Point_3(a[0], a[1], a[2]), K::Point_3(b[0], b[1], b[2]), K::Point_3(c[0], c[1], c[2]));
  if (t.is_degenerate()) return true;
  return impl_->tree.do_intersect(t);
}

bool SurfaceIndex::in_view(const Vec3& from, const Vec3& on, double near) const {
  const double dx = from[0] - on[0], dy = from[1] - on[1], dz = from[2] - on[2];
  const double len = std::sqrt(dx * dx + dy * dy + dz * dz);
  if (len <= near) return true;
  const double k = 0.5 * near / len;  // stop short: the segment's end lies on the input
  const K::Segment_3 s(K::Point_3(from[0], from[1], from[2]), K::Point_3(on[0] + dx * k, on[1] + dy * k, on[2] + dz * k));
  return !impl_->tree.do_intersect(s);
}

}  // namespace vdbwrap::fit
