// Needle untangling (see untangle.h): planned and measured without touching the mesh.
#include "repair/untangle.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <unordered_map>

#include "common/vec.h"

namespace vdbwrap::local_repair {
namespace {

// The distinct neighbours of `v` over its live triangles.
std::vector<uint32_t> neighbours(const std::vector<Tri>& triangles, const VertexFaces& faces, uint32_t v) {
  std::vector<uint32_t> out;
  for (const uint32_t* f = faces.begin(v); f != faces.end(v); ++f)
    for (uint32_t u : triangles[*f])
      if (u != v) out.push_back(u);
  std::sort(out.begin(), out.end());
  out.erase(std::unique(out.begin(), out.end()), out.end());
  return out;
}

Vec3 weighted_average(const std::vector<Vec3>& points, const std::vector<uint32_t>& around, const Vec3& at) {
  if (around.empty()) return at;
  // The scale of the offset: the second shortest edge (a fold may have made the shortest one
  // nearly zero; the long edges of a needle say nothing of its width).
  std::vector<double> length2;
  for (uint32_t u : around) length2.push_back(norm2(points[u] - at));
  std::sort(length2.begin(), length2.end());
  const double scale2 = length2[std::min<size_t>(1, length2.size() - 1)];
  const double offset2 = 0.25 * scale2;
  Vec3 sum{0, 0, 0};
  double total = 0;
  for (uint32_t u : around) {
    const double w = 1.0 / (norm2(points[u] - at) + offset2);
    sum = sum + points[u] * w;
    total += w;
  }
  if (!(total > 0) || !std::isfinite(total)) return at;
  // No farther than that scale: a fold is undone by sliding across a needle or two; a longer
  // way is a change of shape, not an untangling.
  const Vec3 d = sum * (1.0 / total) - at;
  const double len2 = norm2(d);
  return len2 > scale2 ? at + d * std::sqrt(scale2 / len2) : at + d;
}

}  // namespace

Vec3 untangled_position(const std::vector<Vec3>& points, const std::vector<Tri>& triangles, const VertexFaces& faces,
                        uint32_t v) {
  return weighted_average(points, neighbours(triangles, faces, v), points[v]);
}

std::vector<Move> plan_untangling(const std::vector<Vec3>& points, const std::vector<Tri>& triangles,
                                  const VertexFaces& faces, const std::vector<uint32_t>& region,
                                  const std::vector<Crossing>& crossings, size_t singles, int sweeps) {
  const std::vector<uint32_t> region_vertices = vertices_of(triangles, region);
  auto in_region = [&](uint32_t v) { return std::binary_search(region_vertices.begin(), region_vertices.end(), v); };
  std::map<uint32_t, int> cutting;  // vertex -> cutting edges on it (ordered: same plan every run)
  for (const Crossing& c : crossings)
    for (uint32_t v : {c.u, c.v})
      if (in_region(v)) ++cutting[v];
  std::vector<std::pair<int, uint32_t>> ranked;  // (-count, vertex)
  for (const auto& [v, count] : cutting) ranked.push_back({-count, v});
  std::sort(ranked.begin(), ranked.end());
  std::vector<Move> moves;
  for (size_t i = 0; i < ranked.size() && i < singles; ++i) {
    const uint32_t v = ranked[i].second;
    Move m;
    m.kind = Move::Kind::Untangle;
    m.primary = false;
    m.positions.push_back({v, untangled_position(points, triangles, faces, v)});
    moves.push_back(std::move(m));
  }
  // All at once (Jacobi: each round from the last round's positions).
  std::unordered_map<uint32_t, std::vector<uint32_t>> around;
  for (uint32_t v : region_vertices) around[v] = neighbours(triangles, faces, v);
  std::vector<Vec3> at = points;
  for (int sweep = 1; sweep <= sweeps; ++sweep) {
    std::vector<Vec3> next = at;
    for (uint32_t v : region_vertices) next[v] = weighted_average(at, around[v], at[v]);
    at = std::move(next);
    if (sweep != 1 && sweep != sweeps) continue;
    Move m;
    m.kind = Move::Kind::Untangle;
    m.primary = false;
    for (uint32_t v : region_vertices) m.positions.push_back({v, at[v]});
    moves.push_back(std::move(m));
  }
  return moves;
}

}  // namespace vdbwrap::local_repair
