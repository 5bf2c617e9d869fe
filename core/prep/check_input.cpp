#include "prep/check_input.h"

#include <cmath>
#include <cstdio>
#include <string>

#include "vdbwrap/errors.h"

namespace vdbwrap::prep {

void check_input_mesh(const Mesh& mesh, const char* what) {
  auto bad = [&](const std::string& m) { throw Error(ErrorKind::InvalidInput, std::string(what) + ": " + m); };
  if (mesh.triangles.empty()) bad("contains no triangles");
  for (size_t i = 0; i < mesh.points.size(); ++i) {
    const Vec3& p = mesh.points[i];
    for (double c : p) {
      if (!std::isfinite(c)) bad("vertex " + std::to_string(i) + " has a non-finite coordinate");
      if (std::fabs(c) > kMaxCoordinate) {
        char value[32];
        std::snprintf(value, sizeof value, "%.3g", c);
        bad("vertex " + std::to_string(i) + " has the coordinate " + value +
            ", beyond the supported magnitude of 1e15 (rescale the model)");
      }
    }
  }
  const size_t n = mesh.points.size();
  for (size_t t = 0; t < mesh.triangles.size(); ++t)
    for (uint32_t v : mesh.triangles[t])
      if (v >= n)
        bad("triangle " + std::to_string(t) + " refers to vertex " + std::to_string(v) + " of " + std::to_string(n));
  if (!mesh.triangle_part.empty()) {
    if (mesh.triangle_part.size() != mesh.triangles.size())
      bad("has " + std::to_string(mesh.triangle_part.size()) + " part entries for " +
          std::to_string(mesh.triangles.size()) + " triangles");
    for (size_t t = 0; t < mesh.triangle_part.size(); ++t) {
      const int32_t part = mesh.triangle_part[t];
      if (part < 0 || (!mesh.part_names.empty() && size_t(part) >= mesh.part_names.size()))
        bad("triangle " + std::to_string(t) + " is in part " + std::to_string(part) + ", which has no name");
    }
  }
}

}  // namespace vdbwrap::prep
