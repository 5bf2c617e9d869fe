// The exact kernel the intersection checks share: CGAL's exact predicates on the points as
// given in doubles (inexact constructions: nothing is built from the points, only decided).
#pragma once
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>

#include <cstdint>
#include <vector>

#include "vdbwrap/mesh.h"

namespace vdbwrap::check::pair_search {

using K = CGAL::Exact_predicates_inexact_constructions_kernel;
using P3 = K::Point_3;
using T3 = K::Triangle_3;
using S3 = K::Segment_3;

inline P3 to_point(const Vec3& v) { return P3(v[0], v[1], v[2]); }

inline bool is_degenerate(const std::vector<P3>& p, const Tri& t) {
  return t[0] == t[1] || t[1] == t[2] || t[0] == t[2] || CGAL::collinear(p[t[0]], p[t[1]], p[t[2]]);
}

// The points as CGAL points, and which triangles are not degenerate (the others take part in
// no pair).
struct ExactInput {
  std::vector<P3> p;
  std::vector<uint8_t> usable;
};
ExactInput exact_input(const std::vector<Vec3>& points, const std::vector<Tri>& triangles);

}  // namespace vdbwrap::check::pair_search
