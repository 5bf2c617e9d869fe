// Triangle planes in doubles with error bounds (see plane_bounds.h).
#include "check/plane_bounds.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <limits>

#include "common/vec.h"

namespace vdbwrap::check::pair_search {

std::vector<PlaneBound> plane_bounds(const std::vector<Vec3>& points, const std::vector<Tri>& triangles,
                                     const std::vector<uint8_t>& usable) {
  double magnitude = 0;
  for (const Vec3& q : points) magnitude = std::max({magnitude, std::fabs(q[0]), std::fabs(q[1]), std::fabs(q[2])});
  const double eps = std::numeric_limits<double>::epsilon();
  std::vector<PlaneBound> out(triangles.size());
  tbb::parallel_for(tbb::blocked_range<size_t>(0, triangles.size(), 4096), [&](const tbb::blocked_range<size_t>& r) {
    for (size_t t = r.begin(); t != r.end(); ++t) {
      if (!usable[t]) continue;
      const Vec3 &a = points[triangles[t][0]], &b = points[triangles[t][1]], &c = points[triangles[t][2]];
      const Vec3 e1 = b - a, e2 = c - a, n = cross(e1, e2);
      const double len = norm(n), l1 = norm(e1), l2 = norm(e2);
      if (!(len > 0)) continue;
      // Each edge is off by up to eps * magnitude per coordinate, and the cross product's own
      // rounding is a few eps of |e1| |e2|; the direction is off by their sum over |n|.
      out[t].normal = n * (1.0 / len);
      out[t].slope = 16 * eps * (l1 * l2 + 2 * magnitude * (l1 + l2)) / len + 8 * eps;
    }
  });
  return out;
}

bool clearly_beside(const std::vector<Vec3>& points, const PlaneBound& plane, const Tri& own, const Tri& other) {
  if (plane.slope < 0 || plane.slope > 1e-3) return false;
  const Vec3& a = points[own[0]];
  int side = 0;
  for (uint32_t v : other) {
    if (v == own[0] || v == own[1] || v == own[2]) continue;
    const Vec3 d = points[v] - a;
    const double distance = dot(plane.normal, d);
    const double error = plane.slope * (std::fabs(d[0]) + std::fabs(d[1]) + std::fabs(d[2])) +
                         16 * std::numeric_limits<double>::epsilon() *
                             (std::fabs(points[v][0]) + std::fabs(points[v][1]) + std::fabs(points[v][2]) +
                              std::fabs(a[0]) + std::fabs(a[1]) + std::fabs(a[2]));
    const int s = distance > error ? 1 : distance < -error ? -1 : 0;
    if (s == 0 || (side != 0 && s != side)) return false;
    side = s;
  }
  return side != 0;
}

}  // namespace vdbwrap::check::pair_search
