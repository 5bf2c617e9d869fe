// The parts of a surface far from the input: triangles with a corner, an edge midpoint or the
// centroid farther than a distance from it. Proximity refinement works on them; the refit
// refines the grid around them.
#pragma once
#include <cstdint>
#include <vector>

#include "common/vec.h"
#include "vdbwrap/mesh.h"
#include "mesh/surface_index.h"

namespace vdbwrap::mesh {

struct FarTriangle {
  uint32_t triangle = 0;
  double distance = 0;  // of its farthest sampled point
  Vec3 at{0, 0, 0};     // that point (the surface's frame)
};

// Triangles of (points, triangles) with a sampled point farther than `far` from the input, the
// farthest first; those with `alive` 0 are skipped (when `alive` is not empty). `input` is in
// the local frame, the surface's points are `origin` off it. `node_distance`: each point's
// distance to the input, or a bound of it where that is cheaper (within a fiftieth of `far`).
// A triangle whose farthest corner plus its reach from the corners is within `far` cannot have
// such a point, and is not sampled.
std::vector<FarTriangle> far_triangles(const std::vector<Vec3>& points, const std::vector<Tri>& triangles,
                                       const std::vector<uint8_t>& alive, const SurfaceIndex& input, const Vec3& origin,
                                       double far, std::vector<double>& node_distance);

// Has one of the triangles `far` (indices into `triangles`) a point farther than `bound` from the
// input, among the nodes of a barycentric grid of `steps` intervals per edge? far_triangles'
// corners, midpoints and centroid miss the middle of a face across a narrow channel or gap.
bool any_farther(const std::vector<Vec3>& points, const std::vector<Tri>& triangles,
                 const std::vector<FarTriangle>& far, const SurfaceIndex& input, const Vec3& origin, int steps,
                 double bound);

}  // namespace vdbwrap::mesh
