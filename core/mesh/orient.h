// Consistent, outward orientation of each connected piece of a triangle mesh.
#pragma once
#include <cstddef>
#include <vector>

#include "common/edge_triangles.h"
#include "vdbwrap/mesh.h"

namespace vdbwrap::mesh {

// Makes the orientation consistent across every manifold edge of each connected piece and
// turns closed-looking pieces outward (positive signed volume). Returns triangles flipped.
// `edges`: the triangles' edges when known (flipping triangles changes none of them).
size_t orient_pieces(const std::vector<Vec3>& points, std::vector<Tri>& triangles,
                     const EdgeTriangles* edges = nullptr);

}  // namespace vdbwrap::mesh
