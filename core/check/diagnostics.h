// The input diagnosis on a weld made once: the pipeline diagnoses its input and then welds it,
// and both start from the same exact weld of the input's points.
#pragma once
#include "common/exact_weld.h"
#include "vdbwrap/check.h"

namespace vdbwrap::check {

// diagnose() with `weld` the exact weld of mesh.points.
MeshDiagnostics diagnose_welded(const Mesh& mesh, const ExactWeld& weld, bool find_intersections);

}  // namespace vdbwrap::check
