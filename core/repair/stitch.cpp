// Stitching T-junctions along cracks (see stitch.h).
#include "repair/stitch.h"

#include <algorithm>
#include <map>
#include <unordered_map>

#include "common/vec.h"

namespace vdbwrap::local_repair {
namespace {

bool on_border(const std::vector<Tri>& all, const VertexFaces& faces, uint32_t v) {
  for (const uint32_t* f = faces.begin(v); f != faces.end(v); ++f)
    for (uint32_t x : all[*f])
      if (x != v && edge_use(all, faces, v, x) == 1) return true;
  return false;
}

}  // namespace

Stitches find_stitches(const std::vector<Vec3>& points, const std::vector<Tri>& triangles, const VertexFaces& faces,
                       const std::vector<check::TrianglePair>& pairs, double tol,
                       const std::unordered_set<uint32_t>& forbidden) {
  const double tol2 = tol * tol;
  std::map<uint32_t, uint32_t> weld;                                     // vertex -> lower vertex it joins
  std::map<std::pair<uint32_t, uint32_t>, std::vector<uint32_t>> found;  // (u, w) as in the triangle -> vertices
  std::unordered_map<uint32_t, bool> border;
  auto is_border = [&](uint32_t v) {
    auto it = border.find(v);
    return it != border.end() ? it->second : (border[v] = on_border(triangles, faces, v));
  };
  for (const auto& p : pairs) {
    if (p.a == p.b) continue;
    for (int side = 0; side < 2; ++side) {
      const Tri& a = triangles[side ? p.b : p.a];
      const Tri& b = triangles[side ? p.a : p.b];
      if (is_dead(a) || is_dead(b)) continue;
      for (uint32_t v : a) {
        if (forbidden.count(v) || b[0] == v || b[1] == v || b[2] == v || !is_border(v)) continue;
        bool welded = false;
        for (uint32_t u : b)
          if (!forbidden.count(u) && norm2(points[u] - points[v]) <= tol2 && is_border(u)) {
            const uint32_t lo = std::min(u, v), hi = std::max(u, v);
            auto [it, added] = weld.emplace(hi, lo);
            if (!added) it->second = std::min(it->second, lo);
            welded = true;
          }
        if (welded) continue;
        for (int k = 0; k < 3; ++k) {
          const uint32_t u = b[k], w = b[(k + 1) % 3];
          if (edge_use(triangles, faces, u, w) != 1) continue;  // only the border: a crack
          const Vec3 d = points[w] - points[u];
          const double len2 = norm2(d);
          if (!(len2 > 0)) continue;
          const double t = dot(points[v] - points[u], d) / len2;
          if (!(t > 0 && t < 1)) continue;
          if (norm2(points[v] - points[u]) <= tol2 || norm2(points[v] - points[w]) <= tol2) continue;  // a weld's job
          if (norm2(points[u] + d * t - points[v]) > tol2) continue;
          found[{u, w}].push_back(v);
        }
      }
    }
  }
  Stitches out;
  for (auto [hi, lo] : weld) {
    while (weld.count(lo)) lo = weld[lo];  // chains end at the lowest id
    out.welds.push_back({hi, lo});
  }
  if (!out.welds.empty()) return out;  // splits next round, on the welded mesh
  for (auto& [edge, at] : found) {
    const Vec3 from = points[edge.first];
    std::sort(at.begin(), at.end());
    at.erase(std::unique(at.begin(), at.end()), at.end());
    // Along the edge from u.
    std::sort(at.begin(), at.end(),
              [&](uint32_t x, uint32_t y) { return norm2(points[x] - from) < norm2(points[y] - from); });
    // Two vertices within the tolerance of each other would make a needle: they weld first.
    bool close = false;
    for (size_t i = 1; i < at.size(); ++i) close |= norm2(points[at[i]] - points[at[i - 1]]) <= tol2;
    if (close) continue;
    out.splits.push_back({edge.first, edge.second, at});
  }
  return out;
}

std::vector<std::pair<uint32_t, uint32_t>> bad_edges(const std::vector<Tri>& all,
                                                     const std::vector<uint32_t>& triangles, const VertexFaces& faces) {
  std::vector<std::pair<uint32_t, uint32_t>> out;
  for (uint32_t t : triangles) {
    const Tri& tri = all[t];
    if (is_dead(tri)) continue;
    for (int k = 0; k < 3; ++k) {
      const uint32_t u = tri[k], v = tri[(k + 1) % 3];
      size_t uses = 0, same_way = 0;
      for (const uint32_t* f = faces.begin(u); f != faces.end(u); ++f) {
        const Tri& o = all[*f];
        for (int j = 0; j < 3; ++j) {
          if (o[j] == u && o[(j + 1) % 3] == v)
            ++uses, ++same_way;
          else if (o[j] == v && o[(j + 1) % 3] == u)
            ++uses;
        }
      }
      if (uses > 2 || same_way > 1) out.push_back({std::min(u, v), std::max(u, v)});
    }
  }
  std::sort(out.begin(), out.end());
  out.erase(std::unique(out.begin(), out.end()), out.end());
  return out;
}

}  // namespace vdbwrap::local_repair
