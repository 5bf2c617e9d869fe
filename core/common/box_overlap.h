// Separating-axis overlap tests of a triangle or segment against an axis-aligned box, shared
// by the voxel stage (which cells a triangle passes through) and the nearest-point index
// (which cells hold a part of a long triangle). Plain doubles: callers that need a
// conservative answer enlarge the box by more than the rounding.
#pragma once
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <utility>

#include "common/vec.h"

namespace vdbwrap {

inline bool triangle_overlaps_box(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& center, const Vec3& h) {
  // Akenine-Moller's separating axis test: 3 box axes, the triangle normal, 9 edge crosses.
  const Vec3 v0 = a - center, v1 = b - center, v2 = c - center;
  for (int k = 0; k < 3; ++k) {
    double lo = std::min({v0[k], v1[k], v2[k]}), hi = std::max({v0[k], v1[k], v2[k]});
    if (lo > h[k] || hi < -h[k]) return false;
  }
  const Vec3 e[3] = {v1 - v0, v2 - v1, v0 - v2};
  const Vec3 v[3] = {v0, v1, v2};
  for (int i = 0; i < 3; ++i)
    for (int k = 0; k < 3; ++k) {
      Vec3 axis{0, 0, 0};
      Vec3 unit{0, 0, 0};
      unit[k] = 1;
      axis = cross(unit, e[i]);
      double p0 = dot(v[0], axis), p1 = dot(v[1], axis), p2 = dot(v[2], axis);
      double r = h[0] * std::fabs(axis[0]) + h[1] * std::fabs(axis[1]) + h[2] * std::fabs(axis[2]);
      if (std::min({p0, p1, p2}) > r || std::max({p0, p1, p2}) < -r) return false;
    }
  Vec3 n = cross(e[0], e[1]);
  double d = dot(n, v0);
  double r = h[0] * std::fabs(n[0]) + h[1] * std::fabs(n[1]) + h[2] * std::fabs(n[2]);
  return std::fabs(d) <= r;
}

// A triangle prepared for many box tests: the same thirteen separating axes as
// triangle_overlaps_box, with the triangle's extent along each computed once (from its first
// vertex), so that each box costs a dot product per axis. The voxel stage and the
// nearest-point index test each triangle against the blocks and cells of its bounding box:
// tens of millions of tests on big assemblies. (A cell's eight children are tested
// at once by octants_overlapped, below.)
// Mathematically the same test; the rounding differs only far below the callers' margins.
class TriangleBoxTester {
 public:
  TriangleBoxTester(const Vec3& a, const Vec3& b, const Vec3& c) : ref_(a) {
    const Vec3 v[3] = {Vec3{0, 0, 0}, b - a, c - a};
    for (int k = 0; k < 3; ++k)
      lo_[k] = std::min({v[0][k], v[1][k], v[2][k]}), hi_[k] = std::max({v[0][k], v[1][k], v[2][k]});
    const Vec3 e[3] = {v[1] - v[0], v[2] - v[1], v[0] - v[2]};
    // The normal first: a box beside the triangle's plane is the usual miss. (The answer is the
    // same in any order: every axis is tested in full.)
    int n = 0;
    add_axis(cross(e[0], e[1]), v, n++);
    for (int i = 0; i < 3; ++i)
      for (int k = 0; k < 3; ++k) {
        Vec3 unit{0, 0, 0};
        unit[k] = 1;
        add_axis(cross(unit, e[i]), v, n++);
      }
  }
  // Does the triangle meet the cube of this centre and half-width? The same test for a cube,
  // with each axis's sum of absolute components taken once for all the cubes tested.
  bool overlaps_cube(const Vec3& center, double half) const {
    const Vec3 d = center - ref_;
    for (int k = 0; k < 3; ++k)
      if (lo_[k] - d[k] > half || hi_[k] - d[k] < -half) return false;
    for (int i = 0; i < kAxes; ++i) {
      const Vec3& u = axis_[i];
      const double s = u[0] * d[0] + u[1] * d[1] + u[2] * d[2];
      const double r = half * abs_sum_[i];
      if (min_[i] - s > r || max_[i] - s < -r) return false;
    }
    return true;
  }
  // Does the triangle meet the box of this centre and half-widths?
  bool overlaps(const Vec3& center, const Vec3& half) const {
    const Vec3 d = center - ref_;
    for (int k = 0; k < 3; ++k)
      if (lo_[k] - d[k] > half[k] || hi_[k] - d[k] < -half[k]) return false;
    for (int i = 0; i < kAxes; ++i) {
      const Vec3& u = axis_[i];
      const double s = u[0] * d[0] + u[1] * d[1] + u[2] * d[2];
      const double r = half[0] * std::fabs(u[0]) + half[1] * std::fabs(u[1]) + half[2] * std::fabs(u[2]);
      if (min_[i] - s > r || max_[i] - s < -r) return false;
    }
    return true;
  }

 private:
  static constexpr int kAxes = 10;  // the normal, then nine edge crosses
  void add_axis(const Vec3& u, const Vec3 (&v)[3], int i) {
    axis_[i] = u;
    abs_sum_[i] = std::fabs(u[0]) + std::fabs(u[1]) + std::fabs(u[2]);
    const double p0 = dot(v[0], u), p1 = dot(v[1], u), p2 = dot(v[2], u);
    min_[i] = std::min({p0, p1, p2}), max_[i] = std::max({p0, p1, p2});
  }
  Vec3 ref_, lo_, hi_;
  Vec3 axis_[kAxes];
  double min_[kAxes], max_[kAxes];
  double abs_sum_[kAxes];
};

// Which of the eight octant boxes of a cell (those in `among`) triangle abc meets: bit k is
// octant k, whose centre is `centre` + `quarter` * (+-1, +-1, +-1), + along axis j when bit j
// of k is set, and whose half-width is `half`. The same thirteen separating axes as above,
// each projecting the triangle once for all the octants asked about: an octant's centre
// projects to the cell centre's projection plus its offset, and all share the radius.
// Refinement splits its cells with it (asking only about the children no triangle met yet:
// see build_refined_grid), and the nearest-point index its crowded cells.
inline uint8_t octants_overlapped(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& centre, double quarter,
                                  double half, uint8_t among = 0xff) {
  const Vec3 v[3] = {a - centre, b - centre, c - centre};
  // The box axes: along axis j the triangle's extent against the octants below and above.
  static constexpr uint8_t below[3] = {0x55, 0x33, 0x0f}, above[3] = {0xaa, 0xcc, 0xf0};
  uint8_t mask = among;
  for (int j = 0; j < 3; ++j) {
    const double lo = std::min({v[0][j], v[1][j], v[2][j]}), hi = std::max({v[0][j], v[1][j], v[2][j]});
    if (lo + quarter > half || hi + quarter < -half) mask &= uint8_t(~below[j]);
    if (lo - quarter > half || hi - quarter < -half) mask &= uint8_t(~above[j]);
  }
  // The other axes, each against the octants still in.
  auto separate = [&](const Vec3& u) {
    const double p0 = dot(v[0], u), p1 = dot(v[1], u), p2 = dot(v[2], u);
    const double lo = std::min({p0, p1, p2}), hi = std::max({p0, p1, p2});
    const double r = half * (std::fabs(u[0]) + std::fabs(u[1]) + std::fabs(u[2]));
    const double ox = quarter * u[0], oy = quarter * u[1], oz = quarter * u[2];
    for (unsigned left = mask; left; left &= left - 1) {
      const int k = __builtin_ctz(left);
      const double o = (k & 1 ? ox : -ox) + (k & 2 ? oy : -oy) + (k & 4 ? oz : -oz);
      if (lo - o > r || hi - o < -r) mask &= uint8_t(~(1u << k));
    }
  };
  const Vec3 e[3] = {v[1] - v[0], v[2] - v[1], v[0] - v[2]};
  if (mask) separate(cross(e[0], e[1]));  // the normal first (see TriangleBoxTester)
  for (int i = 0; i < 3 && mask; ++i) {   // the edges crossed with the box axes
    separate(Vec3{0, -e[i][2], e[i][1]});
    if (mask) separate(Vec3{e[i][2], 0, -e[i][0]});
    if (mask) separate(Vec3{-e[i][1], e[i][0], 0});
  }
  return mask;
}

// Calls fn(x, y, z) for every cell of the block lo..hi (inclusive, per axis) of a grid of cubes
// of side `cell` from `origin` that triangle abc overlaps, each cell grown to half-width
// `half_cell`: the cells a test of each one would find, but blocks of cells are tested first
// and only those the triangle meets are opened. (A long slanted triangle's box holds hundreds
// of cells for each one it passes through.) A block is grown a little beyond its cells, so
// that rounding never drops a cell the cell's own test would keep.
template <typename F>
void for_cells_overlapping(const TriangleBoxTester& triangle, const Vec3& origin, double cell, double half_cell,
                           const int lo[3], const int hi[3], F&& fn) {
  const int64_t count = int64_t(hi[0] - lo[0] + 1) * (hi[1] - lo[1] + 1) * (hi[2] - lo[2] + 1);
  if (count <= 0) return;
  if (count <= 8) {
    for (int z = lo[2]; z <= hi[2]; ++z)
      for (int y = lo[1]; y <= hi[1]; ++y)
        for (int x = lo[0]; x <= hi[0]; ++x) {
          const Vec3 center{origin[0] + (x + 0.5) * cell, origin[1] + (y + 0.5) * cell, origin[2] + (z + 0.5) * cell};
          if (triangle.overlaps_cube(center, half_cell)) fn(x, y, z);
        }
    return;
  }
  Vec3 center, half;
  const double grow = (half_cell - 0.5 * cell) + 1e-6 * cell;
  for (int k = 0; k < 3; ++k) {
    center[k] = origin[k] + 0.5 * (double(lo[k]) + double(hi[k]) + 1) * cell;
    half[k] = 0.5 * double(hi[k] - lo[k] + 1) * cell + grow;
  }
  if (!triangle.overlaps(center, half)) return;
  int axis = 0;
  for (int k = 1; k < 3; ++k)
    if (hi[k] - lo[k] > hi[axis] - lo[axis]) axis = k;
  const int mid = lo[axis] + (hi[axis] - lo[axis]) / 2;
  int lo2[3] = {lo[0], lo[1], lo[2]}, hi1[3] = {hi[0], hi[1], hi[2]};
  hi1[axis] = mid, lo2[axis] = mid + 1;
  for_cells_overlapping(triangle, origin, cell, half_cell, lo, hi1, fn);
  for_cells_overlapping(triangle, origin, cell, half_cell, lo2, hi, fn);
}
template <typename F>
void for_cells_overlapping(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& origin, double cell,
                           double half_cell, const int lo[3], const int hi[3], F&& fn) {
  for_cells_overlapping(TriangleBoxTester(a, b, c), origin, cell, half_cell, lo, hi, fn);
}

inline bool segment_overlaps_box(const Vec3& a, const Vec3& b, const Vec3& lo, const Vec3& hi) {
  double t0 = 0, t1 = 1;
  for (int k = 0; k < 3; ++k) {
    double d = b[k] - a[k];
    if (std::fabs(d) < 1e-300) {
      if (a[k] < lo[k] || a[k] > hi[k]) return false;
      continue;
    }
    double u = (lo[k] - a[k]) / d, w = (hi[k] - a[k]) / d;
    if (u > w) std::swap(u, w);
    t0 = std::max(t0, u);
    t1 = std::min(t1, w);
    if (t0 > t1) return false;
  }
  return true;
}

}  // namespace vdbwrap
