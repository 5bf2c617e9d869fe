// Fan proofs for the pair search: vertices whose triangles lie round them as an unfolded fan.
// Two triangles sharing only such a vertex cover disjoint sectors there, so they meet only at
// it and their pair needs no exact test.
#pragma once
#include <cstdint>
#include <vector>

#include "check/exact_kernel.h"
#include "common/compressed_lists.h"

namespace vdbwrap::check::pair_search {

// The usable triangles around each vertex, in increasing order: items[first[v] .. first[v + 1]).
using VertexStars = CompressedLists;

VertexStars vertex_stars(size_t points, const std::vector<Tri>& triangles, const std::vector<uint8_t>& usable);

// Vertices whose triangles form an unfolded fan: seen along the axis nearest to their common
// normal, each covers an angular sector at the vertex turning the same way, and sorted by
// angle the sectors follow one another without overlap, once round. Two such triangles that
// share only that vertex cover disjoint sectors there, so they meet only at it (a common
// point would be common in the projection too). CAD caps are such fans with thousands of
// spokes whose boxes all overlap: without this proof every pair of spokes would go to the
// exact tests. Gaps between sectors (a missing spoke) are allowed;
// only vertices with many triangles are looked at.
std::vector<uint8_t> unfolded_fan_vertices(const std::vector<P3>& p, const std::vector<Tri>& triangles,
                                           const VertexStars& stars);

// Vertices whose triangles close one unfolded fan round them (see closed_fan_unfolded): every
// vertex of a wrap nearly, where unfolded_fan_vertices looks only at large fans. Two triangles
// with such a corner meet only where they share, so a wrap's neighbouring pairs, most of its
// candidate pairs, need no test.
std::vector<uint8_t> closed_fan_vertices(const std::vector<Vec3>& points, const std::vector<Tri>& triangles,
                                         const VertexStars& stars);

}  // namespace vdbwrap::check::pair_search
