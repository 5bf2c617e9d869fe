#include "mesh/fold_crossings.h"

#include <tbb/parallel_for.h>

#include <algorithm>

#include "common/compressed_lists.h"

namespace vdbwrap::mesh {

namespace {
constexpr int kRings = 2;  // noise twice as coarse as the faces folds them over the next ring
}  // namespace

std::vector<uint8_t> fold_crossings(size_t points, const std::vector<Tri>& triangles,
                                    const std::vector<std::pair<uint32_t, uint32_t>>& pairs) {
  std::vector<uint8_t> fold(pairs.size(), 0);
  if (pairs.empty()) return fold;
  const CompressedLists faces_at = compressed_lists(points, [&](auto&& emit) {
    for (uint32_t t = 0; t < triangles.size(); ++t)
      for (uint32_t v : triangles[t]) emit(v, t);
  });
  tbb::parallel_for(tbb::blocked_range<size_t>(0, pairs.size(), 1024), [&](const tbb::blocked_range<size_t>& r) {
    std::vector<uint32_t> ring, next;
    for (size_t i = r.begin(); i != r.end(); ++i) {
      const Tri& b = triangles[pairs[i].second];
      auto corner_of_b = [&](uint32_t v) { return v == b[0] || v == b[1] || v == b[2]; };
      // The corners within kRings rings of the first triangle's corners.
      ring.assign(triangles[pairs[i].first].begin(), triangles[pairs[i].first].end());
      bool near = std::any_of(ring.begin(), ring.end(), corner_of_b);
      for (int k = 0; k < kRings && !near; ++k) {
        next.clear();
        for (uint32_t v : ring)
          for (uint32_t t : faces_at[v])
            for (uint32_t w : triangles[t]) next.push_back(w);
        std::sort(next.begin(), next.end());
        next.erase(std::unique(next.begin(), next.end()), next.end());
        near = std::any_of(next.begin(), next.end(), corner_of_b);
        ring.swap(next);
      }
      fold[i] = near;
    }
  });
  return fold;
}

}  // namespace vdbwrap::mesh
