#include "pipeline/stage_params.h"

#include <algorithm>

namespace vdbwrap::pipeline {

prep::PrepareParams prepare_params(const WrapParams& params) {
  // Only around the outside: the inside volume and a seed point's can lie between the solids.
  return {params.weld_tolerance, params.feature_angle_deg, params.volume == VolumeChoice::Outside,
          !params.contact_prevention.empty()};
}

grid::SizeRequests size_requests(const WrapParams& params) {
  return {params.levels, params.control_volumes, params.part_sizes, params.contact_prevention, params.contact_floor};
}

grid::RefineCriteria refine_criteria(const WrapParams& params) {
  grid::RefineCriteria c{params.refine_max_triangles, params.refine_normal_spread_deg, params.refine_at_features,
                         params.refine_far_cells ? 1.0 : 0.0};
  // Around the outside only, as the refit: finer cells beside a part can open a passage, and
  // for a seed point or the inside volume that would turn a result into a leak.
  c.thin_levels = params.volume == VolumeChoice::Outside ? params.thin_part_levels : 0;
  return c;
}

fit::FitParams fit_params(const WrapParams& params, double crack_gap) {
  return {params.presmooth_iterations, params.surface_offset,   params.validity_rounds,
          params.float_coordinates,    params.two_sided_sheets, crack_gap};
}

fit::FeatureInsertParams feature_insert_params(const WrapParams& params, double base, double fine, double crack_gap) {
  fit::FeatureInsertParams p;
  p.spacing = 0.5 * fine;     // curve samples: twice per finest cell, so no cell's worth of curve is skipped
  p.tolerance = 0.02 * fine;  // a sample nearer than this is kept; looser tolerances leave CAD edges visibly off
  p.max_move = base;          // a node moves at most a base cell onto its curve,
  p.far_reach = 2 * base;     // or two where the wrap bridges the curve over half a cell off
  // Across a crack the faces at a crease stand a gap short of each other or cross by a few
  // (a knife edge's by a gap over the sine of its half angle): a node nearer their curve than
  // four gaps touches one of them, as the tracing takes four gaps for clear
  // (docs/pipeline.md, "Nodes stand four gaps off a crease across a crack").
  p.offset = std::max(params.surface_offset * fine, 4 * crack_gap);
  p.min_area2 = 1e-6 * fine * fine;  // no triangle flatter than this from a split
  p.min_separation = 0.05 * fine;    // nor nodes crowded closer
  p.max_deviation = 0.1 * fine;      // nor a triangle farther off the input
  p.float_coordinates = params.float_coordinates;
  return p;
}

post::CoarsenParams coarsen_params(const WrapParams& params, double base, double fine) {
  post::CoarsenParams p;
  p.max_deviation = params.coarsen_tolerance * base;
  p.max_edge = 4.0 * base;  // longer edges halve no further the triangle count, at the same distances
  p.min_area2 = 1e-6 * fine * fine;
  return p;
}

post::RemeshParams remesh_params(const WrapParams& params, double base, double fine) {
  post::RemeshParams p;
  // Rebuilds are held to the coarsening's tolerance (its default when coarsening is off).
  p.max_deviation = (params.coarsen_tolerance > 0 ? params.coarsen_tolerance : WrapParams().coarsen_tolerance) * base;
  p.offset = params.surface_offset * fine;
  p.float_coordinates = params.float_coordinates;
  return p;
}

double repair_bound(double base) { return 0.5 * base; }

}  // namespace vdbwrap::pipeline
