// Stage 4: quality analysis of the fitted surface, remeshing of bad regions, the intersection
// repair where anything still intersects, proximity refinement, sliver removal; then the
// output's part labels.
#include "common/stage_timer.h"
#include "pipeline/stage_params.h"
#include "pipeline/stages.h"
#include "post/proximity_refinement.h"
#include "post/sliver_removal.h"

namespace vdbwrap::pipeline {
namespace {

// What stage 4 measures against: the input, its sharp edges, the cell sizes, the thresholds.
void set_quality_reference(WrapRun& run) {
  post::QualityReference& ref = run.quality_ref;
  ref.input = &run.index();
  ref.origin = run.prepared.origin;
  ref.feature_samples = post::sample_sharp_edges(run.prepared, kFeatureSampleSpacing * run.prepared.diagonal);
  ref.finest_size = run.report.finest_size;
  ref.thresholds = run.params.quality;
  // Nearest input points asked again and again by the analysis, the rebuilds and the part labels.
  run.nearest_memo = std::make_unique<post::NearestMemo>(run.index());
  ref.nearest = run.nearest_memo.get();
}

void remesh(WrapRun& run) {
  WrapReport& report = run.report;
  post::PostSurface& surface = run.surface;
  StageTimer timer("remesh", report.stages);
  if (run.progress)
    run.progress->progress("remesh", 0.0,
                           "quality analysis of " + std::to_string(surface.triangles.size()) + " triangles");
  std::vector<uint8_t> flags;
  report.quality.before = post::analyse_quality(surface.points, surface.triangles, surface.cell_size, run.quality_ref,
                                                &flags, nullptr, &run.deviation_memo);
  if (run.params.remesh) {
    const post::RemeshParams rp = remesh_params(run.params, run.base, run.report.finest_size);
    const post::RemeshStats st =
        post::remesh_bad_regions(surface, flags, run.quality_ref, run.prepared, rp, run.progress);
    report.quality.regions = st.regions;
    report.quality.remeshed_on_input = st.on_input;
    report.quality.remeshed_by_ear_clipping = st.ear_clipping;
    report.quality.restored = st.restored;
    report.quality.refusals = st.refusals;
  }
  // Rebuilds never add an intersection: only a surface that had some can have any left.
  if (report.quality.before.self_intersecting > 0 || !run.fitted.valid) run.repair_if_intersecting();
}

// Where the wrap is still far from the input: nodes onto it, far edges split (before the
// sliver removal, which then works on the triangles the splits made).
void refine_proximity(WrapRun& run) {
  StageTimer timer("proximity", run.report.stages);
  const post::RemeshParams rp = remesh_params(run.params, run.base, run.report.finest_size);
  const post::ProximityRefinementParams pp =
      post::proximity_refinement_params(run.base, rp.offset, 0.5 * rp.max_deviation, rp.float_coordinates);
  if (run.progress)
    run.progress->progress("remesh", 1.0,
                           "bringing the parts of the wrap over 3/4 of a base cell off nearer the input");
  const post::ProximityRefinementStats st = post::refine_proximity(run.surface, run.quality_ref, pp);
  ProximityRefinementReport& out = run.report.quality.proximity_refinement;
  out.ran = true, out.far_distance = pp.far_distance;
  out.far_triangles_before = st.far_before, out.far_triangles_after = st.far_after;
  out.pulls = st.pulls, out.splits = st.splits, out.collapses = st.collapses;
  out.refusals = st.refusals;
}

}  // namespace

void post_process(WrapRun& run) {
  fit::FittedSurface& fitted = run.fitted;
  run.surface = post::PostSurface{std::move(fitted.points), std::move(fitted.triangles), std::move(fitted.cell_size),
                                  std::move(fitted.snapped), std::move(fitted.feature_edges)};
  set_quality_reference(run);
  remesh(run);
  run.check_cancel();
  if (run.params.proximity_refinement) refine_proximity(run);
  run.check_cancel();
  if (run.params.remove_slivers) {  // flips, collapses and tangential moves, held to the rebuilds' tolerance
    StageTimer timer("slivers", run.report.stages);
    const post::RemeshParams rp = remesh_params(run.params, run.base, run.report.finest_size);
    const post::SliverRemovalParams sp =
        post::sliver_removal_params(rp.max_deviation, rp.offset, run.report.finest_size, rp.float_coordinates);
    const post::SliverRemovalStats st = post::remove_slivers(run.surface, run.quality_ref, sp);
    SliverRemovalReport& out = run.report.quality.sliver_removal;
    out.ran = true, out.target_angle_deg = sp.target_angle_deg;
    out.slivers_before = st.slivers_before, out.slivers_after = st.slivers_after;
    out.flips = st.flips, out.collapses = st.collapses, out.moves = st.moves, out.splits = st.splits;
    out.refusals = st.refusals;
  }

  run.result.surface = run.labelled_surface();
  run.quality_ref.nearest = nullptr;  // its memory goes; the final analysis has its own memo
  run.nearest_memo.reset();
  run.check_cancel();
}

}  // namespace vdbwrap::pipeline
