// The triangles around each edge of an indexed triangle set, by one parallel sort.
#pragma once
#include <algorithm>
#include <cstdint>
#include <vector>

#include <tbb/parallel_for.h>
#include <tbb/parallel_sort.h>

#include "common/edge_key.h"
#include "common/fill_vector.h"
#include "vdbwrap/mesh.h"

namespace vdbwrap {

// The triangles around each edge, in increasing order: runs of `tris` sorted by edge key.
// Built by one parallel sort instead of a hash map of vectors (a heap block per edge), which
// was most of orienting and of finding feature edges on millions of triangles. Every edge of
// every triangle is listed, repeated vertices included, as the map listed them.
struct EdgeTriangles {
  std::vector<uint64_t> keys;   // edge keys, sorted, each once
  std::vector<uint32_t> start;  // triangles of keys[i]: tris[start[i] .. start[i + 1])
  std::vector<uint32_t> tris;

  size_t edges() const { return keys.size(); }
  size_t size(size_t i) const { return start[i + 1] - start[i]; }
  const uint32_t* begin(size_t i) const { return tris.data() + start[i]; }
  size_t find(uint64_t key) const { return size_t(std::lower_bound(keys.begin(), keys.end(), key) - keys.begin()); }
};

// `usable` (optional): only triangles t with usable[t] are listed.
inline EdgeTriangles edge_triangles(const std::vector<Tri>& triangles, const std::vector<uint8_t>* usable = nullptr) {
  struct Use {
    uint64_t edge;
    uint32_t triangle;
    bool operator<(const Use& o) const { return edge != o.edge ? edge < o.edge : triangle < o.triangle; }
  };
  FillVector<Use> uses(triangles.size() * 3);
  tbb::parallel_for(tbb::blocked_range<size_t>(0, triangles.size(), 4096), [&](const tbb::blocked_range<size_t>& r) {
    for (size_t t = r.begin(); t != r.end(); ++t)
      for (int e = 0; e < 3; ++e)
        uses[3 * t + e] = usable && !(*usable)[t]
                              ? Use{UINT64_MAX, 0}  // sorted last, cut off below
                              : Use{edge_key(triangles[t][e], triangles[t][(e + 1) % 3]), uint32_t(t)};
  });
  tbb::parallel_sort(uses.begin(), uses.end());  // (key, triangle): a total order, deterministic
  if (usable)
    while (!uses.empty() && uses.back().edge == UINT64_MAX) uses.pop_back();
  EdgeTriangles out;
  out.tris.resize(uses.size());
  for (size_t i = 0; i < uses.size(); ++i) {
    if (i == 0 || uses[i].edge != uses[i - 1].edge) {
      out.keys.push_back(uses[i].edge);
      out.start.push_back(uint32_t(i));
    }
    out.tris[i] = uses[i].triangle;
  }
  out.start.push_back(uint32_t(uses.size()));
  return out;
}

// The side of `tri` that runs from a to b (corner e to corner e + 1), or -1.
inline int directed_side(const Tri& tri, uint32_t a, uint32_t b) {
  for (int e = 0; e < 3; ++e)
    if (tri[e] == a && tri[(e + 1) % 3] == b) return e;
  return -1;
}

}  // namespace vdbwrap
