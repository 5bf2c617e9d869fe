// Line segments looked up by the grid cells they pass through: which segments run beside a
// point (its foot on them within their ends, within a width). Bundled feature lines and the
// two sides of a crack are found this way.
#pragma once
#include <array>
#include <cmath>
#include <cstdint>
#include <vector>

#include "common/cell_lists.h"
#include "common/vec.h"

namespace vdbwrap::mesh {

class SegmentGrid {
 public:
  // `cell`: the side wanted (a few widths or more; a base cell suits). It widens where the
  // segments, `total_length` long in all, would take over a million quarter-cell steps (a comb
  // of long rods' edges at a base cell), and is at least four `width`s.
  SegmentGrid(double cell, double width, double total_length, size_t count);

  // Lists segment i (each index once, in any order).
  void add(uint32_t i, const Vec3& a, const Vec3& b);
  const std::array<Vec3, 2>& segment(uint32_t i) const { return segments_[i]; }

  // Whether segment i runs beside p: p's foot on it within its ends and within the width of p.
  bool passes_beside(uint32_t i, const Vec3& p) const {
    const Vec3 d = foot(i, p) - p;
    return norm2(d) <= width_ * width_;
  }

  // Calls near(j, d) for each listed segment j but `self` whose point nearest p lies within
  // its ends and within the width of p (d: from p to that point), until one returns true;
  // whether one did.
  template <typename Near>
  bool beside(const Vec3& p, uint32_t self, Near&& near) const {
    const Vec3 r{width_, width_, width_};
    return CellLists<uint32_t>::for_cells(grid_.cell_of(p - r), grid_.cell_of(p + r), [&](const GridKey& k) {
      const std::vector<uint32_t>* list = grid_.find(k);
      if (!list) return false;
      for (uint32_t j : *list) {
        if (j == self) continue;
        const Vec3 d = foot(j, p) - p;
        if (norm2(d) <= width_ * width_ && near(j, d)) return true;
      }
      return false;
    });
  }

 private:
  // p's foot on segment i; infinitely far when it falls beyond the ends (beside p, not on from
  // it: the next piece of the same line ends within the width of p too).
  Vec3 foot(uint32_t i, const Vec3& p) const {
    const Vec3 &a = segments_[i][0], ab = segments_[i][1] - a;
    const double at = dot(p - a, ab);
    if (!(at >= 0 && at <= norm2(ab))) return Vec3{INFINITY, INFINITY, INFINITY};
    return a + ab * (at / norm2(ab));
  }

  double cell_, width_;
  CellLists<uint32_t> grid_;
  std::vector<std::array<Vec3, 2>> segments_;
};

}  // namespace vdbwrap::mesh
