// Where a surface crosses itself next to itself: a rough scan's noise folds triangles over
// their neighbours, and each fold crosses the faces around it in a short line of its own, as
// dense as the noise's folds. Parts that cross (a CSG union's pieces, a sweep through itself)
// meet between faces far apart on the surface.
#pragma once
#include <cstdint>
#include <utility>
#include <vector>

#include "vdbwrap/mesh.h"

namespace vdbwrap::mesh {

// Per pair of triangles of `triangles` (over `points` vertices), whether the two lie within
// two rings of each other: a corner of the one is reached from a corner of the other across
// at most two faces (noise twice as coarse as the faces folds them over the next ring).
std::vector<uint8_t> fold_crossings(size_t points, const std::vector<Tri>& triangles,
                                    const std::vector<std::pair<uint32_t, uint32_t>>& pairs);

}  // namespace vdbwrap::mesh
