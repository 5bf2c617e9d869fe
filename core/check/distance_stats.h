// Mean, 95th percentile and maximum distance from sample points to a surface (shared by
// the Metro-style surface distance and the sharp-edge distance).
#pragma once
#include <functional>
#include <vector>

#include "vdbwrap/check.h"

namespace vdbwrap::check {

// `diagonal` is stored in the result for percentages; samples may be empty.
DistanceStats distances_to(const std::vector<Vec3>& samples, const Mesh& to, double diagonal);

// vdbwrap::sampled_distance with the samples `skip` answers true for left out (the repair:
// surface buried inside a solid it united, which no longer exists to be near anything).
DistanceStats sampled_distance_skipping(const Mesh& from, const Mesh& to, double samples_per_diagonal,
                                        const std::function<bool(const Vec3&)>& skip);

}  // namespace vdbwrap::check
