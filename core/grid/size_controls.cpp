#include "grid/size_controls.h"

#include <algorithm>
#include <cmath>
#include <unordered_map>

#include "common/vec.h"
#include "vdbwrap/errors.h"

namespace vdbwrap::grid {
namespace {

// Distance from (x, y) to the segment (x0, y0)-(x1, y1) in the plane.
double segment_distance_2d(double x, double y, double x0, double y0, double x1, double y1) {
  double dx = x1 - x0, dy = y1 - y0;
  double len2 = dx * dx + dy * dy;
  double t = len2 > 0 ? std::clamp(((x - x0) * dx + (y - y0) * dy) / len2, 0.0, 1.0) : 0.0;
  double ex = x0 + t * dx - x, ey = y0 + t * dy - y;
  return std::sqrt(ex * ex + ey * ey);
}

void check_level(int level, const std::string& what, double size, double base) {
  if (level > kMaxGridLevels)
    throw Error(ErrorKind::InvalidArgument, what + " asks for cells of " + std::to_string(size) + ", more than " +
                                                std::to_string(kMaxGridLevels) + " halvings below the base size " +
                                                std::to_string(base) + ": use a larger size or a smaller base size");
}

}  // namespace

int level_for_size(double base, double size) {
  if (!(size > 0)) return 0;
  int level = 0;
  while (base / double(1 << level) > size * (1 + 1e-9) && level < 62) ++level;
  return level;
}

double control_volume_distance(const ControlVolume& cv, const Vec3& p) {
  switch (cv.shape) {
    case ControlVolume::Shape::Box: {
      double outside2 = 0, inside = -INFINITY;
      for (int k = 0; k < 3; ++k) {
        double d = std::max(cv.a[k] - p[k], p[k] - cv.b[k]);
        if (d > 0) outside2 += d * d;
        inside = std::max(inside, d);
      }
      return outside2 > 0 ? std::sqrt(outside2) : inside;
    }
    case ControlVolume::Shape::Sphere:
      return norm(p - cv.a) - cv.radius;
    case ControlVolume::Shape::Cylinder:
    case ControlVolume::Shape::Cone: {
      // A solid of revolution: the distance is the one in the meridian half-plane (x along
      // the axis, y from it) to the profile, the quadrilateral (0,0) (L,0) (L,rb) (0,ra).
      const Vec3 axis = cv.b - cv.a;
      const double L = norm(axis);
      const Vec3 u = axis * (1.0 / L);
      const double x = dot(p - cv.a, u);
      const double y = norm(p - cv.a - u * x);
      const double ra = cv.radius, rb = cv.shape == ControlVolume::Shape::Cone ? cv.radius_b : cv.radius;
      const bool inside = x >= 0 && x <= L && y <= ra + (rb - ra) * x / L;
      double d = std::min({segment_distance_2d(x, y, 0, 0, L, 0), segment_distance_2d(x, y, L, 0, L, rb),
                           segment_distance_2d(x, y, L, rb, 0, ra), segment_distance_2d(x, y, 0, ra, 0, 0)});
      // The axis edge (y = 0) is inside the solid, not on its surface: ignore it for inside points.
      if (inside)
        d = -std::min({segment_distance_2d(x, y, L, 0, L, rb), segment_distance_2d(x, y, L, rb, 0, ra),
                       segment_distance_2d(x, y, 0, ra, 0, 0)});
      return d;
    }
  }
  return INFINITY;
}

int region_level(const SizeControls& controls, const Vec3& lo, double h) {
  int level = 0;
  const Vec3 centre = lo + Vec3{0.5 * h, 0.5 * h, 0.5 * h};
  const double half_diagonal = 0.5 * std::sqrt(3.0) * h;
  for (const auto& r : controls.regions) {
    if (r.level <= level) continue;
    bool overlaps;
    if (r.shape.shape == ControlVolume::Shape::Box) {
      overlaps = true;
      for (int k = 0; k < 3; ++k) overlaps = overlaps && lo[k] <= r.shape.b[k] && lo[k] + h >= r.shape.a[k];
    } else {
      // Conservative: the cell's circumscribed sphere meets the solid.
      overlaps = control_volume_distance(r.shape, centre) <= half_diagonal;
    }
    if (overlaps) level = r.level;
  }
  return level;
}

SizeControls make_size_controls(const SizeRequests& params, const Mesh& mesh, const Vec3& origin, double diagonal,
                                double base) {
  SizeControls sc;
  sc.criteria_levels = params.levels;
  sc.max_level = params.levels;
  for (const ControlVolume& cv : params.control_volumes) {
    SizeControls::Region r;
    r.shape = cv;
    r.shape.a = cv.a - origin;
    r.shape.b = cv.b - origin;
    const double size = cv.size.resolve(diagonal);
    r.level = level_for_size(base, size);
    check_level(r.level, "control volume " + cv.to_string(), size, base);
    sc.max_level = std::max(sc.max_level, r.level);
    sc.described.emplace_back("control volume " + cv.to_string(), base / double(1 << r.level));
    sc.regions.push_back(r);
  }

  const size_t parts = std::max<size_t>(1, mesh.part_names.size());
  std::unordered_map<std::string, int32_t> part_index;
  for (size_t i = 0; i < mesh.part_names.size(); ++i) part_index.emplace(mesh.part_names[i], int32_t(i));
  auto find_part = [&](const std::string& name, const std::string& context) {
    auto it = part_index.find(name);
    if (it == part_index.end()) {
      std::string known;
      for (size_t i = 0; i < mesh.part_names.size() && i < 20; ++i) known += (i ? ", " : "") + mesh.part_names[i];
      throw Error(ErrorKind::InvalidArgument,
                  context + ": the input has no part named '" + name + "'" +
                      (known.empty() ? " (it has no named parts)" : " (parts: " + known + ")"));
    }
    return it->second;
  };

  sc.part_level.assign(parts, 0);
  for (const PartSize& ps : params.part_sizes) {
    const int32_t p = find_part(ps.part, "part size " + ps.part);
    const double size = ps.size.resolve(diagonal);
    const int level = level_for_size(base, size);
    check_level(level, "part size for " + ps.part, size, base);
    sc.part_level[size_t(p)] = std::max(sc.part_level[size_t(p)], level);
    sc.max_level = std::max(sc.max_level, level);
    sc.described.emplace_back("part " + ps.part, base / double(1 << level));
  }

  if (!params.contact_prevention.empty()) {
    sc.conflict.assign(parts, std::vector<uint8_t>(parts, 0));
    sc.part_in_contact_rule.assign(parts, 0);
    for (const ContactRule& rule : params.contact_prevention) {
      // Side of each named part within this rule: its group, or itself for a single group.
      std::vector<std::pair<int32_t, int>> sides;
      const bool single = rule.groups.size() == 1;
      for (size_t g = 0; g < rule.groups.size(); ++g)
        for (size_t i = 0; i < rule.groups[g].size(); ++i) {
          int32_t p = find_part(rule.groups[g][i], "contact prevention " + rule.to_string());
          sides.emplace_back(p, single ? int(i) : int(g));
          sc.part_in_contact_rule[size_t(p)] = 1;
        }
      for (const auto& [p, sp] : sides)
        for (const auto& [q, sq] : sides)
          if (sp != sq && p != q) sc.conflict[size_t(p)][size_t(q)] = 1;
    }
    const double finest = base / double(1 << params.levels);
    sc.contact_floor = params.contact_floor ? params.contact_floor->resolve(diagonal) : finest / 8;
    sc.contact_level = std::max(params.levels, level_for_size(base, sc.contact_floor));
    check_level(sc.contact_level, "the contact floor", sc.contact_floor, base);
    sc.max_level = std::max(sc.max_level, sc.contact_level);
  }
  return sc;
}

}  // namespace vdbwrap::grid
