// Star-shaped pieces for the pair search: closed pieces that every ray from a point inside
// them crosses once. Two triangles of such a piece meet only at their common vertices and
// edge, so their pairs need no test.
#pragma once
#include <cstdint>
#include <vector>

#include "check/exact_kernel.h"

namespace vdbwrap {
struct EdgeTriangles;
}

namespace vdbwrap::check::pair_search {

// A triangle in no star-shaped piece. The pieces are the broad phase's groups: the same value
// as kNoGroup.
constexpr uint32_t kNoPiece = UINT32_MAX;

// Per triangle: the number of its piece when that piece is star-shaped, else kNoPiece.
// `usable`: the triangles that take part (not degenerate); `edges`: their edges when known.
std::vector<uint32_t> star_shaped_pieces(const std::vector<P3>& given_points, const std::vector<Tri>& given_triangles,
                                         const std::vector<uint8_t>& given_usable,
                                         const EdgeTriangles* edges = nullptr);

}  // namespace vdbwrap::check::pair_search
