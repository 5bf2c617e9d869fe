// Mesh diagnostics: the combinatorial checks (borders, non-manifold edges and vertices,
// orientation) and the geometric ones (degenerate and intersecting triangles).
#include <algorithm>
#include <cstring>
#include <numeric>
#include <unordered_map>

#include "check/intersections.h"
#include "common/vec.h"
#include "prep/prepare.h"
#include "vdbwrap/wrap.h"

namespace vdbwrap {
namespace {

struct PointHash {
  size_t operator()(const Vec3& p) const {
    uint64_t h = 1469598103934665603ULL;
    for (double d : p) {
      uint64_t bits;
      double z = d == 0 ? 0.0 : d;  // +0 and -0 alike
      std::memcpy(&bits, &z, 8);
      h = (h ^ bits) * 1099511628211ULL;
    }
    return size_t(h);
  }
};

uint64_t edge_key(uint32_t a, uint32_t b) {
  if (a > b) std::swap(a, b);
  return (uint64_t(a) << 32) | b;
}

struct UnionFind {
  std::vector<uint32_t> parent;
  explicit UnionFind(size_t n) : parent(n) { std::iota(parent.begin(), parent.end(), 0); }
  uint32_t find(uint32_t x) {
    while (parent[x] != x) x = parent[x] = parent[parent[x]];
    return x;
  }
  void unite(uint32_t a, uint32_t b) { parent[find(a)] = find(b); }
};

}  // namespace

MeshDiagnostics diagnose(const Mesh& mesh, bool find_intersections) {
  MeshDiagnostics d;
  // Exact weld: only bit-identical coordinates merge, so the counts describe the file as it is.
  std::unordered_map<Vec3, uint32_t, PointHash> index;
  std::vector<Vec3> pts;
  std::vector<uint32_t> remap(mesh.points.size());
  Box3 box;
  for (size_t i = 0; i < mesh.points.size(); ++i) {
    auto [it, added] = index.emplace(mesh.points[i], uint32_t(pts.size()));
    if (added) pts.push_back(mesh.points[i]);
    remap[i] = it->second;
  }
  std::vector<Tri> tris;
  tris.reserve(mesh.triangles.size());
  for (const Tri& t : mesh.triangles) tris.push_back({remap[t[0]], remap[t[1]], remap[t[2]]});
  std::vector<uint8_t> used(pts.size(), 0);
  for (const Tri& t : tris)
    for (uint32_t v : t) used[v] = 1;
  for (size_t i = 0; i < pts.size(); ++i)
    if (used[i]) box.add(pts[i]), ++d.vertices;
  d.triangles = tris.size();
  if (!box.empty()) {
    d.bbox_min = box.lo;
    d.bbox_max = box.hi;
    d.diagonal = box.diagonal();
  }
  {
    std::vector<int32_t> parts(mesh.triangle_part.begin(), mesh.triangle_part.end());
    std::sort(parts.begin(), parts.end());
    d.parts = parts.empty() ? (tris.empty() ? 0 : 1) : size_t(std::unique(parts.begin(), parts.end()) - parts.begin());
  }

  // Edges: how many triangles use each, and in which directions.
  struct EdgeUse {
    uint32_t count = 0, forward = 0;  // forward: traversed from the smaller to the larger index
  };
  std::unordered_map<uint64_t, EdgeUse> edges;
  edges.reserve(tris.size() * 2);
  const Vec3 c = box.empty() ? Vec3{0, 0, 0} : box.center();
  for (const Tri& t : tris) {
    if (t[0] == t[1] || t[1] == t[2] || t[0] == t[2] ||
        norm2(area_vector(pts[t[0]], pts[t[1]], pts[t[2]])) == 0.0) {
      ++d.degenerate_triangles;
    }
    d.area += 0.5 * norm(area_vector(pts[t[0]], pts[t[1]], pts[t[2]]));
    d.volume += dot(pts[t[0]] - c, cross(pts[t[1]] - c, pts[t[2]] - c)) / 6.0;
    for (int e = 0; e < 3; ++e) {
      uint32_t a = t[e], b = t[(e + 1) % 3];
      if (a == b) continue;
      auto& use = edges[edge_key(a, b)];
      ++use.count;
      if (a < b) ++use.forward;
    }
  }
  for (const auto& [key, use] : edges) {
    if (use.count == 1) ++d.border_edges;
    if (use.count > 2) ++d.nonmanifold_edges;
    if (use.count == 2 && use.forward != 1) ++d.misoriented_edges;
  }

  // Non-manifold vertices: the triangles around a vertex, joined through its manifold edges,
  // must form a single fan.
  {
    std::vector<std::vector<uint32_t>> vert_tris(pts.size());
    for (uint32_t t = 0; t < tris.size(); ++t)
      for (uint32_t v : tris[t]) vert_tris[v].push_back(t);
    for (uint32_t v = 0; v < pts.size(); ++v) {
      const auto& around = vert_tris[v];
      if (around.size() < 2) continue;
      UnionFind uf(around.size());
      for (size_t i = 0; i < around.size(); ++i)
        for (size_t j = i + 1; j < around.size(); ++j) {
          // joined when they share an edge at v that is used by exactly these two
          for (uint32_t w : tris[around[i]]) {
            if (w == v) continue;
            bool shared = std::find(tris[around[j]].begin(), tris[around[j]].end(), w) != tris[around[j]].end();
            if (shared && edges[edge_key(v, w)].count == 2) uf.unite(uint32_t(i), uint32_t(j));
          }
        }
      uint32_t root = uf.find(0);
      for (size_t i = 1; i < around.size(); ++i)
        if (uf.find(uint32_t(i)) != root) {
          ++d.nonmanifold_vertices;
          break;
        }
    }
  }

  // Connected components through shared vertices.
  {
    UnionFind uf(pts.size());
    for (const Tri& t : tris) uf.unite(t[0], t[1]), uf.unite(t[1], t[2]);
    for (uint32_t v = 0; v < pts.size(); ++v)
      if (used[v] && uf.find(v) == v) ++d.components;
  }

  d.closed = !tris.empty() && d.border_edges == 0 && d.nonmanifold_edges == 0;
  d.manifold = d.nonmanifold_edges == 0 && d.nonmanifold_vertices == 0;
  d.oriented = d.manifold && d.misoriented_edges == 0;
  d.outward = d.closed && d.oriented && d.volume > 0;

  if (find_intersections) {
    auto pairs = check::find_intersecting_pairs(pts, tris);
    d.intersecting_pairs = pairs.size();
    std::vector<uint32_t> hit;
    for (const auto& p : pairs) hit.push_back(p.a), hit.push_back(p.b);
    std::sort(hit.begin(), hit.end());
    d.intersecting_triangles = size_t(std::unique(hit.begin(), hit.end()) - hit.begin());
    d.self_intersecting = !pairs.empty();
  }
  return d;
}

}  // namespace vdbwrap
