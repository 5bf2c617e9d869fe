// Needle untangling, a local operation of part 1 beside the paper's two (issue 35). On fine
// anisotropic tessellations (fans of needles at a pole or a cap's hub, long thin side quads) a
// fold is a vertex slid past its neighbour across the needles; the needles it overlaps are
// nearly coplanar, so the crossing points the paper's shifts are planned from say little. The
// vertex goes back between its neighbours instead: to their average weighted by
// 1 / length^2, so that the short edges (the needles' widths) decide and the long ones barely
// pull: it slides across the needles, hardly along them.
#pragma once
#include <cstddef>
#include <cstdint>
#include <vector>

#include "repair/local_operations.h"
#include "repair/regions.h"
#include "vdbwrap/mesh.h"

namespace vdbwrap::local_repair {

// Where vertex `v` goes: the average of its neighbours (vertices sharing a live triangle),
// each weighted by 1 / (length^2 + (second shortest length / 2)^2), and no farther than that
// second shortest length; the offset keeps an edge the fold made nearly zero long from pulling
// the vertex onto its neighbour.
Vec3 untangled_position(const std::vector<Vec3>& points, const std::vector<Tri>& triangles, const VertexFaces& faces,
                        uint32_t v);

// Untangling moves of a region, all marked not primary (tried after the paper's shifts): the
// vertices on cutting edges one at a time (most cutting edges first, at most `singles`), then
// all the region's vertices at once, after one and after `sweeps` rounds of averaging.
std::vector<Move> plan_untangling(const std::vector<Vec3>& points, const std::vector<Tri>& triangles,
                                  const VertexFaces& faces, const std::vector<uint32_t>& region,
                                  const std::vector<Crossing>& crossings, size_t singles = 8, int sweeps = 4);

}  // namespace vdbwrap::local_repair
