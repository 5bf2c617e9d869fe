// The input's openings: its boundary edges joined into loops (holes of a scan, the rim of an
// open sheet), each with a centre and a width. The outside volume gets in through an opening
// wider than the cells; a gap closure above its width keeps it out.
#pragma once
#include <algorithm>
#include <cmath>
#include <numeric>
#include <vector>

#include "common/vec.h"
#include "prep/prepare.h"

namespace vdbwrap::prep {

struct Opening {
  Vec3 centre{0, 0, 0};  // the loop's length-weighted mean point
  double width = 0;      // twice the distance from the centre to the nearest loop edge
  size_t edges = 0;
};

// Loops that touch (at a non-manifold vertex) count as one opening.
inline std::vector<Opening> find_openings(const PreparedInput& in) {
  std::vector<std::pair<uint32_t, uint32_t>> edges;
  for (const FeatureEdge& f : in.feature_edges)
    if (f.kind == FeatureKind::Boundary) edges.push_back({f.a, f.b});
  std::vector<uint32_t> parent(in.mesh.points.size());
  std::iota(parent.begin(), parent.end(), 0u);
  auto find = [&](uint32_t v) {
    while (parent[v] != v) v = parent[v] = parent[parent[v]];
    return v;
  };
  for (const auto& [a, b] : edges) parent[find(a)] = find(b);
  std::vector<uint32_t> root_of(edges.size()), roots;
  for (size_t e = 0; e < edges.size(); ++e) roots.push_back(root_of[e] = find(edges[e].first));
  std::sort(roots.begin(), roots.end());
  roots.erase(std::unique(roots.begin(), roots.end()), roots.end());
  std::vector<Opening> out(roots.size());
  std::vector<double> length(roots.size(), 0);
  auto slot = [&](size_t e) { return size_t(std::lower_bound(roots.begin(), roots.end(), root_of[e]) - roots.begin()); };
  const auto& p = in.mesh.points;
  for (size_t e = 0; e < edges.size(); ++e) {
    const size_t k = slot(e);
    const Vec3 &a = p[edges[e].first], &b = p[edges[e].second];
    const double l = norm(b - a);
    out[k].centre = out[k].centre + (a + b) * (0.5 * l);
    length[k] += l;
    ++out[k].edges;
  }
  for (size_t k = 0; k < out.size(); ++k) {
    if (length[k] > 0) out[k].centre = out[k].centre * (1.0 / length[k]);
    out[k].width = INFINITY;
  }
  for (size_t e = 0; e < edges.size(); ++e) {
    Opening& o = out[slot(e)];
    const Vec3 &a = p[edges[e].first], &b = p[edges[e].second], ab = b - a;
    const double l2 = dot(ab, ab);
    const double s = l2 > 0 ? std::clamp(dot(o.centre - a, ab) / l2, 0.0, 1.0) : 0.0;
    o.width = std::min(o.width, 2 * norm(o.centre - (a + ab * s)));
  }
  return out;
}

}  // namespace vdbwrap::prep
