// The one range check of WrapParams. The CLI's options, the YAML form and the gRPC mapping
// all end here, so a parameter has one range and one message, named as in WrapParameters.
#include <cmath>
#include <string>

#include "vdbwrap/params.h"

namespace vdbwrap {
namespace {

[[noreturn]] void bad(const std::string& field, const std::string& what) {
  throw Error(ErrorKind::InvalidArgument, "parameter " + field + ": " + what);
}

bool finite(const Vec3& v) { return std::isfinite(v[0]) && std::isfinite(v[1]) && std::isfinite(v[2]); }

void positive(const Length& l, const std::string& field) {
  if (!(l.value > 0) || !std::isfinite(l.value)) bad(field, "must be a positive length");
}

}  // namespace

void validate(const WrapParams& p) {
  positive(p.base_size, "base_size");
  if (p.levels < 0 || p.levels > 6) bad("levels", "must be between 0 and 6");
  if (p.thin_part_levels < 0 || p.thin_part_levels > 3) bad("thin_part_levels", "must be between 0 and 3");
  if (!(p.feature_angle_deg > 0 && p.feature_angle_deg < 180))
    bad("feature_angle_deg", "must be strictly between 0 and 180 degrees");
  if (p.volume == VolumeChoice::SeedPoints && p.seed_points.empty())
    bad("seed_points", "a volume chosen by seed points needs at least one");
  if (p.volume != VolumeChoice::SeedPoints && !p.seed_points.empty())
    bad("seed_points", "given, but the volume is not chosen by seed points");
  for (const Vec3& s : p.seed_points)
    if (!finite(s)) bad("seed_points", "a seed point has a non-finite coordinate");
  if (p.threads < 0) bad("threads", "must be 0 (all cores) or more");

  if (p.gap_closure) positive(*p.gap_closure, "gap_closure");
  if (p.contact_floor) positive(*p.contact_floor, "contact_floor");
  for (const auto& cv : p.control_volumes) {
    const std::string field = "control_volumes (" + cv.to_string() + ")";
    positive(cv.size, field + " size");
    if (!finite(cv.a) || !finite(cv.b)) bad(field, "a coordinate is not finite");
    if (!(cv.radius >= 0) || !(cv.radius_b >= 0)) bad(field, "radii must not be negative");
  }
  for (const auto& ps : p.part_sizes) {
    if (ps.part.empty()) bad("part_sizes", "part name is empty");
    positive(ps.size, "part_sizes (" + ps.part + ")");
  }
  for (const auto& rule : p.contact_prevention) {
    size_t names = 0;
    for (const auto& g : rule.groups) names += g.size();
    if (rule.groups.empty() || rule.groups.size() > 2 || names < 2)
      bad("contact_prevention (" + rule.to_string() + ")", "name two groups (a:b) or at least two parts (a,b)");
  }

  if (p.refine_max_triangles < 1) bad("refine_max_triangles", "must be at least 1");
  if (!(p.refine_normal_spread_deg >= 0 && p.refine_normal_spread_deg <= 180))
    bad("refine_normal_spread_deg", "must be between 0 and 180 degrees");
  if (!(p.weld_tolerance >= 0 && p.weld_tolerance < 0.01))
    bad("weld_tolerance", "must be in [0, 0.01) of the diagonal");
  if (!(p.surface_offset >= 0 && p.surface_offset < 0.5))
    bad("surface_offset", "must be in [0, 0.5) of the finest cell");
  if (p.presmooth_iterations < 0 || p.presmooth_iterations > 100)
    bad("presmooth_iterations", "must be between 0 and 100");
  if (p.validity_rounds < 0 || p.validity_rounds > 100000) bad("validity_rounds", "must be between 0 and 100000");
  if (!(p.corner_angle_deg > 0 && p.corner_angle_deg < 180))
    bad("corner_angle_deg", "must be strictly between 0 and 180 degrees");
  if (!(p.coarsen_tolerance >= 0 && p.coarsen_tolerance <= 0.5))
    bad("coarsen_tolerance", "must be in [0, 0.5] of the base size");
}

}  // namespace vdbwrap
