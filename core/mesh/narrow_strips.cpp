#include "mesh/narrow_strips.h"

#include <algorithm>
#include <cmath>

#include "common/cell_lists.h"
#include "common/closest_point.h"
#include "common/edge_key.h"
#include "common/edge_triangles.h"
#include "common/union_find.h"
#include "mesh/orient.h"

namespace vdbwrap::mesh {

NarrowFaces narrow_faces(const std::vector<Vec3>& points, const std::vector<Tri>& triangles,
                         const std::vector<FeatureEdge>& edges, double narrowest,
                         const std::vector<uint32_t>* closed_piece, double narrowest_closed,
                         const std::vector<uint32_t>& also_judged) {
  NarrowFaces narrow;
  narrow.triangles.assign(triangles.size(), 0);
  narrow.between_narrow.assign(edges.size(), 0);
  const bool any_crease =
      std::any_of(edges.begin(), edges.end(), [](const FeatureEdge& e) { return e.kind != FeatureKind::Boundary; });
  if (!(narrowest > 0) || (!any_crease && also_judged.empty())) return narrow;
  const EdgeTriangles around = edge_triangles(triangles);
  // Per edge of `around`, its feature edge (an index into `edges`) or UINT32_MAX.
  std::vector<uint32_t> feature(around.edges(), UINT32_MAX);
  for (uint32_t i = 0; i < edges.size(); ++i) {
    const size_t at = around.find(edge_key(edges[i].a, edges[i].b));
    if (at < around.edges() && around.keys[at] == edge_key(edges[i].a, edges[i].b)) feature[at] = i;
  }
  // The smooth regions: triangles joined across the edges of two triangles that are no feature.
  UnionFind joined(triangles.size());
  for (size_t i = 0; i < around.edges(); ++i)
    if (around.size(i) == 2 && feature[i] == UINT32_MAX) joined.unite(around.begin(i)[0], around.begin(i)[1]);
  std::vector<uint32_t> region(triangles.size());
  for (uint32_t t = 0; t < triangles.size(); ++t) region[t] = joined.find(t);
  // Only regions beside a sharp or a non-manifold edge (and those asked for) are judged; all
  // start narrow until a sample is far from their rim.
  constexpr uint8_t kUnasked = 0, kNarrow = 1, kWide = 2;
  std::vector<uint8_t> state(triangles.size(), kUnasked);  // by region (its root triangle)
  for (size_t i = 0; i < around.edges(); ++i)
    if (feature[i] != UINT32_MAX && edges[feature[i]].kind != FeatureKind::Boundary)
      for (const uint32_t* t = around.begin(i); t != around.begin(i) + around.size(i); ++t) state[region[*t]] = kNarrow;
  for (uint32_t t : also_judged)
    if (t < triangles.size()) state[region[t]] = kNarrow;
  // The rims' edges in a hash grid, each listed at points at most a quarter cell apart along it.
  const double cell = narrowest;
  auto reach_of = [&](uint32_t r) {  // r: a region's root triangle
    const bool closed = closed_piece && closed_piece->size() == triangles.size() && (*closed_piece)[r] != kOpenPiece;
    return (closed ? std::min(narrowest, narrowest_closed) : narrowest) / 2;
  };
  CellLists<uint32_t> rims(cell);
  for (uint32_t i = 0; i < around.edges(); ++i) {
    if (feature[i] == UINT32_MAX) continue;
    const Vec3 &a = points[edges[feature[i]].a], &b = points[edges[feature[i]].b];
    const int steps = 1 + int(std::min(1e6, std::ceil(4 * norm(b - a) / cell)));
    GridKey last{INT64_MAX, 0, 0};
    for (int s = 0; s <= steps; ++s) {
      const GridKey k = rims.cell_of(lerp(a, b, double(s) / steps));
      if (!(k == last)) rims.add(k, i), last = k;
    }
  }
  auto rim_of = [&](uint32_t edge, uint32_t r) {
    for (const uint32_t* t = around.begin(edge); t != around.begin(edge) + around.size(edge); ++t)
      if (region[*t] == r) return true;
    return false;
  };
  // Whether a point of region r lies within `reach` of r's rim.
  auto near_rim = [&](const Vec3& p, uint32_t r) {
    const double reach = reach_of(r);
    const Vec3 margin{reach + cell / 4, reach + cell / 4, reach + cell / 4};
    Box3 box;
    box.add(p - margin), box.add(p + margin);
    return rims.for_lists(box, [&](const std::vector<uint32_t>& list) {
      for (uint32_t e : list) {
        if (!rim_of(e, r)) continue;
        double t;
        const FeatureEdge& f = edges[feature[e]];
        if (norm2(closest_on_segment(points[f.a], points[f.b], p, t) - p) <= reach * reach) return true;
      }
      return false;
    });
  };
  for (uint32_t t = 0; t < triangles.size(); ++t) {
    const uint32_t r = region[t];
    if (state[r] != kNarrow) continue;
    const Tri& tri = triangles[t];
    bool wide = !near_rim((points[tri[0]] + points[tri[1]] + points[tri[2]]) * (1.0 / 3), r);
    for (int e = 0; e < 3 && !wide; ++e) {
      const size_t at = around.find(edge_key(tri[e], tri[(e + 1) % 3]));
      if (feature[at] == UINT32_MAX) wide = !near_rim(lerp(points[tri[e]], points[tri[(e + 1) % 3]], 0.5), r);
    }
    if (wide) state[r] = kWide;
  }
  for (uint32_t t = 0; t < triangles.size(); ++t) narrow.triangles[t] = state[region[t]] == kNarrow;
  for (size_t i = 0; i < around.edges(); ++i)
    if (feature[i] != UINT32_MAX && edges[feature[i]].kind != FeatureKind::Boundary)
      narrow.between_narrow[feature[i]] = std::all_of(around.begin(i), around.begin(i) + around.size(i),
                                                      [&](uint32_t t) { return narrow.triangles[t] != 0; });
  return narrow;
}

size_t drop_narrow_strip_edges(std::vector<FeatureEdge>& edges, const NarrowFaces& narrow) {
  if (narrow.between_narrow.size() != edges.size()) return 0;
  size_t kept = 0;
  for (size_t i = 0; i < edges.size(); ++i)
    if (!narrow.between_narrow[i]) edges[kept++] = edges[i];
  const size_t dropped = edges.size() - kept;
  edges.resize(kept);
  return dropped;
}

}  // namespace vdbwrap::mesh
