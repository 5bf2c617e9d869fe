// CGAL AABB tree behind a small interface, so its headers stay in this file.
#include "fit/surface_index.h"

#include <CGAL/AABB_traits.h>
#include <CGAL/AABB_tree.h>
#include <CGAL/AABB_triangle_primitive.h>
#include <CGAL/Simple_cartesian.h>

#include <algorithm>
#include <atomic>
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

// A serial per index, so the hint of an index freed and another made at the same address
// is not taken for the new one's.
namespace {
std::atomic<uint64_t> next_serial{1};
}  // namespace

struct SurfaceIndex::Impl {
  std::vector<Triangle> triangles;
  Tree tree;
  uint64_t serial = next_serial.fetch_add(1);
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
  // The search prunes by the best distance so far, so a close first guess saves most of it.
  // Queries come in runs of neighbours (the nodes or triangles of one block of a parallel
  // loop), so the triangle this thread found last is usually nearest again, or nearly so.
  thread_local uint64_t last_index = 0;
  thread_local size_t last_triangle = 0;
  Tree::Point_and_primitive_id hint = impl_->tree.best_hint(query);
  if (last_index == impl_->serial && last_triangle < impl_->triangles.size()) {
    const auto it = impl_->triangles.cbegin() + long(last_triangle);
    const K::Point_3 on = K::Construct_projected_point_3()(*it, query);
    if (CGAL::squared_distance(query, on) < CGAL::squared_distance(query, hint.first)) hint = {on, it};
  }
  auto [point, it] = impl_->tree.closest_point_and_primitive(query, hint);
  last_index = impl_->serial;
  last_triangle = size_t(it - impl_->triangles.cbegin());
  Hit hit;
  hit.point = {point.x(), point.y(), point.z()};
  hit.triangle = uint32_t(it - impl_->triangles.cbegin());
  hit.squared_distance = CGAL::squared_distance(query, point);
  K::Vector_3 n = CGAL::cross_product(it->vertex(1) - it->vertex(0), it->vertex(2) - it->vertex(0));
  double len = std::sqrt(n.squared_length());
  hit.normal = len > 0 ? Vec3{n.x() / len, n.y() / len, n.z() / len} : Vec3{0, 0, 0};
  return hit;
}

double SurfaceIndex::squared_distance_unhinted(const Vec3& q) const {
  const K::Point_3 query(q[0], q[1], q[2]);
  return CGAL::squared_distance(query, impl_->tree.closest_point(query));
}

uint32_t SurfaceIndex::closest_triangle_unhinted(const Vec3& q) const {
  const auto hit = impl_->tree.closest_point_and_primitive(K::Point_3(q[0], q[1], q[2]));
  return uint32_t(hit.second - impl_->triangles.cbegin());
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
