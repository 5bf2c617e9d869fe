// What a repaired mesh must keep to, measured on its own (not taken from the repair's report):
// the distance between the input and the output both ways, and where the intersections left
// lie.
#pragma once
#include <algorithm>
#include <cmath>
#include <vector>

#include "check/intersections.h"
#include "mesh/surface_index.h"
#include "vdbwrap/mesh.h"

namespace vdbwrap::testing {

// Points spread over every triangle: its corners and a barycentric grid of `n` steps a side.
inline std::vector<Vec3> surface_samples(const Mesh& m, int n = 4) {
  std::vector<Vec3> out;
  for (const Tri& t : m.triangles)
    for (int i = 0; i <= n; ++i)
      for (int j = 0; i + j <= n; ++j) {
        const double u = double(i) / n, v = double(j) / n, w = 1 - u - v;
        const Vec3 &a = m.points[t[0]], &b = m.points[t[1]], &c = m.points[t[2]];
        out.push_back({a[0] * u + b[0] * v + c[0] * w, a[1] * u + b[1] * v + c[1] * w, a[2] * u + b[2] * v + c[2] * w});
      }
  return out;
}

// The largest distance from a sample of `from` to the surface `to`.
inline double largest_distance(const Mesh& from, const Mesh& to) {
  const mesh::SurfaceIndex index(to.points, to.triangles);
  double worst = 0;
  for (const Vec3& s : surface_samples(from)) worst = std::max(worst, index.squared_distance(s));
  return std::sqrt(worst);
}

// Two-sided: the larger of the distances input -> output and output -> input.
inline double two_sided_distance(const Mesh& a, const Mesh& b) {
  return std::max(largest_distance(a, b), largest_distance(b, a));
}

// The triangles of `output` in an intersecting pair that lie (all their samples) farther than
// `radius` from every triangle of `input` that was in an intersecting pair: intersections
// where the input had none.
inline size_t intersecting_triangles_away_from_the_input_ones(const Mesh& input, const Mesh& output, double radius) {
  std::vector<Tri> was;
  for (const auto& p : check::find_intersecting_pairs(input.points, input.triangles))
    for (uint32_t t : {p.a, p.b}) was.push_back(input.triangles[t]);
  std::vector<uint32_t> now;
  for (const auto& p : check::find_intersecting_pairs(output.points, output.triangles))
    for (uint32_t t : {p.a, p.b}) now.push_back(t);
  std::sort(now.begin(), now.end());
  now.erase(std::unique(now.begin(), now.end()), now.end());
  if (now.empty()) return 0;
  if (was.empty()) return now.size();
  const mesh::SurfaceIndex index(input.points, was);
  size_t away = 0;
  for (uint32_t t : now) {
    Mesh one;
    one.points = output.points;
    one.triangles = {output.triangles[t]};
    bool near = false;
    for (const Vec3& s : surface_samples(one, 1)) near |= index.within(s, radius);
    away += near ? 0 : 1;
  }
  return away;
}

}  // namespace vdbwrap::testing
