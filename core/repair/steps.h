// The steps of the repair, in the order they run (docs/pipeline.md, "Intersection repair"):
// stitch the cracks, part 1 (local operations), part 2 (remove and refill, then refine and
// refill what is left), unite closed bodies still crossing, remove small pieces. Each step
// changes the working mesh only where its change is kept: intersections around it fewer,
// none new.
#pragma once
#include <cstddef>
#include <cstdint>
#include <memory>
#include <set>
#include <vector>

#include "repair/local_operations.h"
#include "repair/unite.h"
#include "repair/work.h"
#include "vdbwrap/progress.h"
#include "vdbwrap/repair.h"

namespace vdbwrap::mesh {
class SurfaceIndex;
}

namespace vdbwrap::local_repair {

// Cracks (faces that share no vertices and touch along their seams) are stitched: corners
// within `tol` of each other welded, border edges split at the corners within `tol` of them.
// Nothing moves by more than `tol`.
void run_stitch(Work& w, double tol, RepairReport& report);

// Part 1: per cluster of intersecting triangles (edge-connected), vertex and triangle shifts
// tried by increasing volume change, then untanglings, all clusters at once, for at most
// params.local_iterations rounds. No vertex leaves `max_dev`
// of where it started.
void run_local(Work& w, const RepairParams& params, const LocalParams& lp, double max_dev, RepairReport& report,
               ProgressSink* progress);

// Part 2: the regions still intersecting (of input region `only`; all when negative) are
// removed with a ring around them and refilled, within `max_dev` of `original` (the input
// surface); `fair` false: fills refined but not faired.
void run_refill(Work& w, const RepairParams& params, double max_dev, const mesh::SurfaceIndex& original,
                RepairReport& report, ProgressSink* progress, int32_t only = -1, bool fair = true);

// Part 2 again, region by region, for the regions the plain refill left: refine around the
// region, refill it; kept only when the region comes out free of intersections.
void run_refine_and_refill(Work& w, const RepairParams& params, double max_dev, const mesh::SurfaceIndex& original,
                           size_t regions_found, RepairReport& report, ProgressSink* progress);

// Closed bodies still crossing each other are united (of input regions `regions` only, when
// given); the united solids are added to `solids`. Returns how many groups of closed bodies
// it tried to unite.
size_t run_unite(Work& w, const RepairParams& params, double max_dev, const mesh::SurfaceIndex& original,
                 std::vector<std::unique_ptr<SolidTest>>& solids, RepairReport& report,
                 const std::set<int32_t>* regions = nullptr);

// Small pieces the repair left on their own or still intersecting are deleted when all of
// each lies within `max_dev` of what stays.
void remove_small_pieces(Work& w, const RepairParams& params, double max_dev, RepairReport& report);

}  // namespace vdbwrap::local_repair
