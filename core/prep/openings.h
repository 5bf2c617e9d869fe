// The input's openings: its boundary edges joined into loops (holes of a scan, the rim of an
// open sheet), each with a centre and a width. The outside volume gets in through an opening
// wider than the cells; a gap closure above its width keeps it out.
#pragma once
#include <algorithm>
#include <cmath>
#include <vector>

#include "common/union_find.h"
#include "common/vec.h"
#include "prep/prepare.h"

namespace vdbwrap::prep {

struct Opening {
  Vec3 centre{0, 0, 0};  // the middle of the widest ball through it, in the loop's mean plane
  double width = 0;      // twice the distance from the centre to the nearest loop edge
  size_t edges = 0;
};

// Loops that touch (at a non-manifold vertex) count as one opening.
inline std::vector<Opening> find_openings(const PreparedInput& in) {
  std::vector<std::pair<uint32_t, uint32_t>> edges;
  for (const FeatureEdge& f : in.feature_edges)
    if (f.kind == FeatureKind::Boundary) edges.push_back({f.a, f.b});
  UnionFind rims(in.mesh.points.size());
  for (const auto& [a, b] : edges) rims.unite(a, b);
  std::vector<uint32_t> root_of(edges.size()), roots;
  for (size_t e = 0; e < edges.size(); ++e) roots.push_back(root_of[e] = rims.find(edges[e].first));
  std::sort(roots.begin(), roots.end());
  roots.erase(std::unique(roots.begin(), roots.end()), roots.end());
  std::vector<Opening> out(roots.size());
  std::vector<double> length(roots.size(), 0);
  auto slot = [&](size_t e) {
    return size_t(std::lower_bound(roots.begin(), roots.end(), root_of[e]) - roots.begin());
  };
  const auto& p = in.mesh.points;
  for (size_t e = 0; e < edges.size(); ++e) {
    const size_t k = slot(e);
    const Vec3 &a = p[edges[e].first], &b = p[edges[e].second];
    const double l = norm(b - a);
    out[k].centre = out[k].centre + (a + b) * (0.5 * l);
    length[k] += l;
    ++out[k].edges;
  }
  std::vector<std::vector<uint32_t>> loop_edges(out.size());
  for (size_t e = 0; e < edges.size(); ++e) loop_edges[slot(e)].push_back(uint32_t(e));
  for (size_t k = 0; k < out.size(); ++k) {
    Opening& o = out[k];
    if (length[k] > 0) o.centre = o.centre * (1.0 / length[k]);
    // The nearest loop edge's point to x, and its distance.
    auto clearance = [&](const Vec3& x, Vec3& nearest) {
      double best = INFINITY;
      for (uint32_t e : loop_edges[k]) {
        const Vec3 &a = p[edges[e].first], &b = p[edges[e].second], ab = b - a;
        const double l2 = dot(ab, ab);
        const Vec3 q = a + ab * (l2 > 0 ? std::clamp(dot(x - a, ab) / l2, 0.0, 1.0) : 0.0);
        const double d = norm(x - q);
        if (d < best) best = d, nearest = q;
      }
      return best;
    };
    // The widest ball through the opening: from the mean point, climb away from the nearest
    // edge within the loop's mean plane (a jagged rim puts the mean point off the middle).
    Vec3 plane{0, 0, 0};
    for (uint32_t e : loop_edges[k]) {  // edges come in no order along the loop: each turned to agree
      const Vec3 t = cross(p[edges[e].first] - o.centre, p[edges[e].second] - o.centre);
      plane = dot(t, plane) < 0 ? plane - t : plane + t;
    }
    const double pn = norm(plane);
    if (pn > 0) plane = plane * (1.0 / pn);
    Vec3 x = o.centre, near{0, 0, 0};
    double best = clearance(x, near), step = 0.25 * best;
    for (int it = 0; it < 200 && step > 1e-3 * best; ++it) {
      Vec3 d = x - near;
      d = d - plane * dot(d, plane);
      const double dn = norm(d);
      if (!(dn > 0)) break;
      const Vec3 y = x + d * (step / dn);
      Vec3 near_y{0, 0, 0};
      const double c = clearance(y, near_y);
      if (c > best) {
        x = y, best = c, near = near_y;
      } else {
        step *= 0.5;
      }
    }
    o.centre = x;
    o.width = 2 * best;
  }
  return out;
}

}  // namespace vdbwrap::prep
