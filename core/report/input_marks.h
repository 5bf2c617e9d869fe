// What the HTML report marks on the input: its defects triangle by triangle (the report only
// counts them) and its feature curves (sharp edges), from an exact weld of its points as the
// report's input diagnosis makes it.
#pragma once
#include <array>
#include <cstdint>
#include <vector>

#include "common/exact_weld.h"
#include "vdbwrap/mesh.h"

namespace vdbwrap::report {

enum InputDefect : uint8_t {
  kInputBorder = 1 << 0,        // an edge of the triangle has no other triangle (a hole's rim)
  kInputNonManifold = 1 << 1,   // an edge of it has more than two
  kInputMisoriented = 1 << 2,   // a neighbour across an edge faces the other way
  kInputDegenerate = 1 << 3,    // repeated or collinear corners
  kInputIntersecting = 1 << 4,  // crosses or overlaps another triangle
};

struct InputMarks {
  std::vector<uint8_t> flags;  // per input triangle, InputDefect bits
  bool intersections_searched = false;
  std::vector<std::array<Vec3, 2>> sharp_edges;  // normals more than the feature angle apart
};

// weld: the exact weld of input.points.
InputMarks mark_input(const Mesh& input, const ExactWeld& weld, double feature_angle_deg, bool find_intersections);

}  // namespace vdbwrap::report
