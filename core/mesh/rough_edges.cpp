#include "mesh/rough_edges.h"

#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>

#include "common/compressed_lists.h"
#include "common/edge_key.h"
#include "common/vec.h"

namespace vdbwrap::mesh {

namespace {
constexpr double kCoherent = 0.7;    // a side's |sum of area normals| over its area, to count as smooth
constexpr size_t kFewestFaces = 12;  // faces within the radius to see the surface over a cell at all
constexpr size_t kMostFaces = 256;   // faces a patch grows to: its normal has settled long before
constexpr double kRough = 0.5;       // share of a patch's faces with a sharp edge at every corner
constexpr double kFolded = 0.1;      // share of a patch's faces with every edge sharp, cut up by noise
}  // namespace

Roughness roughness(size_t points, const std::vector<Tri>& triangles, const std::vector<FeatureEdge>& edges) {
  Roughness out;
  out.on_sharp.assign(points, 0);
  std::vector<uint64_t> sharp;
  for (const FeatureEdge& e : edges)
    if (e.kind == FeatureKind::Sharp) {
      out.on_sharp[e.a] = out.on_sharp[e.b] = 1;
      sharp.push_back(edge_key(e.a, e.b));
    }
  std::sort(sharp.begin(), sharp.end());
  out.sharp_all_round.assign(triangles.size(), 0);
  if (sharp.empty()) return out;
  tbb::parallel_for(tbb::blocked_range<size_t>(0, triangles.size(), 4096), [&](const tbb::blocked_range<size_t>& r) {
    for (size_t t = r.begin(); t != r.end(); ++t) {
      const Tri& f = triangles[t];
      bool all = true;
      for (int k = 0; k < 3 && all; ++k)
        all = std::binary_search(sharp.begin(), sharp.end(), edge_key(f[k], f[(k + 1) % 3]));
      out.sharp_all_round[t] = all;
    }
  });
  return out;
}

bool cut_up_by_noise(const std::vector<uint8_t>& sharp_all_round, const std::vector<uint32_t>& faces) {
  if (faces.size() < kFewestFaces) return false;
  size_t folded = 0;
  for (uint32_t t : faces) folded += sharp_all_round[t];
  return double(folded) >= kFolded * double(faces.size());
}

size_t drop_edges_smooth_at_scale(const std::vector<Vec3>& points, const std::vector<Tri>& triangles,
                                  std::vector<FeatureEdge>& edges, const Roughness& roughness, double radius,
                                  double feature_angle_deg) {
  if (!(radius > 0)) return 0;
  size_t sharp = 0;
  for (const FeatureEdge& e : edges) sharp += e.kind == FeatureKind::Sharp;
  if (sharp == 0) return 0;
  const CompressedLists faces_at = compressed_lists(points.size(), [&](auto&& emit) {
    for (uint32_t t = 0; t < triangles.size(); ++t)
      for (uint32_t v : triangles[t]) emit(v, t);
  });
  auto centre = [&](uint32_t t) {
    const Tri& f = triangles[t];
    return (points[f[0]] + points[f[1]] + points[f[2]]) * (1.0 / 3.0);
  };
  auto area_normal = [&](uint32_t t) {
    const Tri& f = triangles[t];
    return area_vector(points[f[0]], points[f[1]], points[f[2]]);
  };
  const double cos_limit = std::cos(feature_angle_deg * M_PI / 180.0);
  const double r2 = radius * radius;
  std::vector<uint8_t> drop(edges.size(), 0);
  // Per thread, the edge (plus one) whose patch last met each face.
  tbb::enumerable_thread_specific<std::vector<uint32_t>> marks(
      [&] { return std::vector<uint32_t>(triangles.size(), 0); });
  tbb::parallel_for(tbb::blocked_range<size_t>(0, edges.size(), 256), [&](const tbb::blocked_range<size_t>& r) {
    std::vector<uint32_t>& mark = marks.local();
    std::vector<uint32_t> queue, faces;
    for (size_t i = r.begin(); i != r.end(); ++i) {
      const FeatureEdge& e = edges[i];
      if (e.kind != FeatureKind::Sharp) continue;
      faces.clear();
      for (uint32_t t : faces_at[e.a])
        for (uint32_t v : triangles[t])
          if (v == e.b) faces.push_back(t);
      if (faces.size() != 2) continue;
      const Vec3 mid = (points[e.a] + points[e.b]) * 0.5;
      const Vec3 n0 = normalized(area_normal(faces[0])), n1 = normalized(area_normal(faces[1]));
      const Vec3 halving = cross(points[e.b] - points[e.a], n0 + n1);
      const double s0 = dot(halving, centre(faces[0]) - mid);
      if (!(s0 != 0)) continue;
      Vec3 side[2] = {area_normal(faces[0]), area_normal(faces[1])};
      double area[2] = {norm(side[0]), norm(side[1])};
      size_t rough = 0;
      auto all_sharp = [&](uint32_t t) {
        const Tri& f = triangles[t];
        return roughness.on_sharp[f[0]] && roughness.on_sharp[f[1]] && roughness.on_sharp[f[2]];
      };
      rough += all_sharp(faces[0]) + all_sharp(faces[1]);
      const uint32_t stamp = uint32_t(i + 1);
      mark[faces[0]] = mark[faces[1]] = stamp;
      queue.assign(faces.begin(), faces.end());
      for (size_t q = 0; q < queue.size() && queue.size() < kMostFaces; ++q)
        for (uint32_t v : triangles[queue[q]])
          for (uint32_t t : faces_at[v]) {
            if (mark[t] == stamp) continue;
            mark[t] = stamp;
            const Vec3 c = centre(t);
            if (norm2(c - mid) > r2) continue;
            queue.push_back(t);
            const int k = dot(halving, c - mid) * s0 > 0 ? 0 : 1;
            const Vec3 a = area_normal(t);
            side[k] = side[k] + a, area[k] += norm(a);
            rough += all_sharp(t);
          }
      if (queue.size() < kFewestFaces) continue;  // faces as big as the radius: a CAD crease
      if (double(rough) < kRough * double(queue.size())) continue;
      const double l0 = norm(side[0]), l1 = norm(side[1]);
      const bool smooth_sides = l0 >= kCoherent * area[0] && l1 >= kCoherent * area[1];
      // Cut up by noise, the sides' normals scatter; a knurl's facets, sharp all round where
      // its creases cross a fine grid, keep both sides smooth.
      if (!smooth_sides && cut_up_by_noise(roughness.sharp_all_round, queue)) {
        drop[i] = 1;
        continue;
      }
      // Amid sides smooth but for the noise, an edge longer than the radius is a line the wrap
      // can follow.
      if (norm2(points[e.b] - points[e.a]) > r2 || !smooth_sides) continue;
      if (dot(side[0], side[1]) >= cos_limit * l0 * l1) drop[i] = 1;
    }
  });
  size_t kept = 0, dropped = 0;
  for (size_t i = 0; i < edges.size(); ++i) {
    if (drop[i]) {
      ++dropped;
      continue;
    }
    edges[kept++] = edges[i];
  }
  edges.resize(kept);
  return dropped;
}

}  // namespace vdbwrap::mesh
