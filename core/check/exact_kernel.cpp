// The points as the exact predicates take them (see exact_kernel.h).
#include "check/exact_kernel.h"

#include <tbb/parallel_for.h>

namespace vdbwrap::check::pair_search {

ExactInput exact_input(const std::vector<Vec3>& points, const std::vector<Tri>& triangles) {
  ExactInput in{std::vector<P3>(points.size()), std::vector<uint8_t>(triangles.size(), 0)};
  tbb::parallel_for(tbb::blocked_range<size_t>(0, points.size(), 8192), [&](const tbb::blocked_range<size_t>& r) {
    for (size_t i = r.begin(); i != r.end(); ++i) in.p[i] = to_point(points[i]);
  });
  tbb::parallel_for(tbb::blocked_range<size_t>(0, triangles.size(), 4096), [&](const tbb::blocked_range<size_t>& r) {
    for (size_t t = r.begin(); t != r.end(); ++t) in.usable[t] = !is_degenerate(in.p, triangles[t]);
  });
  return in;
}

}  // namespace vdbwrap::check::pair_search
