#include "post/wrap_defects.h"

#include <tbb/parallel_for.h>
#include <tbb/parallel_sort.h>

#include <algorithm>

#include "vdbwrap/deviation.h"

namespace vdbwrap::post {

std::vector<uint8_t> wrap_defect_flags(const std::vector<Vec3>& points, const std::vector<Tri>& triangles,
                                       std::vector<uint8_t> flags, std::vector<Vec3> held_back) {
  flags.resize(triangles.size(), 0);
  if (held_back.empty()) return flags;
  // Held-back nodes are found by position, bit for bit: the stages after the fit renumber nodes.
  tbb::parallel_sort(held_back.begin(), held_back.end());
  std::vector<uint8_t> held(points.size(), 0);
  tbb::parallel_for(tbb::blocked_range<size_t>(0, points.size(), 4096), [&](const tbb::blocked_range<size_t>& r) {
    for (size_t i = r.begin(); i != r.end(); ++i)
      held[i] = std::binary_search(held_back.begin(), held_back.end(), points[i]);
  });
  for (size_t t = 0; t < triangles.size(); ++t)
    for (uint32_t v : triangles[t])
      if (v < held.size() && held[v]) flags[t] |= kDefectHeldBack;
  return flags;
}

}  // namespace vdbwrap::post
