#include "pipeline/stage_params.h"

namespace vdbwrap::pipeline {

prep::PrepareParams prepare_params(const WrapParams& params) {
  prep::PrepareParams p;
  p.weld_tolerance = params.weld_tolerance;
  p.feature_angle_deg = params.feature_angle_deg;
  return p;
}

grid::SizeRequests size_requests(const WrapParams& params) {
  grid::SizeRequests r;
  r.levels = params.levels;
  r.control_volumes = params.control_volumes;
  r.part_sizes = params.part_sizes;
  r.contact_prevention = params.contact_prevention;
  r.contact_floor = params.contact_floor;
  return r;
}

grid::RefineCriteria refine_criteria(const WrapParams& params) {
  grid::RefineCriteria c;
  c.max_triangles = params.refine_max_triangles;
  c.normal_spread_deg = params.refine_normal_spread_deg;
  c.at_features = params.refine_at_features;
  return c;
}

}  // namespace vdbwrap::pipeline
