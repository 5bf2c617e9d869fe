#include "mesh/segment_grid.h"

#include <algorithm>
#include <cmath>

namespace vdbwrap::mesh {
namespace {

// Steps of a quarter cell along the segments, in all, that the grid is sized for.
constexpr size_t kMostSteps = size_t(1) << 20;

double widened(double cell, double width, double total_length, size_t count) {
  const double most_steps = double(std::max<size_t>(kMostSteps, 8 * count));
  return std::max({cell, 4 * width, 4 * total_length / most_steps});
}

}  // namespace

SegmentGrid::SegmentGrid(double cell, double width, double total_length, size_t count)
    : cell_(widened(cell, width, total_length, count)), width_(width), grid_(cell_) {}

void SegmentGrid::add(uint32_t i, const Vec3& a, const Vec3& b) {
  if (segments_.size() <= i) segments_.resize(size_t(i) + 1);
  segments_[i] = {a, b};
  // In steps of a quarter cell, each step's box (at most two cells a side) holds its piece.
  const size_t steps = std::max<size_t>(1, size_t(std::ceil(4 * norm(b - a) / cell_)));
  for (size_t s = 0; s < steps; ++s) {
    const Vec3 p = lerp(a, b, double(s) / double(steps)), q = lerp(a, b, double(s + 1) / double(steps));
    const GridKey lo = grid_.cell_of(Vec3{std::min(p[0], q[0]), std::min(p[1], q[1]), std::min(p[2], q[2])});
    const GridKey hi = grid_.cell_of(Vec3{std::max(p[0], q[0]), std::max(p[1], q[1]), std::max(p[2], q[2])});
    CellLists<uint32_t>::for_cells(lo, hi, [&](const GridKey& k) {
      std::vector<uint32_t>& list = grid_[k];
      if (list.empty() || list.back() != i) list.push_back(i);  // a segment's steps come one after another
    });
  }
}

}  // namespace vdbwrap::mesh
