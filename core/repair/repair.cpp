// The repair pipeline (spec: "Intersection repair"; docs/pipeline.md): find the intersecting
// pairs and group them into regions, stitch cracks, part 1 (vertex and triangle shifts),
// part 2 (remove and refill, then refine and refill), unite closed bodies still crossing,
// remove small leftovers, then the report. Each step has its own file (repair/steps.h); this
// runs them in order. Every change is kept only where the region's intersection count drops
// and no new intersecting pair appears.
#include <tbb/task_arena.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <memory>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include "check/intersections.h"
#include "common/stage_timer.h"
#include "mesh/surface_index.h"
#include "prep/check_input.h"
#include "repair/regions.h"
#include "repair/report_figures.h"
#include "repair/steps.h"
#include "repair/work.h"
#include "vdbwrap/check.h"
#include "vdbwrap/repair.h"

namespace vdbwrap {
namespace {

using local_repair::check_cancel;
using local_repair::clean_regions;
using local_repair::LocalParams;
using local_repair::SolidTest;
using local_repair::Work;

void validate(const RepairParams& p) {
  auto bad = [](const std::string& what) { throw Error(ErrorKind::InvalidArgument, "repair: " + what); };
  if (p.local_iterations < 0 || p.local_iterations > 1000) bad("local iterations must be 0..1000");
  if (p.refill_iterations < 0 || p.refill_iterations > 100) bad("refill iterations must be 0..100");
  if (!(p.alpha > 0 && p.alpha < 1)) bad("alpha must be in (0, 1)");
  if (!(p.beta > 0)) bad("beta must be positive");
  if (!(p.delta > 0)) bad("delta must be positive");
  if (!(p.gamma > 0)) bad("gamma must be positive");
  if (!(p.area_ratio > 0 && p.area_ratio <= 1)) bad("area ratio (eps_S) must be in (0, 1]");
  if (!(p.refill_area_ratio > 0 && p.refill_area_ratio <= 1)) bad("refill area ratio must be in (0, 1]");
  if (!(p.accuracy >= 0) || !std::isfinite(p.accuracy)) bad("accuracy must be 0 (automatic) or positive");
  if (!(p.max_deviation.value > 0) || !std::isfinite(p.max_deviation.value)) bad("max deviation must be positive");
  if (p.small_piece_triangles < 0) bad("small piece triangles must not be negative");
  if (!(p.small_piece_area >= 0 && p.small_piece_area <= 1)) bad("small piece area must be in [0, 1]");
}

void diagnose_input(const Mesh& input, RepairReport& report, ProgressSink* progress) {
  StageTimer timer("diagnose input", report.stages);
  if (progress) progress->progress("repair: diagnose input", 0.0, "checking the input");
  report.before = diagnose(input, true);
}

// The bounds every step keeps to: --max-deviation in model units and the model accuracy.
LocalParams resolve_bounds(const Work& w, const RepairParams& params, RepairReport& report) {
  report.diagonal = report.before.diagonal;
  report.max_deviation = params.max_deviation.resolve(report.diagonal);
  report.accuracy = params.accuracy > 0 ? params.accuracy : std::max(1e-16, 0.05 * local_repair::shortest_edge(w));
  return LocalParams{params.alpha, params.beta, params.delta, params.gamma, report.accuracy};
}

// Step 1: the intersecting pairs, grouped into the input regions the report counts.
void find_intersections(Work& w, RepairReport& report) {
  StageTimer timer("find intersections", report.stages);
  w.set_pairs(check::find_intersecting_pairs(w.points, w.tris));
  auto regions = local_repair::group_regions(w.tris, local_repair::triangles_of(w.pairs), w.pairs);
  for (size_t r = 0; r < regions.size(); ++r)
    for (uint32_t t : regions[r]) w.region_of[t] = int32_t(r);
  report.regions_found = regions.size();
}

// Step 1, cracks.
void stitch_cracks(Work& w, RepairReport& report) {
  if (w.pairs.empty()) return;
  StageTimer timer("stitch cracks", report.stages);
  // Cracks of CAD exports are float noise wide; 1e-6 of the diagonal stays far below any
  // deviation bound.
  local_repair::run_stitch(w, std::min(1e-6 * report.diagonal, report.max_deviation), report);
}

// What a pass of steps 2 to 5 leaves beside the mesh.
struct Pass {
  std::vector<std::unique_ptr<SolidTest>> solids;  // bodies united: their insides
  std::vector<uint8_t> by_union;                   // per input region: the union fixed it
  std::vector<uint8_t> clean_after_local;          // per input region: clean after part 1
  size_t unite_tried = 0;                          // groups of closed crossing bodies the union was tried on
};

// Step 4, the union of crossing closed bodies (of input regions `regions` only, when given),
// noting the regions it fixed. `input`: the input surface as it came.
void unite_bodies(Work& w, const RepairParams& params, const mesh::SurfaceIndex& input,
                  const std::set<int32_t>* regions, Pass& pass, RepairReport& report, ProgressSink* progress) {
  StageTimer timer("unite crossing bodies", report.stages);
  check_cancel(progress);
  const auto clean_before = clean_regions(w, report.regions_found);
  pass.unite_tried += local_repair::run_unite(w, params, report.max_deviation, input, pass.solids, report, regions);
  const auto clean_after = clean_regions(w, report.regions_found);
  for (size_t r = 0; r < report.regions_found; ++r) pass.by_union[r] |= !clean_before[r] && clean_after[r];
}

// Steps 2 to 5 on the stitched mesh. `first`: input regions whose crossing bodies are united
// before part 1 (the second pass).
Pass run_pass(Work& w, const RepairParams& params, const LocalParams& lp, const std::set<int32_t>& first,
              RepairReport& report, ProgressSink* progress) {
  Pass pass;
  pass.by_union.assign(report.regions_found, 0);
  if (!first.empty()) {
    mesh::SurfaceIndex input(w.origin, local_repair::live_triangles(w));
    unite_bodies(w, params, input, &first, pass, report, progress);
  }
  {
    StageTimer timer("local operations", report.stages);
    local_repair::run_local(w, params, lp, report.max_deviation, report, progress);
  }
  pass.clean_after_local = clean_regions(w, report.regions_found);
  if (!w.pairs.empty() && params.refill_iterations > 0) {
    // The input surface as it came (vertices at their starting places).
    mesh::SurfaceIndex input(w.origin, local_repair::live_triangles(w));
    {
      StageTimer timer("remove and refill", report.stages);
      local_repair::run_refill(w, params, report.max_deviation, input, report, progress);
    }
    if (!w.pairs.empty()) {
      StageTimer timer("refine, remove and refill", report.stages);
      local_repair::run_refine_and_refill(w, params, report.max_deviation, input, report.regions_found, report,
                                          progress);
    }
    if (!w.pairs.empty() && params.unite_bodies) unite_bodies(w, params, input, nullptr, pass, report, progress);
  }
  if (params.remove_small_pieces) {
    StageTimer timer("remove small pieces", report.stages);
    local_repair::remove_small_pieces(w, params, report.max_deviation, report);
  }
  return pass;
}

// Steps 2 to 5, twice when the union was needed. The second pass is for the regions the first
// left (or united only after parts 1 and 2 had moved and cut them): their closed bodies (an
// assembly's walls overlapping face to face, crossing over areas) united first, from the
// stitched mesh, then the rest as before. Kept when it leaves fewer regions unfixed, or as
// few when the first pass needed the union too.
Pass repair_regions(Work& w, const RepairParams& params, const LocalParams& lp, RepairReport& report,
                    ProgressSink* progress) {
  const Work stitched = w;
  const RepairReport report_stitched = report;
  Pass pass = run_pass(w, params, lp, {}, report, progress);
  const bool united_late = std::any_of(pass.by_union.begin(), pass.by_union.end(), [](uint8_t u) { return u != 0; });
  if (!(((!w.pairs.empty() && pass.unite_tried > 0) || united_late) && params.unite_bodies)) return pass;
  const auto clean = clean_regions(w, report.regions_found);
  std::set<int32_t> left;
  for (size_t r = 0; r < report.regions_found; ++r)
    if (!clean[r] || pass.by_union[r]) left.insert(int32_t(r));
  Work first_w = std::move(w);
  RepairReport first_report = std::move(report);
  w = stitched;
  report = report_stitched;
  report.stages = first_report.stages;
  Pass second = run_pass(w, params, lp, left, report, progress);
  const auto clean2 = clean_regions(w, report.regions_found);
  const auto left1 = std::count(clean.begin(), clean.end(), 0), left2 = std::count(clean2.begin(), clean2.end(), 0);
  if (left2 > left1 || (left2 == left1 && !united_late)) {
    const auto stages = std::move(report.stages);
    w = std::move(first_w);
    report = std::move(first_report);
    report.stages = stages;
    ++report.refusals["unite: uniting the bodies first left no fewer regions (second pass dropped)"];
    return pass;
  }
  return second;
}

void diagnose_output(const Mesh& output, RepairReport& report, ProgressSink* progress) {
  StageTimer timer("diagnose output", report.stages);
  if (progress) progress->progress("repair: diagnose output", 0.0, "checking the result");
  report.after = diagnose(output, true);
}

RepairResult run_repair(const Mesh& input, const RepairParams& params, ProgressSink* progress) {
  validate(params);
  const auto start = std::chrono::steady_clock::now();
  RepairResult result;
  RepairReport& report = result.report;
  report.params = params;
  diagnose_input(input, report, progress);
  check_cancel(progress);
  Work w = local_repair::make_work(input, params.float_coordinates);
  const std::vector<Tri> input_tris = w.tris;  // the input's triangles (ids stay: deleted ones die in place)
  const LocalParams lp = resolve_bounds(w, params, report);
  find_intersections(w, report);
  stitch_cracks(w, report);
  const Pass pass = repair_regions(w, params, lp, report, progress);
  local_repair::count_fixed_regions(w, pass.by_union, pass.clean_after_local, report);
  report.unfixed = local_repair::describe_regions(w);
  result.mesh = local_repair::compact(w, input);
  check_cancel(progress);
  diagnose_output(result.mesh, report, progress);
  if (params.compute_distances) {
    StageTimer timer("distances", report.stages);
    local_repair::measure_deviation(w, input_tris, pass.solids, report);
  }
  report.total_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return result;
}

}  // namespace

RepairResult repair(const Mesh& input, const RepairParams& params, ProgressSink* progress) {
  prep::check_input_mesh(input, "repair input");
  // A task arena per job, as in wrap(): its thread limit holds for this job only.
  if (params.threads <= 0) return run_repair(input, params, progress);
  tbb::task_arena arena(params.threads);
  return arena.execute([&] { return run_repair(input, params, progress); });
}

}  // namespace vdbwrap
