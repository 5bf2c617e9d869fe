// Mean, 95th percentile and maximum distance from sample points to a surface (shared by
// the Metro-style surface distance and the sharp-edge distance).
#pragma once
#include <vector>

#include "vdbwrap/wrap.h"

namespace vdbwrap::check {

// `diagonal` is stored in the result for percentages; samples may be empty.
DistanceStats distances_to(const std::vector<Vec3>& samples, const Mesh& to, double diagonal);

}  // namespace vdbwrap::check
