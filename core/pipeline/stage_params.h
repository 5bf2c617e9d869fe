// The one place where the user's WrapParams become the stages' own parameter structs: a stage
// sees only what it uses. The factors that scale a stage's tolerances to the cell sizes are
// here, with the reason for each.
#pragma once
#include <cstddef>

#include "fit/feature_insert.h"
#include "fit/fit_surface.h"
#include "grid/refine.h"
#include "grid/size_controls.h"
#include "post/coarsen.h"
#include "post/remesh.h"
#include "prep/prepare.h"
#include "vdbwrap/params.h"

namespace vdbwrap::pipeline {

// A base size giving more cells than this across the diagonal is refused (memory and time).
inline constexpr double kMostCellsAcross = 20000;
// Output in single precision (binary STL): a wrap is refused where a float's step at its
// coordinates is this share of the finest cell or more (nodes merge, the wrap cannot both
// hug the input and stay valid), and the user is warned above the second share.
inline constexpr double kCoarsestFloatStep = 0.5;
inline constexpr double kFloatStepWarned = 1.0 / 16;
// Runs of sharp edges shorter than this many base cells, many to a cell, are dropped as noise
// (mesh/short_feature_runs.h).
inline constexpr double kShortestSharpRun = 1.0;
// Rims of open pieces and holes smaller than this many base cells across are no feature curves
// (mesh/small_rims.h).
inline constexpr double kSmallestRim = 3.0;
// Where open sheets a few base cells across cross in a clump (leaves, hair cards, a scan's
// overlapping views), their crossing lines are about as short as the sheets are wide: runs of
// such lines shorter than this many base cells, many to a cell, are noise
// (mesh/short_feature_runs.h), as short runs under kShortestSharpRun are everywhere.
inline constexpr double kShortestSheetCrossing = 3.0;
// Self-intersection line ends closer than this fraction of the diagonal are one point, as the
// feature curves join them (fit/features.cpp).
inline constexpr double kLineWeld = 1e-9;
// Feature lines of a part placed more than once a hair apart run parallel within this angle,
// and closer than a triangle with this smallest angle is wide at the finest cell
// (mesh/bundled_lines.h): the outermost of such a bundle is kept.
inline constexpr double kBundleAngle = 10;
// A crack, the gap between faces that do not share their corners, is up to this many finest
// cells wide: an exporter's tolerance, coordinates rounded coarsely, faces tessellated each on
// its own. No narrower gap lets the volume through, so the wrap passes over it either way;
// as rims its sides would fold the wrap along every edge. The sides of so wide a gap are
// parallel only within kCrackAngle (each end off by up to the width, on edges a cell or two
// long; mesh/cracks.h narrows it to the edges). The creases kept from one side still join
// within the sliver width: within a cell, both ends of a finely tessellated crease's short
// edges would join, and the edges go.
inline constexpr double kCrackWidth = 1.0;
inline constexpr double kCrackAngle = 30;
// Unresolved contacts listed in the report, one per base cell.
inline constexpr size_t kMostContactLocations = 100;
// The refit where the first fit is far from the input (refine_where_far): it looks at triangles
// with a point over kRefitFar base cells off, and runs when one is over kRefitTrigger (the
// stages after it can move the farthest point out by a little: the target is a base cell), or
// a node is held back over a base cell off. Then the cells within kRefitNearReach base cells of
// them are refined to the finest level, and those within kRefitFarCellsReach with a boundary
// point over a base cell from their triangles (a concave crease's cells, whose corners
// project far apart).
inline constexpr double kRefitFar = 0.75;
inline constexpr double kRefitTrigger = 0.9;
inline constexpr double kRefitNearReach = 2;
inline constexpr double kRefitFarCellsReach = 6;
// The trigger looks at the far triangles' points on a barycentric grid this fine.
inline constexpr int kRefitSampleSteps = 6;
// Stage 4 samples the input's sharp edges every this fraction of the diagonal.
inline constexpr double kFeatureSampleSpacing = 1e-3;

prep::PrepareParams prepare_params(const WrapParams& params);
grid::SizeRequests size_requests(const WrapParams& params);
grid::RefineCriteria refine_criteria(const WrapParams& params);
// base: the base size, fine: the finest cell, both in model units; crack_gap: what nine in ten
// hairline cracks' sides stay within (features.crack_gap; 0 without cracks).
fit::FeatureInsertParams feature_insert_params(const WrapParams& params, double base, double fine,
                                               double crack_gap = 0);
fit::FitParams fit_params(const WrapParams& params, double crack_gap = 0);
post::CoarsenParams coarsen_params(const WrapParams& params, double base, double fine);
post::RemeshParams remesh_params(const WrapParams& params, double base, double fine);
// The intersection repair of stage 4 moves nothing farther than this.
double repair_bound(double base);

}  // namespace vdbwrap::pipeline
