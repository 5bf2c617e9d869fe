// Stage 3: the lattice surface projected onto the input with its feature curves, nodes
// inserted where the traced chains missed a curve, and flat parts coarsened; where the first fit
// stays far from the input, the grid refined there and the lattice fitted again.
#include "common/stage_timer.h"
#include "fit/feature_insert.h"
#include "fit/two_sided_report.h"
#include "mesh/far_from_input.h"
#include "pipeline/stage_params.h"
#include "pipeline/stages.h"
#include "post/coarsen.h"

namespace vdbwrap::pipeline {
namespace {

void report_snapping(WrapReport& report, const fit::FittedSurface& fitted) {
  report.nodes_held_back = fitted.held_back;
  report.nodes_projected = fitted.points.size();
  report.features.curves = fitted.snap.curves;
  report.features.corners = fitted.snap.corners;
  report.features.curves_captured = fitted.snap.curves_captured;
  report.features.corners_captured = fitted.snap.corners_captured;
  report.features.nodes_snapped = fitted.snap.nodes_snapped;
}

// Curve points the traced chains missed get nodes of their own (edge splits).
void insert_feature_nodes(WrapRun& run, const std::vector<fit::FeatureCurve>& curves) {
  StageTimer timer("insert feature nodes", run.report.stages);
  if (run.progress) run.progress->progress("project", 0.97, "inserting nodes where the wrap misses a feature curve");
  const fit::FeatureInsertParams fp =
      feature_insert_params(run.params, run.base, run.report.finest_size, run.report.features.crack_gap);
  // The rims of sheets wrapped from both sides were left to the projection (the wrap passes
  // around them): nodes inserted there were mostly refused, at most of the stage's time on a
  // clump of hair cards or leaves.
  const std::vector<uint8_t>& rim = run.fitted.rim_of_two_sided_sheet;
  std::vector<fit::FeatureCurve> followed;
  for (size_t i = 0; i < curves.size(); ++i)
    if (i >= rim.size() || !rim[i]) followed.push_back(curves[i]);
  const auto fs = fit::insert_feature_nodes(run.fitted, followed, run.index(), run.prepared.origin, fp);
  FeatureStats& features = run.report.features;
  features.points_missed = fs.samples_missed;
  features.nodes_inserted = fs.nodes_inserted;
  features.nodes_moved = fs.nodes_moved;
  features.inserts_refused = fs.refused;
  features.points_unreachable = fs.unreachable;
}

void coarsen(WrapRun& run) {
  StageTimer timer("coarsen", run.report.stages);
  fit::FittedSurface& fitted = run.fitted;
  const post::CoarsenParams cp = coarsen_params(run.params, run.base, run.report.finest_size);
  const post::CoarsenStats cs = post::coarsen(fitted.points, fitted.triangles, fitted.snapped, run.index(),
                                              run.prepared.origin, cp, run.progress);
  // The per-point data follow their points (snapped nodes are never merged away).
  std::vector<double> cell(fitted.points.size());
  std::vector<uint8_t> snapped(fitted.points.size());
  for (size_t i = 0; i < cs.remap.size(); ++i)
    if (cs.remap[i] != UINT32_MAX) cell[cs.remap[i]] = fitted.cell_size[i], snapped[cs.remap[i]] = fitted.snapped[i];
  std::vector<std::pair<uint32_t, uint32_t>> edges;
  for (const auto& [a, b] : fitted.feature_edges)
    if (cs.remap[a] != UINT32_MAX && cs.remap[b] != UINT32_MAX) edges.push_back({cs.remap[a], cs.remap[b]});
  fitted.cell_size.swap(cell);
  fitted.snapped.swap(snapped);
  fitted.feature_edges.swap(edges);
}

// How much of the input the fit wraps from both sides, the input's openings, and the gap closure
// that would keep the volume out: for the report and the progress log. Of the fit that stays
// only (not of a first fit the refit replaces: on a large input it costs seconds).
void report_two_sided(WrapRun& run) {
  StageTimer timer("two-sided report", run.report.stages);
  const std::string text = fit::describe_two_sided(run.fitted.two_sided, run.prepared, run.report.two_sided);
  if (run.progress && !text.empty()) run.progress->progress("project", 1.0, text);
}

// The first fit's parts far from the input, into run.refine_near and the report. True when a
// point is nearly a base cell off or more: where the first fit is nearer everywhere, proximity
// refinement's local edits are enough, at a fraction of a refit's cost.
bool find_far_parts(WrapRun& run) {
  StageTimer timer("far check", run.report.stages);
  const mesh::SurfaceIndex& index = run.index();
  std::vector<Vec3> near;
  for (const Vec3& p : run.fitted.held_back_points) {
    const Vec3 local = p - run.prepared.origin;
    if (index.squared_distance(local) > run.base * run.base) near.push_back(local);
  }
  run.report.nodes_held_back_far_first_fit = near.size();
  std::vector<double> node_distance;
  const std::vector<mesh::FarTriangle> far = mesh::far_triangles(
      run.fitted.points, run.fitted.triangles, {}, index, run.prepared.origin, kRefitFar * run.base, node_distance);
  run.report.triangles_far_first_fit = far.size();
  // far_triangles stops at a triangle's first sample over kRefitFar, and its samples miss the
  // middle of a face across a narrow channel (a hole two or three cells wide in a plate).
  if (near.empty() &&
      (far.empty() || (far.front().distance <= kRefitTrigger * run.base &&
                       !mesh::any_farther(run.fitted.points, run.fitted.triangles, far, index, run.prepared.origin,
                                          kRefitSampleSteps, kRefitTrigger * run.base))))
    return false;
  for (const mesh::FarTriangle& f : far) near.push_back(f.at - run.prepared.origin);
  run.refine_near = std::move(near);
  return true;
}

}  // namespace

void project_lattice(WrapRun& run) {
  WrapReport& report = run.report;
  const mesh::SurfaceIndex& index = run.index();
  StageTimer timer("project", report.stages);
  const std::vector<fit::FeatureCurve>& curves = run.curves_builder->get();
  if (run.result.feature_curves.empty())
    for (const fit::FeatureCurve& c : curves) {  // WrapResult::feature_curves, in model coordinates
      std::vector<Vec3>& out = run.result.feature_curves.emplace_back();
      for (const Vec3& p : c.points) out.push_back(p + run.prepared.origin);
    }
  run.fitted = fit::fit_to_input(run.lattice, *run.refined.grid, index, curves, run.prepared.origin,
                                 fit_params(run.params, run.report.features.crack_gap), run.progress);
  report_snapping(report, run.fitted);
}

void refine_where_far(WrapRun& run) {
  // Only around the outside: a finer grid can open a passage, and for a seed point or the
  // inside volume that would turn a result into a leak.
  if (!run.params.refine_where_far || run.params.volume != VolumeChoice::Outside) return;
  if (!find_far_parts(run)) return;
  if (run.progress)
    run.progress->progress("project", 1.0,
                           std::to_string(run.report.triangles_far_first_fit) + " triangles and " +
                               std::to_string(run.report.nodes_held_back_far_first_fit) +
                               " held-back nodes far from the input: refining around them, fitting again");
  run.fitted = {};  // not needed any more: the refit's peak memory is the first fit's
  // Once: a second refit gained a few hundredths of a cell for the same cost again.
  build_volume(run);
  project_lattice(run);
}

void fit_surface(WrapRun& run) {
  report_two_sided(run);
  const std::vector<fit::FeatureCurve>& curves = run.curves_builder->get();
  if (!curves.empty() && run.fitted.valid) insert_feature_nodes(run, curves);
  run.report.triangles_before_coarsening = run.fitted.triangles.size();
  if (run.params.coarsen_tolerance > 0) coarsen(run);
  run.check_cancel();
}

}  // namespace vdbwrap::pipeline
