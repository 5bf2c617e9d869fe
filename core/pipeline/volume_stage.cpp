// Stage 2: the voxel volume. Size controls and the refined grid, the flood fill that chooses
// the volume (gap closure, leaks), and the volume's manifold lattice surface.
#include <array>
#include <cmath>
#include <cstdio>
#include <set>

#include "common/stage_timer.h"
#include "common/vec.h"
#include "grid/flood_fill.h"
#include "grid/volume_select.h"
#include "mesh/surface_index.h"
#include "pipeline/stage_params.h"
#include "pipeline/stages.h"

namespace vdbwrap::pipeline {
namespace {

void report_contacts(WrapRun& run) {
  ContactReport& contact = run.report.contact;
  contact.rules = run.params.contact_prevention.size();
  contact.floor = run.controls.contact_floor;
  contact.unresolved_cells = run.refined.unresolved_contacts.size();
  contact.unresolved_locations.clear();  // a second build (refine_where_far) lists them anew
  // One location per base cell is plenty to find them.
  std::set<std::array<long, 3>> seen;
  for (const Vec3& c : run.refined.unresolved_contacts) {
    std::array<long, 3> key{long(std::floor(c[0] / run.base)), long(std::floor(c[1] / run.base)),
                            long(std::floor(c[2] / run.base))};
    if (seen.insert(key).second && contact.unresolved_locations.size() < kMostContactLocations)
      contact.unresolved_locations.push_back(c + run.prepared.origin);
  }
}

// A seed point's volume reached the outside or another seed's: the wrap stops here, with the
// way through in the report.
[[noreturn]] void fail_with_leak(WrapRun& run, const LeakReport& leak) {
  WrapReport& report = run.report;
  report.leak = leak;
  report.leak.location = report.leak.location + run.prepared.origin;
  for (Vec3& p : report.leak.path) p = p + run.prepared.origin;
  const Vec3& at = report.leak.location;
  char where[160];
  std::snprintf(where, sizeof where, " through a passage about %.4g wide at (%.6g, %.6g, %.6g)", report.leak.width,
                at[0], at[1], at[2]);
  report.total_seconds = run.seconds();
  throw WrapFailure(
      "leak: " + report.leak.description + where + " (close the hole, or set --gap-closure above its width)", report);
}

void choose_volume(WrapRun& run) {
  StageTimer timer("flood fill", run.report.stages);
  const WrapParams& params = run.params;
  grid::VolumeRequest request;
  request.choice = params.volume;
  request.world_offset = run.prepared.origin;
  for (const Vec3& s : params.seed_points) request.seeds.push_back(s - run.prepared.origin);
  request.gap_closure = params.gap_closure ? params.gap_closure->resolve(run.prepared.diagonal) : 0.0;
  // Clearances are measured for gap closure and for a seed's leak only.
  if (request.gap_closure > 0 || !request.seeds.empty()) run.index();
  grid::VolumeSelection sel = grid::select_volume(
      *run.refined.grid, request,
      [&](const Vec3& p) {
        const mesh::SurfaceIndex::Hit hit = run.index_builder->get()->closest(p);
        const double d = std::sqrt(hit.squared_distance);
        return dot(p - hit.point, hit.normal) < 0 ? -d : d;
      },
      run.progress);
  run.report.volumes = sel.report;
  if (sel.leak.detected) fail_with_leak(run, sel.leak);
  run.label = sel.label;
  run.anchors = sel.anchors;
}

}  // namespace

void build_volume(WrapRun& run) {
  WrapReport& report = run.report;
  const prep::PreparedInput& prepared = run.prepared;
  run.controls =
      grid::make_size_controls(size_requests(run.params), prepared.mesh, prepared.origin, prepared.diagonal, run.base);
  report.finest_size = run.base / double(1 << run.controls.max_level);
  report.control_sizes = run.controls.described;
  run.check_cancel();

  // The nearest-point index: for the clearance of gap closure and leaks, then projection. Its
  // build is serial in part (CGAL's tree): it overlaps the refinement and the flood fill.
  // (A second build, the refit where the first fit is far, keeps the index and the curves of the first.)
  if (!run.index_builder)
    run.index_builder = std::make_unique<InBackground<std::unique_ptr<mesh::SurfaceIndex>>>(
        [&prepared] { return std::make_unique<mesh::SurfaceIndex>(prepared.mesh.points, prepared.mesh.triangles); });
  {
    StageTimer timer("refine", report.stages);
    grid::RefineCriteria criteria = refine_criteria(run.params);
    criteria.refine_near = run.refine_near;
    criteria.near_reach = kRefitNearReach * run.base;
    if (!run.refine_near.empty() && !(criteria.far_point_cells > 0))  // the refit: cells with far points, near them
      criteria.far_point_cells = 1, criteria.far_point_reach = kRefitFarCellsReach * run.base;
    run.refined = grid::build_refined_grid(prepared, criteria, run.base, run.controls, run.progress);
  }
  report.cells_per_level = run.refined.touched_per_level;
  report.thin_part_cells = run.refined.thin_cells;
  if (run.controls.contact()) report_contacts(run);
  run.check_cancel();

  // The input's feature curves (serial), beside the flood fill (serial too).
  const bool snap = run.params.snap_features;
  const double corner_angle = run.params.corner_angle_deg;
  if (!run.curves_builder)
    run.curves_builder =
        std::make_unique<InBackground<std::vector<fit::FeatureCurve>>>([&prepared, snap, corner_angle] {
          return snap ? fit::build_feature_curves(prepared, corner_angle) : std::vector<fit::FeatureCurve>();
        });
  choose_volume(run);
  run.check_cancel();

  {
    StageTimer timer("extract", report.stages);
    extract::ExtractStats stats;
    run.lattice = extract::extract_manifold_surface(*run.refined.grid, run.label, run.params.volume, stats,
                                                    run.progress, run.anchors, run.params.levels);
    report.manifold_fixes = stats.excluded_cells;
  }
  run.check_cancel();
}

}  // namespace vdbwrap::pipeline
