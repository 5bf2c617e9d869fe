// The triangle mesh that flows through every stage of vdbwrap.
#pragma once
#include <array>
#include <cstdint>
#include <string>
#include <vector>

namespace vdbwrap {

using Vec3 = std::array<double, 3>;
using Tri = std::array<uint32_t, 3>;

// An indexed triangle mesh with optional named parts (STL solids, OBJ groups).
// triangle_part is either empty (everything is part 0) or one entry per triangle,
// indexing part_names.
struct Mesh {
  std::vector<Vec3> points;
  std::vector<Tri> triangles;
  std::vector<int32_t> triangle_part;
  std::vector<std::string> part_names;
  // What reading the file had to assume, in words for the user (a binary STL whose declared
  // count disagrees with the records it holds); empty for a file read as it says.
  std::vector<std::string> notes;

  int32_t part_of(size_t t) const { return triangle_part.empty() ? 0 : triangle_part[t]; }
};

}  // namespace vdbwrap
