// Welding: vertices closer than a tolerance become one.
#pragma once
#include <cstdint>
#include <vector>

#include "vdbwrap/mesh.h"

namespace vdbwrap::mesh {

// Merges vertices closer than `tolerance` (model units). Returns the new index of each old point.
std::vector<uint32_t> weld_points(const std::vector<Vec3>& points, double tolerance, std::vector<Vec3>& welded);

}  // namespace vdbwrap::mesh
