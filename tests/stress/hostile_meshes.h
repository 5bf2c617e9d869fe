// Hostile meshes for the stress test (issue 33, "never crash, on any input"): the kinds of dirt
// real exports carry (degenerate and duplicated triangles, non-manifold fans, T-junctions,
// intersecting CSG solids, open scans, extreme coordinates, unreadable files), each as the bytes
// of a file in a format the CLI reads. Deterministic for a given (kind, scale, seed).
#pragma once
#include <cstdint>
#include <string>
#include <vector>

#include "vdbwrap/mesh.h"

namespace vdbwrap::stress {

struct HostileMesh {
  std::string kind;                // the class, e.g. "csg_intersecting"
  std::string file_name;           // KIND_sSCALE_SEED.EXT; the extension gives the format
  std::string bytes;               // the file as written
  Vec3 seed_point{0, 0, 0};        // a material point: inside a solid where the mesh has one
  std::vector<std::string> parts;  // part names the file carries (OBJ groups, PLY part values)
  // The reader must refuse the file (exit 3, one line naming the file and `refusal_word`).
  bool must_be_refused = false;
  std::string refusal_word;
  size_t triangles = 0;  // as generated (before any reader)
};

// Every kind the generator makes, in a fixed order.
const std::vector<std::string>& hostile_kinds();

// One mesh of `kind`; `scale` (1..16) multiplies the tessellation, `seed` picks the dirt.
// Throws std::invalid_argument for an unknown kind.
HostileMesh make_hostile(const std::string& kind, int scale, uint32_t seed);

// Binary STL of a mesh (one solid; part names are not kept). Coordinates are rounded to float.
std::string binary_stl_bytes(const Mesh& mesh);

}  // namespace vdbwrap::stress
