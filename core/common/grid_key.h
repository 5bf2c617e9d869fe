// Integer cell coordinates for hash grids over points (welding, buckets, spacing checks).
#pragma once
#include <cmath>
#include <cstdint>
#include <functional>

#include "vdbwrap/mesh.h"

namespace vdbwrap {

struct GridKey {
  int64_t x, y, z;
  bool operator==(const GridKey& o) const { return x == o.x && y == o.y && z == o.z; }
  // x first, then y, then z: for sorting entries by cell.
  bool operator<(const GridKey& o) const { return x != o.x ? x < o.x : y != o.y ? y < o.y : z < o.z; }
};

struct GridKeyHash {
  // Unsigned arithmetic: the same values, without the signed overflow (undefined behaviour,
  // found by UBSan) that cells far from the origin caused.
  size_t operator()(const GridKey& k) const {
    return size_t(uint64_t(k.x) * 73856093ULL ^ uint64_t(k.y) * 19349663ULL ^ uint64_t(k.z) * 83492791ULL);
  }
};

// The cell of p on a grid of cells 1/inv_cell wide.
inline GridKey grid_key(const Vec3& p, double inv_cell) {
  return {int64_t(std::floor(p[0] * inv_cell)), int64_t(std::floor(p[1] * inv_cell)),
          int64_t(std::floor(p[2] * inv_cell))};
}

// fn(cell) for the 27 cells around k (k among them).
template <typename F>
void for_each_cell_around(const GridKey& k, F&& fn) {
  for (int64_t dx = -1; dx <= 1; ++dx)
    for (int64_t dy = -1; dy <= 1; ++dy)
      for (int64_t dz = -1; dz <= 1; ++dz) fn(GridKey{k.x + dx, k.y + dy, k.z + dz});
}

}  // namespace vdbwrap
