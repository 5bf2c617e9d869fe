// Points sorted by their cell on a uniform grid, for "is another point this close?" over
// millions of points. Built by one parallel sort (a hash map of per-cell lists is filled
// serially, a heap list per cell: on a 1.4M-node wrap, probing its 27 cells per node was a
// sixth of the projection stage); a cell's points are then found by binary search.
// Read-only once built: queries are thread-safe.
#pragma once
#include <algorithm>
#include <cstdint>
#include <vector>

#include <tbb/parallel_for.h>
#include <tbb/parallel_sort.h>

#include "common/fill_vector.h"
#include "common/grid_key.h"
#include "common/vec.h"

namespace vdbwrap {

// Calls visit(key) for every cell (of side 1 / inv_cell) that the box of half-width `reach`
// around q reaches, the box widened by its own width so that a rounding in the cell keys
// never hides one. Stops at the first visit that returns true, and returns whether one did.
template <typename Visit>
bool any_cell_near(const Vec3& q, double reach, double inv_cell, Visit&& visit) {
  const double r = 2 * reach;
  const GridKey lo = grid_key(q - Vec3{r, r, r}, inv_cell), hi = grid_key(q + Vec3{r, r, r}, inv_cell);
  for (int64_t x = lo.x; x <= hi.x; ++x)
    for (int64_t y = lo.y; y <= hi.y; ++y)
      for (int64_t z = lo.z; z <= hi.z; ++z)
        if (visit(GridKey{x, y, z})) return true;
  return false;
}

class SortedPointGrid {
 public:
  // `cell` should be much wider than the distances asked about, so that most queries look in
  // one cell; the positions are those at construction.
  SortedPointGrid(const std::vector<Vec3>& points, double cell) : inv_(1.0 / cell), entries_(points.size()) {
    tbb::parallel_for(tbb::blocked_range<size_t>(0, points.size(), 8192), [&](const tbb::blocked_range<size_t>& r) {
      for (size_t i = r.begin(); i != r.end(); ++i) entries_[i] = {grid_key(points[i], inv_), uint32_t(i)};
    });
    tbb::parallel_sort(entries_.begin(), entries_.end());
  }

  double inverse_cell() const { return inv_; }

  // Calls visit(j) for the points j of every cell any_cell_near(q, reach) visits (a superset
  // of the points within `reach`). Stops at the first visit that returns true, and returns
  // whether one did.
  template <typename Visit>
  bool any_near(const Vec3& q, double reach, Visit&& visit) const {
    return any_cell_near(q, reach, inv_, [&](const GridKey& k) {
      for (auto it = std::lower_bound(entries_.begin(), entries_.end(), Entry{k, 0});
           it != entries_.end() && it->key == k; ++it)
        if (visit(it->point)) return true;
      return false;
    });
  }

 private:
  struct Entry {
    GridKey key;
    uint32_t point;
    bool operator<(const Entry& o) const { return key == o.key ? point < o.point : key < o.key; }
  };
  double inv_;
  FillVector<Entry> entries_;
};

}  // namespace vdbwrap
