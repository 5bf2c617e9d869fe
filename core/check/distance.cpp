// Metro-style sampled distance between two surfaces.
#include <algorithm>
#include <cmath>
#include <random>

#include <tbb/parallel_for.h>

#include "check/distance_stats.h"
#include "common/vec.h"
#include "mesh/surface_index.h"
#include "vdbwrap/check.h"

namespace vdbwrap {

DistanceStats sampled_distance(const Mesh& from, const Mesh& to, double samples_per_diagonal) {
  return check::sampled_distance_skipping(from, to, samples_per_diagonal, {});
}

DistanceStats check::sampled_distance_skipping(const Mesh& from, const Mesh& to, double samples_per_diagonal,
                                               const std::function<bool(const Vec3&)>& skip) {
  DistanceStats s;
  Box3 box;
  for (const auto& p : to.points) box.add(p);
  s.diagonal = box.diagonal();
  if (from.triangles.empty() || to.triangles.empty()) return s;
  // Samples: the vertices (every one up to half a million, evenly strided beyond), plus
  // points spread by area (a stratified count per triangle), about a million at most: plenty
  // for mean and p95, and multi-million-triangle inputs stay quick.
  double area = 0;
  for (const Tri& t : from.triangles)
    area += 0.5 * norm(area_vector(from.points[t[0]], from.points[t[1]], from.points[t[2]]));
  const double spacing = std::max(s.diagonal / samples_per_diagonal, std::sqrt(area / 1e6));
  std::vector<Vec3> samples;
  const size_t stride = std::max<size_t>(1, from.points.size() / 500000);
  for (size_t i = 0; i < from.points.size(); i += stride) samples.push_back(from.points[i]);
  std::mt19937_64 rng(12345);
  std::uniform_real_distribution<double> uni(0.0, 1.0);
  for (const Tri& t : from.triangles) {
    const Vec3 &a = from.points[t[0]], &b = from.points[t[1]], &c = from.points[t[2]];
    double area = 0.5 * norm(area_vector(a, b, c));
    double expected = area / (spacing * spacing);
    size_t k = size_t(expected);
    if (uni(rng) < expected - double(k)) ++k;
    for (size_t i = 0; i < k; ++i) {
      double u = uni(rng), v = uni(rng);
      if (u + v > 1) u = 1 - u, v = 1 - v;
      samples.push_back(a + (b - a) * u + (c - a) * v);
    }
  }
  if (skip) samples.erase(std::remove_if(samples.begin(), samples.end(), skip), samples.end());
  return check::distances_to(samples, to, s.diagonal);
}

namespace check {

DistanceStats distances_to(const std::vector<Vec3>& samples, const Mesh& to, double diagonal) {
  DistanceStats s;
  s.diagonal = diagonal;
  if (samples.empty() || to.triangles.empty()) return s;
  mesh::SurfaceIndex index(to.points, to.triangles);
  std::vector<double> dist(samples.size());
  tbb::parallel_for(tbb::blocked_range<size_t>(0, samples.size(), 1024), [&](const tbb::blocked_range<size_t>& r) {
    for (size_t i = r.begin(); i != r.end(); ++i) dist[i] = std::sqrt(index.squared_distance(samples[i]));
  });
  s.samples = dist.size();
  double sum = 0;
  for (double d : dist) sum += d;
  s.mean = sum / double(dist.size());
  size_t k95 = std::min(dist.size() - 1, size_t(0.95 * double(dist.size())));
  const size_t farthest = size_t(std::max_element(dist.begin(), dist.end()) - dist.begin());
  s.max = dist[farthest];
  s.max_at = samples[farthest];
  std::nth_element(dist.begin(), dist.begin() + k95, dist.end());
  s.p95 = dist[k95];
  return s;
}

}  // namespace check

}  // namespace vdbwrap
