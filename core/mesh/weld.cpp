#include "mesh/weld.h"

#include <tbb/parallel_for.h>
#include <tbb/parallel_sort.h>

#include <algorithm>
#include <cmath>
#include <numeric>

#include "common/cell_lists.h"
#include "common/edge_key.h"
#include "common/edge_triangles.h"
#include "common/exact_weld.h"
#include "common/fill_vector.h"
#include "common/grid_key.h"
#include "common/sorted_point_grid.h"
#include "common/vec.h"

namespace vdbwrap::mesh {
namespace {

// Per point: is another point within the tolerance? In parallel, on a grid of cells much
// wider than the tolerance, so that most points look in their own cell only. A point that
// has none is its own weld whatever the order (and no other point's), so only the crowded
// ones need the ordered pass below: on most inputs none.
std::vector<uint8_t> crowded_points(const std::vector<Vec3>& points, double tolerance) {
  const size_t n = points.size();
  const double tol2 = tolerance * tolerance;
  const SortedPointGrid grid(points, 1024 * tolerance);
  std::vector<uint8_t> crowded(n, 0);
  tbb::parallel_for(tbb::blocked_range<size_t>(0, n, 4096), [&](const tbb::blocked_range<size_t>& r) {
    for (size_t i = r.begin(); i != r.end(); ++i) {
      const Vec3& p = points[i];
      crowded[i] =
          grid.any_near(p, tolerance, [&](uint32_t j) { return j != i && norm2(points[j] - p) <= tol2; }) ? 1 : 0;
    }
  });
  return crowded;
}

}  // namespace

std::vector<uint32_t> weld_points(const std::vector<Vec3>& points, double tolerance, std::vector<Vec3>& welded) {
  // Bit-identical copies first, in parallel (an STL file repeats every point about six
  // times); then the tolerance, among the distinct points only.
  std::vector<Vec3> distinct;
  const std::vector<uint32_t> copy_of = exact_weld(points, distinct);
  std::vector<uint32_t> distinct_to_welded(distinct.size());
  welded.clear();
  if (tolerance > 0) {
    // In order, each crowded point goes to the first weld within the tolerance (hash grid with
    // cells of the tolerance: a match can only be in the 27 cells around), or starts one.
    const std::vector<uint8_t> crowded = crowded_points(distinct, tolerance);
    const double tol2 = tolerance * tolerance;
    CellLists<> buckets(tolerance);
    for (size_t i = 0; i < distinct.size(); ++i) {
      const Vec3& p = distinct[i];
      uint32_t found = UINT32_MAX;
      if (crowded[i]) {
        const GridKey key = buckets.cell_of(p);
        buckets.for_lists(GridKey{key.x - 1, key.y - 1, key.z - 1}, GridKey{key.x + 1, key.y + 1, key.z + 1},
                          [&](const std::vector<uint32_t>& list) {
                            for (uint32_t w : list)
                              if (norm2(welded[w] - p) <= tol2) return found = w, true;
                            return false;
                          });
        if (found == UINT32_MAX) buckets.add(key, uint32_t(welded.size()));
      }
      if (found == UINT32_MAX) {
        found = uint32_t(welded.size());
        welded.push_back(p);
      }
      distinct_to_welded[i] = found;
    }
  } else {
    welded = distinct;
    for (size_t i = 0; i < distinct.size(); ++i) distinct_to_welded[i] = uint32_t(i);
  }
  std::vector<uint32_t> remap(points.size());
  tbb::parallel_for(tbb::blocked_range<size_t>(0, points.size(), 8192), [&](const tbb::blocked_range<size_t>& r) {
    for (size_t i = r.begin(); i != r.end(); ++i) remap[i] = distinct_to_welded[copy_of[i]];
  });
  return remap;
}

}  // namespace vdbwrap::mesh
