#include "mesh/small_rims.h"

#include <algorithm>

#include "common/union_find.h"
#include "common/vec.h"

namespace vdbwrap::mesh {

size_t drop_small_rims(const std::vector<Vec3>& points, std::vector<FeatureEdge>& edges, double smallest) {
  if (!(smallest > 0)) return 0;
  // The rims: boundary edges joined at their vertices, each with its box.
  UnionFind rims(points.size());
  for (const FeatureEdge& e : edges)
    if (e.kind == FeatureKind::Boundary) rims.unite(e.a, e.b);
  std::vector<uint32_t> rim_of(points.size(), UINT32_MAX);  // a rim's root -> its box
  std::vector<Box3> box;
  auto rim_box = [&](const FeatureEdge& e) -> Box3& {
    uint32_t& slot = rim_of[rims.find(e.a)];
    if (slot == UINT32_MAX) slot = uint32_t(box.size()), box.emplace_back();
    return box[slot];
  };
  for (const FeatureEdge& e : edges)
    if (e.kind == FeatureKind::Boundary) {
      Box3& b = rim_box(e);
      b.add(points[e.a]), b.add(points[e.b]);
    }
  if (box.empty()) return 0;
  const size_t before = edges.size();
  edges.erase(std::remove_if(edges.begin(), edges.end(),
                             [&](const FeatureEdge& e) {
                               return e.kind == FeatureKind::Boundary && rim_box(e).diagonal() < smallest;
                             }),
              edges.end());
  return before - edges.size();
}

}  // namespace vdbwrap::mesh
