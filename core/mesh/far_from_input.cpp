#include "mesh/far_from_input.h"

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>

#include <tbb/parallel_for.h>

namespace vdbwrap::mesh {
namespace {

// The distance to the input, or an upper bound of it: a point within a fiftieth of `far` (most
// of a wrap lies on the input) gets that, from a query bounded by so small a radius, which is
// cheap; a point within `far` its distance; the others the full query.
double distance_within(const SurfaceIndex& input, const Vec3& local, double far) {
  if (input.within(local, 0.02 * far)) return 0.02 * far;
  SurfaceIndex::Hit hit;
  if (input.closest_within(local, far, hit)) return std::sqrt(hit.squared_distance);
  return std::sqrt(input.closest(local).squared_distance);
}

// The farthest a point of the triangle can be from its nearest corner: the circumradius of
// an acute triangle, half the longest edge of any other.
double reach_from_corners(const Vec3& a, const Vec3& b, const Vec3& c) {
  std::array<double, 3> e = {norm2(b - c), norm2(c - a), norm2(a - b)};
  std::sort(e.begin(), e.end());
  if (e[2] >= e[0] + e[1]) return 0.5 * std::sqrt(e[2]);
  const double area2 = norm(area_vector(a, b, c));  // twice the area
  return area2 > 0 ? std::sqrt(e[0] * e[1] * e[2]) / (2 * area2) : 0.5 * std::sqrt(e[2]);
}

}  // namespace

std::vector<FarTriangle> far_triangles(const std::vector<Vec3>& points, const std::vector<Tri>& triangles,
                                       const std::vector<uint8_t>& alive, const SurfaceIndex& input, const Vec3& origin,
                                       double far, std::vector<double>& node_distance) {
  node_distance.assign(points.size(), 0);
  tbb::parallel_for(tbb::blocked_range<size_t>(0, points.size(), 512), [&](const tbb::blocked_range<size_t>& r) {
    for (size_t v = r.begin(); v != r.end(); ++v) node_distance[v] = distance_within(input, points[v] - origin, far);
  });
  const size_t nt = triangles.size();
  std::vector<FarTriangle> worst(nt);
  tbb::parallel_for(tbb::blocked_range<size_t>(0, nt, 512), [&](const tbb::blocked_range<size_t>& r) {
    for (size_t f = r.begin(); f != r.end(); ++f) {
      if (!alive.empty() && !alive[f]) continue;
      const Tri& t = triangles[f];
      FarTriangle& w = worst[f];
      w.triangle = uint32_t(f);
      for (uint32_t v : t)
        if (node_distance[v] >= w.distance) w.distance = node_distance[v], w.at = points[v];
      const Vec3 &a = points[t[0]], &b = points[t[1]], &c = points[t[2]];
      if (w.distance <= far && w.distance + reach_from_corners(a, b, c) > far)
        for (const Vec3& q : {(a + b + c) * (1.0 / 3.0), (a + b) * 0.5, (b + c) * 0.5, (c + a) * 0.5}) {
          const double d = distance_within(input, q - origin, far);
          if (d > w.distance) w.distance = d, w.at = q;
        }
    }
  });
  std::vector<FarTriangle> out;
  for (const FarTriangle& w : worst)
    if (w.distance > far) out.push_back(w);
  std::sort(out.begin(), out.end(), [](const FarTriangle& x, const FarTriangle& y) {
    return x.distance != y.distance ? x.distance > y.distance : x.triangle < y.triangle;
  });
  return out;
}

bool any_farther(const std::vector<Vec3>& points, const std::vector<Tri>& triangles,
                 const std::vector<FarTriangle>& far, const SurfaceIndex& input, const Vec3& origin, int steps,
                 double bound) {
  std::atomic<bool> found{false};
  tbb::parallel_for(tbb::blocked_range<size_t>(0, far.size(), 16), [&](const tbb::blocked_range<size_t>& r) {
    SurfaceIndex::Hit hit;
    for (size_t k = r.begin(); k != r.end() && !found.load(std::memory_order_relaxed); ++k) {
      const Tri& t = triangles[far[k].triangle];
      const Vec3 &a = points[t[0]], &b = points[t[1]], &c = points[t[2]];
      for (int i = 0; i <= steps; ++i)
        for (int j = 0; i + j <= steps; ++j) {
          const Vec3 q = a + (b - a) * (double(i) / steps) + (c - a) * (double(j) / steps);
          if (!input.closest_within(q - origin, bound, hit)) {
            found = true;
            return;
          }
        }
    }
  });
  return found;
}

}  // namespace vdbwrap::mesh
