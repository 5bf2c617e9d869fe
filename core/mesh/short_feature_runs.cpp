#include "mesh/short_feature_runs.h"

#include <algorithm>
#include <cmath>
#include <cstdint>

#include "common/vec.h"

namespace vdbwrap::mesh {

size_t drop_short_sharp_runs(const std::vector<Vec3>& points, std::vector<FeatureEdge>& edges, double shortest,
                             double corner_angle_deg) {
  if (!(shortest > 0)) return 0;
  const double cos_corner = std::cos(corner_angle_deg * M_PI / 180.0);
  // The sharp edges around each vertex, as (vertex, edge index) pairs sorted by vertex.
  std::vector<std::pair<uint32_t, uint32_t>> at;
  for (uint32_t i = 0; i < edges.size(); ++i)
    if (edges[i].kind == FeatureKind::Sharp) at.push_back({edges[i].a, i}), at.push_back({edges[i].b, i});
  if (at.empty()) return 0;
  std::sort(at.begin(), at.end());
  auto around = [&](uint32_t v) {
    auto lo = std::lower_bound(at.begin(), at.end(), std::pair<uint32_t, uint32_t>{v, 0});
    auto hi = std::lower_bound(lo, at.end(), std::pair<uint32_t, uint32_t>{v + 1, 0});
    return std::make_pair(lo, hi);
  };
  auto degree = [&](uint32_t v) {
    const auto [lo, hi] = around(v);
    return size_t(hi - lo);
  };
  std::vector<uint8_t> seen(edges.size(), 0), drop(edges.size(), 0);
  std::vector<uint32_t> run;
  for (uint32_t first = 0; first < edges.size(); ++first) {
    if (edges[first].kind != FeatureKind::Sharp || seen[first]) continue;
    // Walk both ways from the edge through vertices on exactly two sharp edges.
    run.assign(1, first);
    seen[first] = 1;
    double length = norm(points[edges[first].b] - points[edges[first].a]);
    for (uint32_t from : {edges[first].a, edges[first].b}) {
      uint32_t v = from, e = first;
      while (degree(v) == 2) {
        const auto [lo, hi] = around(v);
        const uint32_t next = lo->second == e ? (lo + 1)->second : lo->second;
        if (seen[next]) break;  // a closed loop, walked round
        // A turn sharper than the corner angle ends the run, as it ends a feature curve.
        const uint32_t back = edges[e].a == v ? edges[e].b : edges[e].a;
        const uint32_t ahead = edges[next].a == v ? edges[next].b : edges[next].a;
        if (dot(normalized(points[back] - points[v]), normalized(points[ahead] - points[v])) > -cos_corner) break;
        seen[next] = 1;
        run.push_back(next);
        length += norm(points[edges[next].b] - points[edges[next].a]);
        v = edges[next].a == v ? edges[next].b : edges[next].a;
        e = next;
      }
    }
    if (length < shortest)
      for (uint32_t e : run) drop[e] = 1;
  }
  size_t dropped = 0, kept = 0;
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
