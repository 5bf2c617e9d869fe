// Fuzzes the mesh readers: byte 0 picks the format (content detection, STL, OBJ, OFF, PLY),
// the rest is the file. A reader must either return a consistent mesh or throw
// vdbwrap::Error; a mesh it returns must survive every writer and read back the same.
#include <algorithm>
#include <iterator>
#include <cmath>
#include <cstdint>
#include <limits>
#include <string>
#include <string_view>
#include <vector>

#include "fuzz_check.h"
#include "vdbwrap/io.h"
#include "vdbwrap/errors.h"

using namespace vdbwrap;

namespace {

// What read_mesh_from_bytes promises about any mesh it returns (io/mesh_io.h).
void check_consistent(const Mesh& m) {
  FUZZ_CHECK(!m.triangles.empty(), "a mesh without triangles was returned");
  for (const Vec3& p : m.points)
    FUZZ_CHECK(std::isfinite(p[0]) && std::isfinite(p[1]) && std::isfinite(p[2]), "non-finite point");
  for (const Tri& t : m.triangles)
    for (uint32_t v : t) FUZZ_CHECK(v < m.points.size(), "index %u of %zu points", v, m.points.size());
  if (m.part_names.size() <= 1) {
    FUZZ_CHECK(m.triangle_part.empty(), "triangle_part filled for %zu part(s)", m.part_names.size());
    return;
  }
  FUZZ_CHECK(m.triangle_part.size() == m.triangles.size(), "%zu parts for %zu triangles", m.triangle_part.size(),
             m.triangles.size());
  std::vector<bool> used(m.part_names.size(), false);
  for (int32_t p : m.triangle_part) {
    FUZZ_CHECK(p >= 0 && size_t(p) < m.part_names.size(), "part %d of %zu", p, m.part_names.size());
    used[size_t(p)] = true;
  }
  for (size_t p = 0; p < used.size(); ++p) FUZZ_CHECK(used[p], "part %zu has no triangles", p);
}

// OBJ, OFF and PLY store doubles and the triangles as given: a round trip is exact (OBJ
// may group the faces by part, so only the set of triangles is compared there).
void check_round_trip(const Mesh& m, io::Format format) {
  const std::string bytes = io::write_mesh_to_bytes(m, format);
  Mesh back;
  try {
    back = io::read_mesh_from_bytes(bytes, format, "round trip");
  } catch (const Error& e) {
    FUZZ_CHECK(false, "format %d: written mesh does not read back: %s", int(format), e.what());
  }
  FUZZ_CHECK(back.points == m.points, "format %d: points differ after a round trip", int(format));
  std::vector<Tri> expected = m.triangles, got = back.triangles;
  if (format == io::Format::Obj) {
    std::sort(expected.begin(), expected.end());
    std::sort(got.begin(), got.end());
  }
  FUZZ_CHECK(got == expected, "format %d: triangles differ after a round trip", int(format));
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size < 1) return 0;
  // New formats go at the end: the seeds' first bytes keep their meaning.
  static const io::Format kFormats[] = {io::Format::Unknown, io::Format::Stl, io::Format::Obj,    io::Format::Off,
                                        io::Format::Ply,     io::Format::Vtp, io::Format::Nastran};
  const io::Format format = kFormats[data[0] % std::size(kFormats)];
  const std::string_view bytes(reinterpret_cast<const char*>(data) + 1, size - 1);
  Mesh mesh;
  try {
    mesh = io::read_mesh_from_bytes(bytes, format, "fuzz input");
  } catch (const Error& e) {
    FUZZ_CHECK(e.kind() == ErrorKind::InvalidInput, "reader threw kind %d: %s", int(e.kind()), e.what());
    return 0;
  }
  check_consistent(mesh);
  check_round_trip(mesh, io::Format::Obj);
  check_round_trip(mesh, io::Format::Off);
  check_round_trip(mesh, io::Format::Ply);
  check_round_trip(mesh, io::Format::Vtp);
  // Nastran's 16-character fields round the points: only the triangle count must survive.
  try {
    const Mesh back =
        io::read_mesh_from_bytes(io::write_mesh_to_bytes(mesh, io::Format::Nastran), io::Format::Nastran, "round trip");
    FUZZ_CHECK(back.triangles.size() == mesh.triangles.size(), "Nastran: %zu triangles read back of %zu",
               back.triangles.size(), mesh.triangles.size());
  } catch (const Error& e) {
    FUZZ_CHECK(false, "Nastran: written mesh does not read back: %s", e.what());
  }
  // STL stores floats: only the triangle count survives, and only for coordinates a float holds.
  const std::string stl = io::write_mesh_to_bytes(mesh, io::Format::Stl);
  bool fits_float = true;
  for (const Vec3& p : mesh.points)
    for (double c : p) fits_float = fits_float && std::fabs(c) <= double(std::numeric_limits<float>::max());
  if (fits_float) {
    try {
      Mesh back = io::read_mesh_from_bytes(stl, io::Format::Stl, "round trip");
      FUZZ_CHECK(back.triangles.size() == mesh.triangles.size(), "STL round trip: %zu triangles for %zu",
                 back.triangles.size(), mesh.triangles.size());
    } catch (const Error& e) {
      FUZZ_CHECK(false, "written STL does not read back: %s", e.what());
    }
  }
  return 0;
}
