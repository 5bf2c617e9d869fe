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

namespace {

// Points spread by area over `from` for the mean and p95: a hundred thousand at most (the
// sampling error of a mean over so many is far below what the figures show); the max is
// sought again near the farthest of them (refine_max).
constexpr double kMostAreaSamples = 1e5;
constexpr double kLeastAreaSamples = 2e4;  // on small or slender surfaces, whatever the spacing

std::vector<double> distances_of(const std::vector<Vec3>& samples, const check::IndexedSurface& to) {
  std::vector<double> dist(samples.size());
  // Small grains: a query far from the surface opens hundreds of index boxes, and the search
  // for the max asks a few hundred at a time.
  tbb::parallel_for(tbb::blocked_range<size_t>(0, samples.size(), 64), [&](const tbb::blocked_range<size_t>& r) {
    for (size_t i = r.begin(); i != r.end(); ++i)
      dist[i] = std::sqrt(to.index.squared_distance(samples[i] - to.origin));
  });
  return dist;
}

DistanceStats stats_of(std::vector<double> dist, const std::vector<Vec3>& samples, double diagonal) {
  DistanceStats s;
  s.diagonal = diagonal;
  if (dist.empty()) return s;
  s.samples = dist.size();
  double sum = 0;
  for (double d : dist) sum += d;
  s.mean = sum / double(dist.size());
  const size_t farthest = size_t(std::max_element(dist.begin(), dist.end()) - dist.begin());
  s.max = dist[farthest];
  s.max_at = samples[farthest];
  const size_t k95 = std::min(dist.size() - 1, size_t(0.95 * double(dist.size())));
  std::nth_element(dist.begin(), dist.begin() + k95, dist.end());
  s.p95 = dist[k95];
  return s;
}

// The farthest point of a surface lies between the samples, a spacing's share of a slope
// beyond the farthest of them: the triangles nearest to it by their farthest sample or vertex
// are sampled again on a fine barycentric lattice, for the max alone (the mean and p95 stay
// those of the even sampling).
//
// Distance to a surface changes no faster than the point moves, so a triangle can hold no
// point farther than any of its samples' distance plus that sample's reach to the triangle's
// farthest corner. Triangles whose bound is below the max found so far are not sampled: far
// from the surface measured against (a part deep inside a round wrap) each query opens
// hundreds of index boxes, and the lattice would spend them where nothing can be gained.
void refine_max(DistanceStats& s, const Mesh& from, const std::vector<Vec3>& samples,
                const std::vector<uint32_t>& on_triangle, const std::vector<uint32_t>& at_vertex,
                const std::vector<double>& dist, const check::IndexedSurface& index,
                const std::function<bool(const Vec3&)>& skip) {
  constexpr size_t kTriangles = 256;
  constexpr size_t kBatch = 32;  // triangles sampled between two updates of the bound
  constexpr int kSteps = 12;     // 91 points per triangle
  constexpr double kUnknown = -1;
  std::vector<double> vertex_distance(from.points.size(), kUnknown);
  std::vector<double> score(from.triangles.size(), 0);
  std::vector<double> bound(from.triangles.size(), INFINITY);
  auto reach = [&](uint32_t t, const Vec3& p) {  // to the triangle's farthest corner
    double r2 = 0;
    for (uint32_t v : from.triangles[t]) r2 = std::max(r2, norm2(from.points[v] - p));
    return std::sqrt(r2);
  };
  for (size_t i = 0; i < dist.size(); ++i)
    if (on_triangle[i] != UINT32_MAX) {
      const uint32_t t = on_triangle[i];
      score[t] = std::max(score[t], dist[i]);
      bound[t] = std::min(bound[t], dist[i] + reach(t, samples[i]));
    } else {
      vertex_distance[at_vertex[i]] = dist[i];
    }
  std::vector<std::pair<double, uint32_t>> far(from.triangles.size());
  for (uint32_t t = 0; t < from.triangles.size(); ++t) {
    for (uint32_t v : from.triangles[t]) {
      const double d = vertex_distance[v];
      if (d == kUnknown) continue;
      score[t] = std::max(score[t], d);
      bound[t] = std::min(bound[t], d + reach(t, from.points[v]));
    }
    far[t] = {score[t], t};
  }
  const size_t k = std::min(kTriangles, far.size());
  std::partial_sort(far.begin(), far.begin() + k, far.end(), std::greater<>());
  // A point of triangle t at barycentric (u, v) from its first corner.
  struct Spot {
    uint32_t t;
    double u, v, d;
  };
  auto at = [&](uint32_t t, double u, double v) {
    const Tri& tri = from.triangles[t];
    const Vec3& a = from.points[tri[0]];
    return a + (from.points[tri[1]] - a) * u + (from.points[tri[2]] - a) * v;
  };
  // A bound within rounding of the max is no reason to look (it cannot raise the figure).
  const double margin = 1e-9 * s.diagonal;
  double best = s.max;
  std::vector<Spot> spots;
  std::vector<Vec3> points;
  for (size_t first = 0; first < k; first += kBatch) {
    const size_t batch_start = spots.size();
    points.clear();
    for (size_t f = first; f < std::min(k, first + kBatch); ++f) {
      const uint32_t t = far[f].second;
      if (bound[t] < best - margin) continue;
      for (int i = 0; i <= kSteps; ++i)
        for (int j = 0; i + j <= kSteps; ++j) {
          const Spot spot{t, double(i) / kSteps, double(j) / kSteps, 0};
          const Vec3 p = at(spot.t, spot.u, spot.v);
          if (!skip || !skip(p)) spots.push_back(spot), points.push_back(p);
        }
    }
    const std::vector<double> d = distances_of(points, index);
    for (size_t i = 0; i < d.size(); ++i) spots[batch_start + i].d = d[i], best = std::max(best, d[i]);
  }
  // Then uphill from the farthest lattice points: each tries six steps across its triangle,
  // moves to the farthest that is farther, and halves the step where none is.
  constexpr size_t kClimbers = 32;
  constexpr int kRounds = 12;
  const size_t m = std::min(kClimbers, spots.size());
  std::partial_sort(spots.begin(), spots.begin() + m, spots.end(),
                    [](const Spot& x, const Spot& y) { return x.d > y.d; });
  spots.resize(m);
  std::vector<double> step(m, 1.0 / kSteps);
  // A climber moves at most a step across its triangle a round: one that could not pass the
  // farthest point found in the rounds left stops.
  std::vector<double> longest_edge(m, 0);
  for (size_t c = 0; c < m; ++c)
    for (int e = 0; e < 3; ++e) {
      const Tri& tri = from.triangles[spots[c].t];
      longest_edge[c] = std::max(longest_edge[c], norm(from.points[tri[e]] - from.points[tri[(e + 1) % 3]]));
    }
  static constexpr double kDirections[6][2] = {{1, 0}, {-1, 0}, {0, 1}, {0, -1}, {1, -1}, {-1, 1}};
  for (int round = 0; round < kRounds; ++round) {
    for (size_t c = 0; c < m; ++c) best = std::max(best, spots[c].d);
    std::vector<Spot> tries;
    points.clear();
    for (size_t c = 0; c < m; ++c)
      if (spots[c].d + (kRounds - round) * step[c] * longest_edge[c] >= best - margin)
        for (const auto& dir : kDirections) {
          const double u = spots[c].u + step[c] * dir[0], v = spots[c].v + step[c] * dir[1];
          if (u < 0 || v < 0 || u + v > 1) continue;
          const Vec3 p = at(spots[c].t, u, v);
          if (skip && skip(p)) continue;
          tries.push_back({uint32_t(c), u, v, 0}), points.push_back(p);  // t: the climber here
        }
    const std::vector<double> d = distances_of(points, index);
    std::vector<uint8_t> moved(m, 0);
    for (size_t i = 0; i < tries.size(); ++i) {
      Spot& c = spots[tries[i].t];
      if (d[i] > c.d) c.u = tries[i].u, c.v = tries[i].v, c.d = d[i], moved[tries[i].t] = 1;
    }
    for (size_t c = 0; c < m; ++c)
      if (!moved[c]) step[c] /= 2;
  }
  for (const Spot& c : spots)
    if (c.d > s.max) s.max = c.d, s.max_at = at(c.t, c.u, c.v);
}

}  // namespace

DistanceStats check::sampled_distance_skipping(const Mesh& from, const Mesh& to, double samples_per_diagonal,
                                               const std::function<bool(const Vec3&)>& skip) {
  Box3 box;
  for (const auto& p : to.points) box.add(p);
  if (from.triangles.empty() || to.triangles.empty()) {
    DistanceStats s;
    s.diagonal = box.diagonal();
    return s;
  }
  const mesh::SurfaceIndex index(to.points, to.triangles);
  return sampled_distance_to(from, IndexedSurface{index, {0, 0, 0}, box.diagonal()}, samples_per_diagonal, skip);
}

DistanceStats check::sampled_distance_to(const Mesh& from, const IndexedSurface& to, double samples_per_diagonal,
                                         const std::function<bool(const Vec3&)>& skip) {
  DistanceStats s;
  s.diagonal = to.diagonal;
  if (from.triangles.empty()) return s;
  // Samples: the vertices (every one up to half a million, evenly strided beyond), plus
  // points spread by area (a stratified count per triangle).
  double area = 0;
  for (const Tri& t : from.triangles)
    area += 0.5 * norm(area_vector(from.points[t[0]], from.points[t[1]], from.points[t[2]]));
  const double wanted = area * samples_per_diagonal * samples_per_diagonal / (s.diagonal * s.diagonal);
  const double spacing = std::sqrt(area / std::clamp(wanted, kLeastAreaSamples, kMostAreaSamples));
  std::vector<Vec3> samples;
  std::vector<uint32_t> on_triangle;                 // the triangle of an area sample; UINT32_MAX for a vertex
  std::vector<uint32_t> at_vertex;                   // the vertex of a vertex sample
  std::vector<uint8_t> used(from.points.size(), 0);  // a stray point of the file is no surface
  for (const Tri& t : from.triangles) used[t[0]] = used[t[1]] = used[t[2]] = 1;
  const size_t stride = std::max<size_t>(1, from.points.size() / 500000);
  for (size_t i = 0; i < from.points.size(); i += stride)
    if (used[i]) samples.push_back(from.points[i]), at_vertex.push_back(uint32_t(i));
  on_triangle.assign(samples.size(), UINT32_MAX);
  std::mt19937_64 rng(12345);
  std::uniform_real_distribution<double> uni(0.0, 1.0);
  for (uint32_t t = 0; t < from.triangles.size(); ++t) {
    const Vec3 &a = from.points[from.triangles[t][0]], &b = from.points[from.triangles[t][1]],
               &c = from.points[from.triangles[t][2]];
    double area = 0.5 * norm(area_vector(a, b, c));
    // (No area samples on a surface of no area: the vertices alone.)
    const double expected = spacing > 0 ? area / (spacing * spacing) : 0;
    size_t k = size_t(expected);
    if (uni(rng) < expected - double(k)) ++k;
    for (size_t i = 0; i < k; ++i) {
      double u = uni(rng), v = uni(rng);
      if (u + v > 1) u = 1 - u, v = 1 - v;
      samples.push_back(a + (b - a) * u + (c - a) * v);
      on_triangle.push_back(t), at_vertex.push_back(UINT32_MAX);
    }
  }
  if (skip) {
    size_t kept = 0;
    for (size_t i = 0; i < samples.size(); ++i)
      if (!skip(samples[i]))
        samples[kept] = samples[i], on_triangle[kept] = on_triangle[i], at_vertex[kept] = at_vertex[i], ++kept;
    samples.resize(kept), on_triangle.resize(kept), at_vertex.resize(kept);
  }
  if (samples.empty()) return s;
  const std::vector<double> dist = distances_of(samples, to);
  // The mean and p95 of the area samples (the vertices, as many as half a million, would weigh
  // a dense patch of the mesh over the rest); the max of all.
  std::vector<double> spread;
  std::vector<Vec3> spread_at;
  for (size_t i = 0; i < samples.size(); ++i)
    if (on_triangle[i] != UINT32_MAX) spread.push_back(dist[i]), spread_at.push_back(samples[i]);
  s = spread.empty() ? stats_of(dist, samples, s.diagonal) : stats_of(std::move(spread), spread_at, s.diagonal);
  s.samples = samples.size();
  const size_t farthest = size_t(std::max_element(dist.begin(), dist.end()) - dist.begin());
  if (dist[farthest] > s.max) s.max = dist[farthest], s.max_at = samples[farthest];
  refine_max(s, from, samples, on_triangle, at_vertex, dist, to, skip);
  return s;
}

namespace check {

DistanceStats distances_to(const std::vector<Vec3>& samples, const Mesh& to, double diagonal) {
  DistanceStats s;
  s.diagonal = diagonal;
  if (samples.empty() || to.triangles.empty()) return s;
  const mesh::SurfaceIndex index(to.points, to.triangles);
  return stats_of(distances_of(samples, IndexedSurface{index, {0, 0, 0}, diagonal}), samples, diagonal);
}

}  // namespace check

}  // namespace vdbwrap
