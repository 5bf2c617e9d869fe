// Nearest-point queries on a triangle set (CGAL AABB tree). Thread-safe queries once built;
// every answer is a function of the query alone (the same on any thread, in any order).
#pragma once
#include <cstdint>
#include <memory>
#include <vector>

#include "vdbwrap/mesh.h"

namespace vdbwrap::mesh {

class SurfaceIndex {
 public:
  SurfaceIndex(const std::vector<Vec3>& points, const std::vector<Tri>& triangles);
  ~SurfaceIndex();
  SurfaceIndex(const SurfaceIndex&) = delete;
  SurfaceIndex& operator=(const SurfaceIndex&) = delete;

  struct Hit {
    Vec3 point;
    uint32_t triangle;
    double squared_distance;
    Vec3 normal;  // unit normal of the triangle hit (its vertex order decides the sign)
  };
  // `hint`: a triangle likely near the query (UINT32_MAX: none), tried first so that the
  // tree opens fewer boxes. The answer does not depend on it.
  Hit closest(const Vec3& query, uint32_t hint = UINT32_MAX) const;
  // The same hit when the input is within `radius` of the query (false, and `hit` untouched,
  // when it is not): boxes beyond the radius are never opened, so a far query costs little.
  bool closest_within(const Vec3& query, double radius, Hit& hit, uint32_t hint = UINT32_MAX) const;
  double squared_distance(const Vec3& query) const { return closest(query).squared_distance; }
  // The hit on a given triangle: for the nearest triangle, the same hit as closest() gives.
  Hit hit_on(const Vec3& query, uint32_t triangle) const;
  // Is the input within `radius` of the query? (Much cheaper than closest() for small radii.)
  bool within(const Vec3& query, double radius) const;
  // The same answer, trying `hints` first (input triangles, UINT32_MAX for none): a caller that
  // knows a triangle near the query skips the tree (the answer does not depend on the hints).
  // On a yes from the tree, `found` (when given) receives the triangle that gave it.
  bool within(const Vec3& query, double radius, const uint32_t* hints, size_t count, uint32_t* found) const;
  // Does triangle abc touch or cross the input? (Floating point: a near miss may count.)
  bool touches(const Vec3& a, const Vec3& b, const Vec3& c) const;
  // Is input point `on` in view from `from`: within `near` of it, or the segment from `from`
  // to half `near` short of it clear of the input? (Curves buried inside the input are not.)
  bool in_view(const Vec3& from, const Vec3& on, double near) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace vdbwrap::mesh
