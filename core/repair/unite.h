// Closed bodies pushed into each other (an assembly exported as one mesh, walls overlapping at
// every edge of a box): their union, exact (CGAL corefinement, exact constructions). The
// surface of the union lies on the input surface; what goes is only the surface buried inside
// another body and faces lying flat on another body's face (coplanar contact).
#pragma once
#include <memory>
#include <string>
#include <vector>

#include "vdbwrap/mesh.h"

namespace vdbwrap::local_repair {

struct Union {
  bool ok = false;
  std::string why;  // when not ok
  std::vector<Vec3> points;
  std::vector<Tri> triangles;  // closed, oriented outward
};

// The union of `bodies` (triangle lists on `points`), each a closed, oriented surface that
// bounds a volume and does not cut itself; coordinates rounded to float when asked.
Union unite_bodies(const std::vector<Vec3>& points, const std::vector<std::vector<Tri>>& bodies,
                   bool float_coordinates);

// Do triangles a and b lie in one plane (exact predicates)?
bool coplanar_pair(const std::vector<Vec3>& points, const Tri& a, const Tri& b);

// Is a point strictly inside a closed surface (and not on it)? Thread-safe once built.
class SolidTest {
 public:
  SolidTest(const std::vector<Vec3>& points, const std::vector<Tri>& triangles);
  ~SolidTest();
  SolidTest(const SolidTest&) = delete;
  SolidTest& operator=(const SolidTest&) = delete;
  bool inside(const Vec3& q) const;
  bool outside(const Vec3& q) const;  // strictly outside (not on it)

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace vdbwrap::local_repair
