// The final checks of the wrap and the report's last numbers: validity (CGAL's verdict), the
// final quality analysis, the defect flags, the sampled distances.
#include <tbb/task_group.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>

#include "check/distance_stats.h"
#include "check/intersections.h"
#include "common/debug_switch.h"
#include "common/float_round.h"
#include "common/stage_timer.h"
#include "vdbwrap/io.h"
#include "pipeline/stages.h"
#include "post/wrap_defects.h"

namespace vdbwrap::pipeline {
namespace {

// Why the surface failed validation, in words a user can act on.
std::string why_invalid(const WrapRun& run, const check::CgalVerdict& verdict) {
  const WrapReport& report = run.report;
  std::string why = "the wrap failed validation: closed=" + std::to_string(report.output.closed) +
                    " manifold=" + std::to_string(report.output.manifold) +
                    " outward=" + std::to_string(verdict.outward);
  // CGAL's self-intersection test runs on a closed manifold only: otherwise there is no verdict.
  if (verdict.valid_polygon_mesh) why += " self-intersecting=" + std::to_string(verdict.self_intersects);
  if (run.params.float_coordinates) {
    // Far from the origin, single precision cannot hold cells this small: points merge.
    double far = 0, cell = INFINITY;
    for (const Vec3& p : run.result.surface.points)
      far = std::max({far, std::fabs(p[0]), std::fabs(p[1]), std::fabs(p[2])});
    for (double c : run.surface.cell_size) cell = std::min(cell, c);
    const double step = float_step(far);
    if (step > 1e-3 * cell) {
      char text[160];
      std::snprintf(text, sizeof text,
                    "; the output is rounded to single precision for STL, whose steps (about %.3g at "
                    "these coordinates) are too coarse for cells of %.3g",
                    step, cell);
      why += std::string(text) + ": write .ply, .obj or .vtp, which keep doubles, or move the model nearer the origin";
    }
  }
  if (verdict.valid_polygon_mesh && verdict.self_intersects && report.quality.repair_runs > 0)
    why += " (" + std::to_string(report.output.intersecting_triangles) +
           " intersecting triangles left after the intersection repair: " + report.quality.repair_summary + ")";
  // The validity loop is what keeps a projection from crossing itself; the repair after it
  // mends a few regions only.
  const int default_rounds = WrapParams{}.validity_rounds;
  if (verdict.valid_polygon_mesh && verdict.self_intersects && run.params.validity_rounds < default_rounds)
    why += "; the projection's validity loop ran " + std::to_string(run.params.validity_rounds) +
           " rounds only: more (--validity-rounds, default " + std::to_string(default_rounds) +
           ") hold back the nodes whose moves cross the wrap";
  return why;
}

// The inside and a seed point's volume are not refined where the fit is far (a finer grid can
// open a passage: a leak), so where such a volume is thinner than a few base cells the wrap
// stays off the input, or holds only the piece of it the flood fill kept at this base size.
// The user is told, with the remedy, when a twentieth of the wrap is over half a cell off (a
// single far point is a crease the wrap bridges, as the outside's are before their refit).
void warn_where_far(const WrapRun& run) {
  const DistanceStats& d = run.report.output_to_input;
  if (!run.progress || run.params.volume == VolumeChoice::Outside || !(d.p95 > 0.5 * run.base)) return;
  char text[400];
  std::snprintf(text, sizeof text,
                "a twentieth of the wrap is over %.3g base cells off the input (the farthest point %.3g, at %.6g, "
                "%.6g, %.6g): the %s is not refined where the fit is far, so where it is thinner than a few base "
                "cells the flood fill may have kept only part of it; a smaller --base-size wraps it closer",
                d.p95 / run.base, d.max / run.base, d.max_at[0], d.max_at[1], d.max_at[2],
                run.params.volume == VolumeChoice::Inside ? "inside volume" : "seed point's volume");
  run.progress->progress("distances", 1.0, text);
}

}  // namespace

void validate_surface(WrapRun& run) {
  WrapReport& report = run.report;
  post::PostSurface& surface = run.surface;
  std::vector<uint32_t> crossing;  // CGAL's intersecting faces of the final surface
  // The final quality analysis runs beside the first validation: it holds when the validation
  // finds no intersection (nothing to count for it, nothing repaired); else it runs again after.
  QualityCounts quality_beside;
  std::vector<uint8_t> final_flags;  // per triangle, for WrapResult::triangle_flags
  double quality_beside_seconds = 0;
  bool repaired_in_validation = false;
  {
    StageTimer timer("validate", report.stages);
    if (run.progress) run.progress->progress("validate", 0.0, "checking the wrap");
    check::CgalVerdict verdict;
    for (int attempt = 0;; ++attempt) {
      // The authoritative self-intersection verdict is CGAL's own on the closed mesh. The
      // checks only read the surface, and each has serial parts: side by side.
      tbb::task_group checks;
      checks.run([&] { report.output = diagnose(run.result.surface, false); });
      if (attempt == 0)
        checks.run([&] {
          const auto start = std::chrono::steady_clock::now();
          const std::vector<uint32_t> none;
          quality_beside = post::analyse_quality(surface.points, surface.triangles, surface.cell_size, run.quality_ref,
                                                 &final_flags, &none, &run.deviation_memo);
          quality_beside_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
        });
      checks.run_and_wait(
          [&] { verdict = check::cgal_verdict(run.result.surface.points, run.result.surface.triangles); });
      run.check_cancel();
      report.output.self_intersecting = verdict.self_intersects;
      crossing.clear();
      if (verdict.valid_polygon_mesh && verdict.self_intersects) {
        // Count what CGAL finds. Not asked again when its verdict was no: the same search
        // would find nothing.
        crossing = check::mesh_self_intersecting_faces(run.result.surface.points, run.result.surface.triangles);
        report.output.intersecting_triangles = crossing.size();
      }
      // A closed manifold that intersects itself: the intersection repair, once.
      if (attempt > 0 || !verdict.self_intersects || !verdict.valid_polygon_mesh || !report.output.closed) break;
      if (!run.repair_if_intersecting()) break;
      repaired_in_validation = true;
      run.result.surface = run.labelled_surface();
    }
    if (!report.output.valid_closed_surface() || !verdict.valid_polygon_mesh || !verdict.outward) {
      // For diagnosis (debug-dump builds): VDBWRAP_DUMP_INVALID=FILE keeps the rejected surface.
      if (const char* dump = debug::setting("VDBWRAP_DUMP_INVALID")) io::write_mesh(run.result.surface, dump);
      throw WrapFailure(why_invalid(run, verdict), report);
    }
    report.contact.separate_bodies = report.output.components;
    if (run.progress) run.progress->progress("validate", 1.0, "closed, manifold, outward, no self-intersections");
  }
  if (crossing.empty() && !repaired_in_validation) {
    report.quality.after = quality_beside;
    StageStats beside;  // timed inside the validation
    beside.name = "quality";
    beside.seconds = quality_beside_seconds;
    beside.peak_memory_mb = current_peak_memory_mb();
    report.stages.push_back(beside);
  } else {
    StageTimer timer("quality", report.stages);
    report.quality.after = post::analyse_quality(surface.points, surface.triangles, surface.cell_size, run.quality_ref,
                                                 &final_flags, &crossing, &run.deviation_memo);
  }
  run.result.triangle_flags = post::wrap_defect_flags(run.result.surface.points, run.result.surface.triangles,
                                                      std::move(final_flags), std::move(run.fitted.held_back_points));
}

void measure_distances(WrapRun& run) {
  if (run.params.compute_distances) {
    StageTimer timer("distances", run.report.stages);
    if (run.progress) run.progress->progress("distances", 0.0, "sampling distances between the wrap and the input");
    // To the input as prepared, whose index the projection built (a second index over a large
    // input took seconds): the same surface up to the weld, less degenerate triangles and faces
    // inside the material (voxel art's contact faces), which only a point inside the material
    // can have nearer than the surface.
    Box3 box;
    for (const Vec3& p : run.input.points) box.add(p);
    run.report.output_to_input = check::sampled_distance_to(
        run.result.surface, check::IndexedSurface{run.index(), run.prepared.origin, box.diagonal()}, 1000);
    run.check_cancel();
    run.report.input_to_output = sampled_distance(run.input, run.result.surface);
    run.check_cancel();
    run.report.sharp_edges_to_output = sharp_edge_distance(run.input, run.result.surface);
    warn_where_far(run);
  }
  run.report.total_seconds = run.seconds();
}

}  // namespace vdbwrap::pipeline
