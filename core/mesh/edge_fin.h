// The fin of a triangle at one of its edges: the direction from the edge into the triangle.
#pragma once
#include <cstdint>
#include <vector>

#include "common/vec.h"
#include "vdbwrap/mesh.h"

namespace vdbwrap::mesh {

// Unit direction from edge (a, b) towards the triangle's third corner, square to the edge. Around
// an edge with many triangles, the angles between fins say which are flat, folded or coincident
// whatever the triangles' orientations.
inline Vec3 edge_fin(const std::vector<Vec3>& points, const Tri& t, uint32_t a, uint32_t b) {
  const uint32_t c = t[0] != a && t[0] != b ? t[0] : t[1] != a && t[1] != b ? t[1] : t[2];
  const Vec3 e = points[b] - points[a], d = points[c] - points[a];
  return normalized(d - e * (dot(d, e) / dot(e, e)));
}

}  // namespace vdbwrap::mesh
