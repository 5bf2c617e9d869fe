// Mean, 95th percentile and maximum distance from sample points to a surface (shared by
// the Metro-style surface distance and the sharp-edge distance).
#pragma once
#include <functional>
#include <vector>

#include "mesh/surface_index.h"
#include "vdbwrap/check.h"

namespace vdbwrap::check {

// `diagonal` is stored in the result for percentages; samples may be empty.
DistanceStats distances_to(const std::vector<Vec3>& samples, const Mesh& to, double diagonal);

// A surface to measure against, already indexed: its points are the index's plus `origin` (the
// pipeline indexes the prepared input in a local frame); `diagonal` its bounding box's.
struct IndexedSurface {
  const mesh::SurfaceIndex& index;
  Vec3 origin;
  double diagonal;
};

// vdbwrap::sampled_distance from `from` to a surface already indexed (the wrap's report reuses
// the pipeline's index of the prepared input instead of indexing the input again).
DistanceStats sampled_distance_to(const Mesh& from, const IndexedSurface& to, double samples_per_diagonal,
                                  const std::function<bool(const Vec3&)>& skip = {});

// vdbwrap::sampled_distance with the samples `skip` answers true for left out (the repair:
// surface buried inside a solid it united, which no longer exists to be near anything).
DistanceStats sampled_distance_skipping(const Mesh& from, const Mesh& to, double samples_per_diagonal,
                                        const std::function<bool(const Vec3&)>& skip);

}  // namespace vdbwrap::check
