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

}  // namespace vdbwrap
