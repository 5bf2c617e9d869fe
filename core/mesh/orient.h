// Consistent, outward orientation of each connected piece of a triangle mesh.
#pragma once
#include <cstddef>
#include <cstdint>
#include <vector>

#include "common/edge_triangles.h"
#include "vdbwrap/mesh.h"

namespace vdbwrap::mesh {

// Makes the orientation consistent across every manifold edge of each connected piece and
// turns closed-looking pieces outward (positive signed volume). Returns triangles flipped.
// `edges`: the triangles' edges when known (flipping triangles changes none of them).
// `closed`, when given: per triangle, the number of its piece among the closed ones (every side
// shared with one other triangle of it), whose normals point out of the material; kOpenPiece
// on open pieces and soups, whose outward side is a guess.
constexpr uint32_t kOpenPiece = UINT32_MAX;
size_t orient_pieces(const std::vector<Vec3>& points, std::vector<Tri>& triangles, const EdgeTriangles* edges = nullptr,
                     std::vector<uint32_t>* closed = nullptr);

}  // namespace vdbwrap::mesh
