// Points of an integer box numbered densely, x first, then y, then z: the numbers order the
// points as (x, y, z) does and need only as many bits as the box has points, so that a radix
// sort by them takes few passes (cells of refinement and of the nearest-point index, lattice
// points of extraction).
#pragma once
#include <array>
#include <cstdint>

namespace vdbwrap {

struct DenseNumbers {
  std::array<int64_t, 3> low{0, 0, 0};  // the box's first point
  uint64_t ny = 1, nz = 1;              // points along y and z
  uint64_t count = 0;                   // points in the box: every number is below it
  DenseNumbers() = default;
  DenseNumbers(const std::array<int64_t, 3>& first, const std::array<uint64_t, 3>& points)
      : low(first), ny(points[1]), nz(points[2]), count(points[0] * points[1] * points[2]) {}
  uint64_t number(int64_t x, int64_t y, int64_t z) const {
    return (uint64_t(x - low[0]) * ny + uint64_t(y - low[1])) * nz + uint64_t(z - low[2]);
  }
  std::array<int64_t, 3> point(uint64_t n) const {
    return {int64_t(n / (ny * nz)) + low[0], int64_t(n / nz % ny) + low[1], int64_t(n % nz) + low[2]};
  }
};

}  // namespace vdbwrap
