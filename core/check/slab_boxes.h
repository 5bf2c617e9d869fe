// Long triangles cut into slabs for the pair search. A CAD cylinder's side triangle runs its
// whole length and is a thousandth as wide; tilted, its box holds a large part of every
// neighbouring part, and it met most of their triangles there. Cut across its longest axis
// into slabs about a grid cell thick, each slab's part of it has a box of about a cell, and
// the search meets only what is near it. A pair of triangles is then met once per pair of
// their boxes that overlap; it is tested at the first such pair (met_earlier).
#pragma once
#include <cstdint>
#include <vector>

#include "check/exact_kernel.h"
#include "check/intersections_broad_phase.h"
#include "common/fill_vector.h"

namespace vdbwrap::check::pair_search {

struct SlabBoxes {
  FillVector<Bounds> boxes;
  std::vector<uint32_t> owner;  // triangle of each box
  std::vector<uint32_t> first;  // boxes of triangle t: first[t] .. first[t + 1] (none if unusable)

  uint32_t count(uint32_t t) const { return first[t + 1] - first[t]; }
};

// The slabs of every usable triangle: one box for most, up to 16 for the long ones.
SlabBoxes slab_boxes(const std::vector<P3>& p, const std::vector<Tri>& triangles, const std::vector<uint8_t>& usable);

// Boxes a of triangle x and b of triangle y overlap: did an earlier pair of their boxes (in the
// order of (a, b)) overlap too? Then that pair was the one to test. Only boxes that can reach
// the other triangle along the cut axis are looked at.
bool met_earlier(const SlabBoxes& s, const std::vector<P3>& p, const std::vector<Tri>& triangles, uint32_t x,
                 uint32_t a, uint32_t y, uint32_t b);

}  // namespace vdbwrap::check::pair_search
