// Parts of the input thinner than a cell across two directions: a rod, a narrow strip, a small
// closed piece. The cells around them are refined below the criteria's depth, so the wrap has
// nodes enough across the part: on a rod a tenth of a cell thick, the nodes of a cell-sized
// lattice project onto a circle smaller than their spacing, and every triangle between them
// is a sliver.
#pragma once
#include <cstdint>
#include <vector>

#include "common/vec.h"
#include "prep/prepare.h"

namespace vdbwrap::grid {

// The thickness of the thinnest part among `cell_tris` under `within`, or `within` when none is.
// A part's side is two triangles of one closed piece whose normals point away from each other
// (over 143 degrees apart), with solid between them: the distance between their planes,
// measured through `centre` (the planes' offsets from it along their own normals). A part is
// thin across two such sides at least 45 degrees apart, and as thick as the thicker; a closed
// piece is also as thin as its bounding box's longest side. A plain thin wall is thin across
// one only: each side of the wrap projects to its own face there, and its rim's strip of
// needles is mended by the sliver removal at less cost than refining along the wall.
double thinnest_part(const prep::PreparedInput& in, const std::vector<uint32_t>& cell_tris, const Vec3& centre,
                     double within);

}  // namespace vdbwrap::grid
