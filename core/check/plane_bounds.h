// A triangle's plane in doubles with a bound on its error, for a cheap first test of the
// candidate pairs: on a CAD cylinder the long side triangles' boxes nearly all overlap, and
// most of those pairs lie clearly beside each other's planes, which the exact predicates would
// take far longer to tell.
#pragma once
#include <cstdint>
#include <vector>

#include "vdbwrap/mesh.h"

namespace vdbwrap::check::pair_search {

struct PlaneBound {
  Vec3 normal{0, 0, 0};  // unit
  double slope = -1;     // error of the normal's direction (radians); < 0: no plane
};

// The plane of every usable triangle.
std::vector<PlaneBound> plane_bounds(const std::vector<Vec3>& points, const std::vector<Tri>& triangles,
                                     const std::vector<uint8_t>& usable);

// Are the vertices of `other` not in `own` all clearly on one side of own's plane? Then the
// triangles meet at most at their shared vertex: apart. Vertices on the plane within the error
// give no answer.
bool clearly_beside(const std::vector<Vec3>& points, const PlaneBound& plane, const Tri& own, const Tri& other);

}  // namespace vdbwrap::check::pair_search
