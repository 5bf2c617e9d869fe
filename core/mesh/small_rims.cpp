#include "mesh/small_rims.h"

#include <algorithm>
#include <unordered_map>

#include "common/vec.h"

namespace vdbwrap::mesh {

size_t drop_small_rims(const std::vector<Vec3>& points, std::vector<FeatureEdge>& edges, double smallest) {
  if (!(smallest > 0)) return 0;
  // Union-find over the rims' vertices, numbered densely.
  std::unordered_map<uint32_t, uint32_t> dense;
  auto number = [&](uint32_t v) { return dense.emplace(v, uint32_t(dense.size())).first->second; };
  std::vector<uint32_t> parent;
  auto find = [&](uint32_t x) {
    while (parent[x] != x) x = parent[x] = parent[parent[x]];
    return x;
  };
  for (const FeatureEdge& e : edges) {
    if (e.kind != FeatureKind::Boundary) continue;
    const uint32_t a = number(e.a), b = number(e.b);
    while (parent.size() < dense.size()) parent.push_back(uint32_t(parent.size()));
    parent[find(a)] = find(b);
  }
  if (parent.empty()) return 0;
  std::vector<Box3> box(parent.size());
  for (const auto& [v, i] : dense) box[find(i)].add(points[v]);
  const size_t before = edges.size();
  edges.erase(std::remove_if(edges.begin(), edges.end(),
                             [&](const FeatureEdge& e) {
                               return e.kind == FeatureKind::Boundary && box[find(dense.at(e.a))].diagonal() < smallest;
                             }),
              edges.end());
  return before - edges.size();
}

}  // namespace vdbwrap::mesh
