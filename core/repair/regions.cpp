// Regions of intersecting triangles: union-find over shared vertices (clusters: shared edges)
// and intersecting pairs.
#include "repair/regions.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <numeric>
#include <unordered_map>

#include "common/edge_key.h"
#include "common/vec.h"

namespace vdbwrap::local_repair {

VertexFaces vertex_faces(size_t point_count, const std::vector<Tri>& triangles) {
  VertexFaces vf;
  vf.offset.assign(point_count + 1, 0);
  for (const Tri& t : triangles)
    if (!is_dead(t))
      for (uint32_t v : t) ++vf.offset[v + 1];
  for (size_t i = 0; i < point_count; ++i) vf.offset[i + 1] += vf.offset[i];
  vf.faces.resize(vf.offset.back());
  std::vector<uint32_t> fill(vf.offset.begin(), vf.offset.end() - 1);
  for (uint32_t t = 0; t < triangles.size(); ++t) {
    const Tri& tri = triangles[t];
    if (is_dead(tri)) continue;
    for (int k = 0; k < 3; ++k) {
      // A triangle with a repeated vertex is listed once per distinct vertex.
      bool repeated = false;
      for (int j = 0; j < k; ++j) repeated |= tri[j] == tri[k];
      if (!repeated) vf.faces[fill[tri[k]]++] = t;
    }
  }
  // Rows shrink where triangles repeat a vertex: close the gaps.
  size_t out = 0;
  std::vector<uint32_t> offset(point_count + 1, 0);
  for (size_t v = 0; v < point_count; ++v) {
    for (uint32_t i = vf.offset[v]; i < fill[v]; ++i) vf.faces[out++] = vf.faces[i];
    offset[v + 1] = uint32_t(out);
  }
  vf.faces.resize(out);
  vf.offset = std::move(offset);
  return vf;
}

std::vector<uint32_t> triangles_of(const std::vector<check::TrianglePair>& pairs) {
  std::vector<uint32_t> out;
  out.reserve(pairs.size() * 2);
  for (const auto& p : pairs) {
    out.push_back(p.a);
    out.push_back(p.b);
  }
  std::sort(out.begin(), out.end());
  out.erase(std::unique(out.begin(), out.end()), out.end());
  return out;
}

namespace {

// Union-find over the listed triangles: those with a common key (`keys_of`) and the pairs are
// joined.
template <class Keys>
std::vector<std::vector<uint32_t>> group_by(const std::vector<Tri>& all, const std::vector<uint32_t>& triangles,
                                            const std::vector<check::TrianglePair>& pairs, const Keys& keys_of) {
  std::unordered_map<uint32_t, uint32_t> slot;
  slot.reserve(triangles.size() * 2);
  for (uint32_t i = 0; i < triangles.size(); ++i) slot.emplace(triangles[i], i);
  std::vector<uint32_t> parent(triangles.size());
  std::iota(parent.begin(), parent.end(), 0);
  auto find = [&](uint32_t x) {
    while (parent[x] != x) x = parent[x] = parent[parent[x]];
    return x;
  };
  auto unite = [&](uint32_t a, uint32_t b) { parent[find(a)] = find(b); };
  std::unordered_map<uint64_t, uint32_t> first_with_key;
  for (uint32_t i = 0; i < triangles.size(); ++i)
    for (uint64_t key : keys_of(all[triangles[i]])) {
      auto [it, added] = first_with_key.emplace(key, i);
      if (!added) unite(i, it->second);
    }
  for (const auto& p : pairs) {
    auto a = slot.find(p.a), b = slot.find(p.b);
    if (a != slot.end() && b != slot.end()) unite(a->second, b->second);
  }
  std::unordered_map<uint32_t, size_t> index;
  std::vector<std::vector<uint32_t>> regions;
  for (uint32_t i = 0; i < triangles.size(); ++i) {
    auto [it, added] = index.emplace(find(i), regions.size());
    if (added) regions.emplace_back();
    regions[it->second].push_back(triangles[i]);
  }
  for (auto& r : regions) std::sort(r.begin(), r.end());
  std::sort(regions.begin(), regions.end());
  return regions;
}

}  // namespace

std::vector<std::vector<uint32_t>> group_regions(const std::vector<Tri>& all, const std::vector<uint32_t>& triangles,
                                                 const std::vector<check::TrianglePair>& pairs) {
  return group_by(all, triangles, pairs, [](const Tri& t) { return std::array<uint64_t, 3>{t[0], t[1], t[2]}; });
}

std::vector<std::vector<uint32_t>> group_clusters(const std::vector<Tri>& all, const std::vector<uint32_t>& triangles,
                                                  const std::vector<check::TrianglePair>& pairs) {
  return group_by(all, triangles, pairs, [](const Tri& t) {
    return std::array<uint64_t, 3>{edge_key(t[0], t[1]), edge_key(t[1], t[2]), edge_key(t[2], t[0])};
  });
}

std::vector<uint32_t> grow_ring(const std::vector<Tri>& all, const VertexFaces& faces,
                                const std::vector<uint32_t>& set) {
  std::vector<uint32_t> out(set);
  for (uint32_t t : set)
    for (uint32_t v : all[t]) out.insert(out.end(), faces.begin(v), faces.end(v));
  std::sort(out.begin(), out.end());
  out.erase(std::unique(out.begin(), out.end()), out.end());
  return out;
}

std::vector<uint32_t> vertices_of(const std::vector<Tri>& all, const std::vector<uint32_t>& set) {
  std::vector<uint32_t> out;
  out.reserve(set.size() * 3);
  for (uint32_t t : set) out.insert(out.end(), all[t].begin(), all[t].end());
  std::sort(out.begin(), out.end());
  out.erase(std::unique(out.begin(), out.end()), out.end());
  return out;
}

EdgeRange edge_range(const std::vector<Vec3>& points, const std::vector<Tri>& all, const std::vector<uint32_t>& set) {
  double lo = std::numeric_limits<double>::infinity(), hi = 0;
  for (uint32_t t : set)
    for (int k = 0; k < 3; ++k) {
      double len = norm(points[all[t][(k + 1) % 3]] - points[all[t][k]]);
      if (len <= 0) continue;  // repeated vertices: not an edge
      lo = std::min(lo, len);
      hi = std::max(hi, len);
    }
  if (!(lo < std::numeric_limits<double>::infinity())) lo = 0;
  return {lo, hi};
}

std::vector<uint32_t> close_pinches(const std::vector<Tri>& all, const VertexFaces& faces, std::vector<uint32_t> set,
                                    int rounds) {
  for (int round = 0; round < rounds; ++round) {
    // Border edges of the set: used once by it. A vertex starting two of them is a pinch.
    std::unordered_map<uint64_t, int> used;
    for (uint32_t t : set)
      for (int k = 0; k < 3; ++k) {
        uint32_t u = all[t][k], v = all[t][(k + 1) % 3];
        ++used[u < v ? (uint64_t(u) << 32 | v) : (uint64_t(v) << 32 | u)];
      }
    std::unordered_map<uint32_t, int> starts;
    for (uint32_t t : set)
      for (int k = 0; k < 3; ++k) {
        uint32_t u = all[t][k], v = all[t][(k + 1) % 3];
        if (used[u < v ? (uint64_t(u) << 32 | v) : (uint64_t(v) << 32 | u)] == 1) ++starts[u];
      }
    std::vector<uint32_t> grown = set;
    for (const auto& [v, n] : starts)
      if (n > 1) grown.insert(grown.end(), faces.begin(v), faces.end(v));
    if (grown.size() == set.size()) break;
    std::sort(grown.begin(), grown.end());
    grown.erase(std::unique(grown.begin(), grown.end()), grown.end());
    set = std::move(grown);
  }
  return set;
}

// Live triangles on edge (u, v).
size_t edge_use(const std::vector<Tri>& triangles, const VertexFaces& faces, uint32_t u, uint32_t v) {
  size_t n = 0;
  for (const uint32_t* f = faces.begin(u); f != faces.end(u); ++f) {
    const Tri& t = triangles[*f];
    n += (t[0] == v || t[1] == v || t[2] == v) ? 1 : 0;
  }
  return n;
}

}  // namespace vdbwrap::local_repair
