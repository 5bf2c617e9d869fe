// The wrap's per-triangle defect flags as the API hands them out (WrapResult::triangle_flags).
#pragma once
#include <cstdint>
#include <vector>

#include "vdbwrap/mesh.h"

namespace vdbwrap::post {

// The final quality analysis' flags (one byte per triangle, DefectFlag bits), plus
// kDefectHeldBack on the triangles with a corner where the fit held a node back off the input
// (`held_back`: those nodes' positions; a node a later stage moved is no longer one of them).
std::vector<uint8_t> wrap_defect_flags(const std::vector<Vec3>& points, const std::vector<Tri>& triangles,
                                       std::vector<uint8_t> quality_flags, std::vector<Vec3> held_back);

}  // namespace vdbwrap::post
