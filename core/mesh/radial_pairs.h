// The triangles around a non-manifold edge paired into the sides of the solids that meet there.
// Struts of an unmerged lattice, boxes of an assembly touching along an edge: once welded, the
// edge has four or more triangles, and orienting and the closed-piece test stop at it, so each
// solid falls apart into open pieces and its material side is lost.
#pragma once
#include <cstddef>
#include <cstdint>
#include <vector>

#include "common/vec.h"
#include "vdbwrap/mesh.h"

namespace vdbwrap::mesh {

// The triangle paired with `t` around edge (a, b), or UINT32_MAX. `around`: the `count`
// triangles using the edge (t among them). Sorted by angle around the edge, each triangle's
// material side (behind its normal, in the input's orientation) must face exactly one
// neighbour's material side, that neighbour running the edge the other way: the triangles
// then bound wedges of solid, two by two. Anything else (an odd count, two triangles in one
// half-plane, a sheet among solids, inconsistent orientation, over 16 triangles) pairs nothing.
uint32_t radial_partner(const std::vector<Vec3>& points, const std::vector<Tri>& triangles, uint32_t a, uint32_t b,
                        const uint32_t* around, size_t count, uint32_t t);

}  // namespace vdbwrap::mesh
