// The pipeline: stage 1 (prepare), stage 2 (refine, flood fill, extract), stage 3 and the
// triangulation (fit), final validation and the report.
#include <tbb/task_arena.h>
#include <tbb/parallel_for.h>
#include <tbb/task_group.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <memory>
#include <set>

#include "check/diagnostics.h"
#include "check/intersections.h"
#include "common/debug_switch.h"
#include "common/in_background.h"
#include "common/stage_timer.h"
#include "common/vec.h"
#include "io/mesh_io.h"
#include "pipeline/stage_params.h"
#include "extract/extract_surface.h"
#include "fit/feature_insert.h"
#include "fit/fit_surface.h"
#include "fit/surface_index.h"
#include "grid/flood_fill.h"
#include "grid/refine.h"
#include "grid/size_controls.h"
#include "grid/volume_select.h"
#include "post/coarsen.h"
#include "post/quality.h"
#include "post/remesh.h"
#include "post/repair_wrap.h"
#include "post/wrap_defects.h"
#include "prep/check_input.h"
#include "prep/prepare.h"
#include "vdbwrap/wrap.h"

namespace vdbwrap {
namespace {

void check_cancel(ProgressSink* progress) {
  if (progress && progress->cancelled()) throw Error(ErrorKind::Cancelled, "cancelled");
}

}  // namespace

namespace {
WrapResult run_pipeline(const Mesh& input, const WrapParams& params, ProgressSink* progress);
}

WrapResult wrap(const Mesh& input, const WrapParams& params, ProgressSink* progress) {
  validate(params);
  prep::check_input_mesh(input);
  // A task arena per job: its thread limit holds for this job only, so a server running
  // several jobs at once does not let one job's limit throttle the others.
  if (params.threads <= 0) return run_pipeline(input, params, progress);
  tbb::task_arena arena(params.threads);
  return arena.execute([&] { return run_pipeline(input, params, progress); });
}

namespace {
WrapResult run_pipeline(const Mesh& input, const WrapParams& params, ProgressSink* progress) {
  const auto t0 = std::chrono::steady_clock::now();
  WrapResult result;
  WrapReport& report = result.report;
  report.params = params;

  ExactWeld input_weld;  // shared with prepare
  {
    StageTimer timer("diagnose input", report.stages);
    if (progress) progress->progress("diagnose input", 0.0, "checking the input for defects");
    // Intersections are left to prepare, whose one search serves both the report and the
    // intersection lines; the counts are filled in below.
    input_weld = exact_weld(input.points);
    report.input = check::diagnose_welded(input, input_weld, false);
  }
  check_cancel(progress);

  prep::PreparedInput prepared;
  {
    StageTimer timer("prepare", report.stages);
    prepared = prep::prepare(input, pipeline::prepare_params(params), progress, &input_weld);
    input_weld = ExactWeld();  // its memory back
  }
  {
    const prep::InputIntersections crossing =
        prep::input_intersections(prepared.intersecting_pairs, prepared.input_to_mesh, prepared.mesh.triangles.size());
    report.input.intersecting_pairs = crossing.pairs;
    report.input.intersecting_triangles = crossing.triangles;
    report.input.self_intersecting = crossing.pairs > 0;
  }
  for (const auto& f : prepared.feature_edges) {
    if (f.kind == prep::FeatureKind::Sharp) ++report.features.sharp_edges;
    if (f.kind == prep::FeatureKind::Boundary) ++report.features.boundary_edges;
    if (f.kind == prep::FeatureKind::NonManifold) ++report.features.nonmanifold_edges;
  }
  report.features.intersection_segments = prepared.intersections.size();
  report.diagonal = prepared.diagonal;
  const double base = params.base_size.resolve(prepared.diagonal);
  report.base_size = base;
  if (prepared.diagonal / base > 20000)
    throw Error(ErrorKind::InvalidArgument, "base size " + params.base_size.to_string() +
                                                " is too small for this model (over 20000 cells across its diagonal)");
  const grid::SizeControls controls =
      grid::make_size_controls(pipeline::size_requests(params), prepared.mesh, prepared.origin, prepared.diagonal, base);
  report.finest_size = base / double(1 << controls.max_level);
  report.control_sizes = controls.described;
  check_cancel(progress);

  // The nearest-point index: for the clearance of gap closure and leaks, then projection. Its
  // build is serial in part (CGAL's tree), seconds on millions of triangles.
  InBackground<std::unique_ptr<fit::SurfaceIndex>> index_builder(
      [&] { return std::make_unique<fit::SurfaceIndex>(prepared.mesh.points, prepared.mesh.triangles); });
  const fit::SurfaceIndex* index_ready = nullptr;
  auto wait_for_index = [&]() -> const fit::SurfaceIndex& {
    if (!index_ready) {
      StageTimer timer("index", report.stages);  // what is left of the build when first needed
      index_ready = index_builder.get().get();
    }
    return *index_ready;
  };
  grid::RefineResult refined;
  {
    StageTimer timer("refine", report.stages);
    refined = grid::build_refined_grid(prepared, pipeline::refine_criteria(params), base, controls, progress);
  }
  report.cells_per_level = refined.touched_per_level;
  if (controls.contact()) {
    report.contact.rules = params.contact_prevention.size();
    report.contact.floor = controls.contact_floor;
    report.contact.unresolved_cells = refined.unresolved_contacts.size();
    // One location per base cell is plenty to find them.
    std::set<std::array<long, 3>> seen;
    for (const Vec3& c : refined.unresolved_contacts) {
      std::array<long, 3> key{long(std::floor(c[0] / base)), long(std::floor(c[1] / base)), long(std::floor(c[2] / base))};
      if (seen.insert(key).second && report.contact.unresolved_locations.size() < 100)
        report.contact.unresolved_locations.push_back(c + prepared.origin);
    }
  }
  grid::AdaptiveGrid& g = *refined.grid;
  check_cancel(progress);

  // The input's feature curves (serial), beside the flood fill (serial too).
  InBackground<std::vector<fit::FeatureCurve>> curves_builder([&] {
    return params.snap_features ? fit::build_feature_curves(prepared, params.corner_angle_deg) : std::vector<fit::FeatureCurve>();
  });
  int32_t label;
  std::vector<grid::Coord> anchors;
  {
    StageTimer timer("flood fill", report.stages);
    grid::VolumeRequest request;
    request.choice = params.volume;
    request.world_offset = prepared.origin;
    for (const Vec3& s : params.seed_points) request.seeds.push_back(s - prepared.origin);
    request.gap_closure = params.gap_closure ? params.gap_closure->resolve(prepared.diagonal) : 0.0;
    // Clearances are measured for gap closure and for a seed's leak only.
    if (request.gap_closure > 0 || !request.seeds.empty()) wait_for_index();
    grid::VolumeSelection sel = grid::select_volume(
        g, request, [&](const Vec3& p) { return std::sqrt(index_builder.get()->squared_distance(p)); }, progress);
    report.volumes = sel.report;
    if (sel.leak.detected) {
      report.leak = sel.leak;
      report.leak.location = report.leak.location + prepared.origin;
      for (Vec3& p : report.leak.path) p = p + prepared.origin;
      const Vec3& at = report.leak.location;
      char where[160];
      std::snprintf(where, sizeof where, " through a passage about %.4g wide at (%.6g, %.6g, %.6g)", report.leak.width, at[0],
                    at[1], at[2]);
      report.total_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
      throw WrapFailure("leak: " + report.leak.description + where +
                            " (close the hole, or set --gap-closure above its width)",
                        report);
    }
    label = sel.label;
    anchors = sel.anchors;
  }
  check_cancel(progress);

  extract::LatticeSurface lattice;
  {
    StageTimer timer("extract", report.stages);
    extract::ExtractStats stats;
    lattice = extract::extract_manifold_surface(g, label, params.volume, stats, progress, anchors, params.levels);
    report.manifold_fixes = stats.excluded_cells;
  }
  check_cancel(progress);

  const fit::SurfaceIndex& index = wait_for_index();
  fit::FittedSurface fitted;
  {
    StageTimer timer("project", report.stages);
    const std::vector<fit::FeatureCurve>& curves = curves_builder.get();
    fitted = fit::fit_to_input(lattice, g, index, curves, prepared.origin, params, progress);
    report.nodes_held_back = fitted.held_back;
    report.features.curves = fitted.snap.curves;
    report.features.corners = fitted.snap.corners;
    report.features.curves_captured = fitted.snap.curves_captured;
    report.features.corners_captured = fitted.snap.corners_captured;
    report.features.nodes_snapped = fitted.snap.nodes_snapped;
    if (!curves.empty() && fitted.valid) {
      // Curve points the traced chains missed get nodes of their own (edge splits).
      StageTimer insert_timer("insert feature nodes", report.stages);
      if (progress) progress->progress("project", 0.97, "inserting nodes where the wrap misses a feature curve");
      fit::FeatureInsertParams fp;
      const double hf = g.fine_size();
      fp.spacing = 0.5 * hf;
      fp.tolerance = 0.02 * hf;  // measured on the CAD corpus: 0.05 and 0.1 leave more of the edges off
      fp.max_move = base;
      fp.offset = params.surface_offset * hf;
      fp.min_area2 = 1e-6 * hf * hf;
      fp.min_separation = 0.05 * hf;
      fp.max_deviation = 0.1 * hf;
      fp.float_coordinates = params.float_coordinates;
      const auto fs = fit::insert_feature_nodes(fitted, curves, index, prepared.origin, fp);
      report.features.points_missed = fs.samples_missed;
      report.features.nodes_inserted = fs.nodes_inserted;
      report.features.nodes_moved = fs.nodes_moved;
      report.features.inserts_refused = fs.refused;
      report.features.points_unreachable = fs.unreachable;
    }

    report.triangles_before_coarsening = fitted.triangles.size();
    if (params.coarsen_tolerance > 0) {
      StageTimer coarsen_timer("coarsen", report.stages);
      post::CoarsenParams cp;
      cp.max_deviation = params.coarsen_tolerance * base;
      cp.max_edge = 4.0 * base;  // measured: half the triangles of 2 base, same distances
      cp.min_area2 = 1e-6 * g.fine_size() * g.fine_size();
      const post::CoarsenStats cs =
          post::coarsen(fitted.points, fitted.triangles, fitted.snapped, index, prepared.origin, cp, progress);
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
  }
  check_cancel(progress);

  // Stage 4: quality analysis, remeshing of bad regions, intersection repair when anything
  // still intersects; then the part labels and the final validation.
  post::PostSurface surface{std::move(fitted.points), std::move(fitted.triangles), std::move(fitted.cell_size),
                            std::move(fitted.snapped), std::move(fitted.feature_edges)};
  post::QualityReference quality_ref;
  quality_ref.input = &index;
  quality_ref.origin = prepared.origin;
  quality_ref.feature_samples = post::sample_sharp_edges(prepared, 1e-3 * prepared.diagonal);
  quality_ref.finest_size = report.finest_size;
  quality_ref.thresholds = params.quality;
  post::NormalDeviationMemo deviation_memo;  // the final analysis re-measures only what changed
  // Nearest input points asked again and again by the analysis, the rebuilds and the part labels.
  auto nearest_memo = std::make_unique<post::NearestMemo>(index);
  quality_ref.nearest = nearest_memo.get();
  const double repair_bound = 0.5 * base;  // the intersection repair moves nothing farther than half a base cell
  auto repair_if_intersecting = [&]() {
    const post::WrapRepairOutcome r = post::repair_intersections(surface, repair_bound, params.float_coordinates, progress);
    report.quality.repair_runs += r.ran ? 1 : 0;
    report.quality.intersecting_before_repair += r.intersecting_before;
    report.quality.intersecting_after_repair = r.intersecting_after;
    if (r.ran) report.quality.repair_summary = r.summary;
    return r.ran;
  };
  {
    StageTimer timer("remesh", report.stages);
    if (progress) progress->progress("remesh", 0.0, "quality analysis of " + std::to_string(surface.triangles.size()) + " triangles");
    std::vector<uint8_t> flags;
    report.quality.before = post::analyse_quality(surface.points, surface.triangles, surface.cell_size, quality_ref, &flags, nullptr, &deviation_memo);
    if (params.remesh) {
      post::RemeshParams rp;
      // Rebuilds are held to the coarsening's tolerance (its default when coarsening is off).
      rp.max_deviation = (params.coarsen_tolerance > 0 ? params.coarsen_tolerance : WrapParams().coarsen_tolerance) * base;
      rp.offset = params.surface_offset * g.fine_size();
      rp.float_coordinates = params.float_coordinates;
      const post::RemeshStats st = post::remesh_bad_regions(surface, flags, quality_ref, prepared, rp, progress);
      report.quality.regions = st.regions;
      report.quality.remeshed_on_input = st.on_input;
      report.quality.remeshed_by_ear_clipping = st.ear_clipping;
      report.quality.restored = st.restored;
      report.quality.refusals = st.refusals;
    }
    // Rebuilds never add an intersection: only a surface that had some can have any left.
    if (report.quality.before.self_intersecting > 0 || !fitted.valid) repair_if_intersecting();
  }
  check_cancel(progress);

  // Every output triangle carries the part of the input triangle nearest its centroid. An
  // input of one part (an STL file) gives it to every triangle without asking (a nearest
  // point per output triangle: 0.24 s on the 2.37M assembly at 0.5 %).
  const std::vector<int32_t>& input_parts = prepared.mesh.triangle_part;
  const bool one_part = std::all_of(input_parts.begin(), input_parts.end(), [&](int32_t p) { return p == input_parts.front(); });
  auto label_parts = [&]() {
    Mesh out;
    out.points = surface.points;
    out.triangles = surface.triangles;
    out.part_names = prepared.mesh.part_names;
    if (one_part) {
      out.triangle_part.assign(out.triangles.size(), prepared.mesh.triangles.empty() ? 0 : prepared.mesh.part_of(0));
      return out;
    }
    out.triangle_part.resize(out.triangles.size());
    tbb::parallel_for(tbb::blocked_range<size_t>(0, out.triangles.size(), 1024), [&](const tbb::blocked_range<size_t>& r) {
      for (size_t t = r.begin(); t != r.end(); ++t) {
        const Tri& tri = out.triangles[t];
        Vec3 c = (out.points[tri[0]] + out.points[tri[1]] + out.points[tri[2]]) * (1.0 / 3.0) - prepared.origin;
        out.triangle_part[t] = prepared.mesh.part_of(quality_ref.closest(c).triangle);
      }
    });
    return out;
  };
  result.surface = label_parts();
  quality_ref.nearest = nullptr;  // its memory goes; the final analysis has its own memo
  nearest_memo.reset();
  check_cancel(progress);

  std::vector<uint32_t> crossing;  // CGAL's intersecting faces of the final surface
  // The final quality analysis runs beside the first validation: it holds when the validation
  // finds no intersection (nothing to count for it, nothing repaired); else it runs again after.
  QualityCounts quality_beside;
  std::vector<uint8_t> final_flags;  // per triangle, for WrapResult::triangle_flags
  double quality_beside_seconds = 0;
  bool repaired_in_validation = false;
  {
    StageTimer timer("validate", report.stages);
    if (progress) progress->progress("validate", 0.0, "checking the wrap");
    check::CgalVerdict verdict;
    for (int attempt = 0;; ++attempt) {
      // The authoritative self-intersection verdict is CGAL's own on the closed mesh. The
      // checks only read the surface, and each has serial parts: side by side.
      tbb::task_group checks;
      checks.run([&] { report.output = diagnose(result.surface, false); });
      if (attempt == 0)
        checks.run([&] {
          const auto start = std::chrono::steady_clock::now();
          const std::vector<uint32_t> none;
          quality_beside = post::analyse_quality(surface.points, surface.triangles, surface.cell_size, quality_ref, &final_flags, &none,
                                                 &deviation_memo);
          quality_beside_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
        });
      checks.run_and_wait([&] { verdict = check::cgal_verdict(result.surface.points, result.surface.triangles); });
      check_cancel(progress);
      report.output.self_intersecting = verdict.self_intersects;
      crossing.clear();
      if (verdict.valid_polygon_mesh && verdict.self_intersects) {
        // Count what CGAL finds. Not asked again when its verdict was no: the same search
        // would find nothing (it was a third of the stage).
        crossing = check::mesh_self_intersecting_faces(result.surface.points, result.surface.triangles);
        report.output.intersecting_triangles = crossing.size();
      }
      // A closed manifold that intersects itself: the intersection repair, once.
      if (attempt > 0 || !verdict.self_intersects || !verdict.valid_polygon_mesh || !report.output.closed) break;
      if (!repair_if_intersecting()) break;
      repaired_in_validation = true;
      result.surface = label_parts();
    }
    if (!report.output.valid_closed_surface() || !verdict.valid_polygon_mesh || !verdict.outward) {
      // For diagnosis (debug-dump builds): VDBWRAP_DUMP_INVALID=FILE keeps the rejected surface.
      if (const char* dump = debug::setting("VDBWRAP_DUMP_INVALID")) io::write_mesh(result.surface, dump);
      std::string why = "the wrap failed validation: closed=" + std::to_string(report.output.closed) +
                        " manifold=" + std::to_string(report.output.manifold) + " outward=" + std::to_string(verdict.outward);
      // CGAL's self-intersection test runs on a closed manifold only: otherwise there is no verdict.
      if (verdict.valid_polygon_mesh) why += " self-intersecting=" + std::to_string(verdict.self_intersects);
      if (params.float_coordinates) {
        // Far from the origin, single precision cannot hold cells this small: points merge.
        double far = 0, cell = INFINITY;
        for (const Vec3& p : result.surface.points) far = std::max({far, std::fabs(p[0]), std::fabs(p[1]), std::fabs(p[2])});
        for (double c : surface.cell_size) cell = std::min(cell, c);
        const double float_step = far * 6e-8;  // a float's spacing at that magnitude, about
        if (float_step > 1e-3 * cell) {
          char text[160];
          std::snprintf(text, sizeof text, "; the output is rounded to single precision for STL, whose steps (about %.3g at "
                        "these coordinates) are too coarse for cells of %.3g", float_step, cell);
          why += std::string(text) + ": write .ply, .obj or .vtp, which keep doubles, or move the model nearer the origin";
        }
      }
      if (verdict.valid_polygon_mesh && verdict.self_intersects && report.quality.repair_runs > 0)
        why += " (" + std::to_string(report.output.intersecting_triangles) +
               " intersecting triangles left after the intersection repair: " + report.quality.repair_summary + ")";
      throw WrapFailure(why, report);
    }
    report.contact.separate_bodies = report.output.components;
    if (progress) progress->progress("validate", 1.0, "closed, manifold, outward, no self-intersections");
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
    report.quality.after = post::analyse_quality(surface.points, surface.triangles, surface.cell_size, quality_ref, &final_flags, &crossing, &deviation_memo);
  }

  result.triangle_flags = post::wrap_defect_flags(result.surface.points, result.surface.triangles, std::move(final_flags),
                                                  std::move(fitted.held_back_points));

  if (params.compute_distances) {
    StageTimer timer("distances", report.stages);
    if (progress) progress->progress("distances", 0.0, "sampling distances between the wrap and the input");
    report.output_to_input = sampled_distance(result.surface, input);
    check_cancel(progress);
    report.input_to_output = sampled_distance(input, result.surface);
    check_cancel(progress);
    report.sharp_edges_to_output = sharp_edge_distance(input, result.surface);
  }
  report.total_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return result;
}
}  // namespace

}  // namespace vdbwrap
