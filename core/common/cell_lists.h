// Items listed by the cell of a uniform grid: the hash-grid index that welding, the sharp-edge
// samples of the post-processing checks, the batches of coarsening, the moved nodes of the
// validity loop and the triangle buckets share. A cell's items keep the order they were added
// in, and cells are visited x first, then y, then z, so that results never depend on the hash.
#pragma once
#include <cstdint>
#include <type_traits>
#include <unordered_map>
#include <utility>
#include <vector>

#include "common/grid_key.h"
#include "common/vec.h"

namespace vdbwrap {

template <typename T = uint32_t>
class CellLists {
 public:
  // Cells `cell` wide; without one, the caller makes the keys (cell_of is then unit cells).
  explicit CellLists(double cell = 1.0) : inv_(1.0 / cell) {}

  double inverse_cell() const { return inv_; }
  GridKey cell_of(const Vec3& p) const { return grid_key(p, inv_); }

  // The list of cell k, made empty when it has none yet.
  std::vector<T>& operator[](const GridKey& k) { return cells_[k]; }
  void add(const GridKey& k, T item) { cells_[k].push_back(std::move(item)); }
  void add(const Vec3& p, T item) { add(cell_of(p), std::move(item)); }
  // Sets cell k's list, which must not exist yet.
  void set(const GridKey& k, std::vector<T>&& items) { cells_.emplace(k, std::move(items)); }

  // The list of cell k, or null.
  const std::vector<T>* find(const GridKey& k) const {
    const auto it = cells_.find(k);
    return it == cells_.end() ? nullptr : &it->second;
  }
  std::vector<T>* find(const GridKey& k) {
    const auto it = cells_.find(k);
    return it == cells_.end() ? nullptr : &it->second;
  }
  bool has(const GridKey& k) const { return cells_.count(k) != 0; }
  bool empty() const { return cells_.empty(); }
  void clear() { cells_.clear(); }
  void reserve(size_t cells) { cells_.reserve(cells); }

  // Calls visit(key) for the cells from lo to hi, both included. When visit returns bool, true
  // stops the walk; returns whether one did.
  template <typename Visit>
  static bool for_cells(const GridKey& lo, const GridKey& hi, Visit&& visit) {
    for (int64_t x = lo.x; x <= hi.x; ++x)
      for (int64_t y = lo.y; y <= hi.y; ++y)
        for (int64_t z = lo.z; z <= hi.z; ++z) {
          if constexpr (std::is_same_v<decltype(visit(GridKey{})), bool>) {
            if (visit(GridKey{x, y, z})) return true;
          } else {
            visit(GridKey{x, y, z});
          }
        }
    return false;
  }
  // The cells that box b covers.
  template <typename Visit>
  bool for_cells(const Box3& b, Visit&& visit) const {
    return for_cells(cell_of(b.lo), cell_of(b.hi), std::forward<Visit>(visit));
  }

  // Calls visit(list) for the cells from lo to hi that have one; bool-returning visits stop
  // the walk as in for_cells.
  template <typename Visit>
  bool for_lists(const GridKey& lo, const GridKey& hi, Visit&& visit) const {
    return for_cells(lo, hi, [&](const GridKey& k) {
      const std::vector<T>* list = find(k);
      if constexpr (std::is_same_v<decltype(visit(*list)), bool>) {
        return list && visit(*list);
      } else {
        if (list) visit(*list);
        return false;
      }
    });
  }
  // The lists of the cells that box b covers, widened by `margin` cells on every side.
  template <typename Visit>
  bool for_lists(const Box3& b, Visit&& visit, int64_t margin = 0) const {
    const GridKey lo = cell_of(b.lo), hi = cell_of(b.hi);
    return for_lists(GridKey{lo.x - margin, lo.y - margin, lo.z - margin},
                     GridKey{hi.x + margin, hi.y + margin, hi.z + margin}, std::forward<Visit>(visit));
  }

 private:
  double inv_;
  std::unordered_map<GridKey, std::vector<T>, GridKeyHash> cells_;
};

}  // namespace vdbwrap
