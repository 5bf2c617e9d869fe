// STL, binary and ASCII. Readers do not weld: every facet adds its own three points.
#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdint>

#include <tbb/parallel_for.h>

#include "io/readers.h"

namespace vdbwrap::io::detail {
namespace {

constexpr size_t kHeaderBytes = 84;  // 80-byte header + uint32 triangle count
constexpr size_t kRecordBytes = 50;  // normal, 3 corners (12 floats) + uint16 attribute

uint64_t declared_count(std::string_view bytes) { return load<uint32_t>(bytes.data() + 80, true); }

// ---- binary -------------------------------------------------------------------------------

[[noreturn]] void fail_binary_size(std::string_view bytes, const std::string& name) {
  if (bytes.size() < kHeaderBytes)
    fail(name, "binary STL is truncated: " + std::to_string(bytes.size()) + " bytes, shorter than the 84-byte header");
  uint64_t count = declared_count(bytes);
  uint64_t needed = kHeaderBytes + kRecordBytes * count;
  fail(name, "binary STL declares " + std::to_string(count) + " triangles (needs " + std::to_string(needed) +
                 " bytes) but the file has " + std::to_string(bytes.size()) + " bytes (" +
                 (bytes.size() < needed ? "truncated" : "too long") + ")");
}

// `count` records, validated against the file's size by the caller.
Mesh read_binary_stl(std::string_view bytes, const std::string& name, size_t count) {
  check_point_count(name, uint64_t(count) * 3);
  Mesh mesh;
  mesh.points.resize(count * 3);
  mesh.triangles.resize(count);
  // Records parsed in parallel chunks; the first triangle (in file order) with a non-finite
  // coordinate is the one reported.
  std::atomic<size_t> first_bad{SIZE_MAX};
  tbb::parallel_for(tbb::blocked_range<size_t>(0, count, 16384), [&](const tbb::blocked_range<size_t>& r) {
    const char* record = bytes.data() + kHeaderBytes + r.begin() * kRecordBytes;
    for (size_t t = r.begin(); t != r.end(); ++t, record += kRecordBytes) {
      for (size_t k = 0; k < 3; ++k) {
        Vec3& p = mesh.points[3 * t + k];
        for (size_t c = 0; c < 3; ++c) p[c] = load<float>(record + 12 + 12 * k + 4 * c, true);
        if (!is_finite(p)) {
          size_t seen = first_bad.load();
          while (t < seen && !first_bad.compare_exchange_weak(seen, t)) {
          }
        }
      }
      const uint32_t base = uint32_t(3 * t);
      mesh.triangles[t] = {base, base + 1, base + 2};
    }
  });
  if (first_bad.load() != SIZE_MAX)
    fail(name, "triangle " + std::to_string(first_bad.load()) + " has a non-finite coordinate");
  mesh.part_names.push_back(file_stem(name));
  return mesh;
}

// ---- ASCII --------------------------------------------------------------------------------

// Line-by-line reader for "solid / facet normal / outer loop / vertex x3 / endloop / endfacet /
// endsolid". Facet normals are ignored (exporters write "nan" normals for degenerate facets).
class AsciiStlReader {
 public:
  AsciiStlReader(std::string_view text, const std::string& name) : lines_(text), name_(name) {}

  Mesh read() {
    std::string_view line;
    while (lines_.next(line)) handle(line);
    if (corners_ >= 0)
      fail_line(name_, lines_.line_number(),
                "file ends inside the facet that starts at line " + std::to_string(facet_line_) + " (truncated)");
    return std::move(mesh_);
  }

 private:
  [[noreturn]] void error(const std::string& what) { fail_line(name_, lines_.line_number(), what); }

  void handle(std::string_view line) {
    Tokens tokens(line);
    std::string_view keyword;
    if (!tokens.next(keyword)) return;  // blank line
    if (iequals(keyword, "vertex")) return add_corner(tokens);
    if (iequals(keyword, "facet")) return begin_facet();
    if (iequals(keyword, "outer") || iequals(keyword, "endloop")) return require_facet(keyword);
    if (iequals(keyword, "endfacet")) return end_facet();
    if (iequals(keyword, "solid")) return begin_solid(tokens.rest());
    if (iequals(keyword, "endsolid")) return end_solid();
    error("unexpected " + quoted(keyword) + " in an ASCII STL");
  }

  void begin_solid(std::string_view solid_name) {
    if (corners_ >= 0) error("'solid' inside an unfinished facet");
    ++solid_ordinal_;
    in_solid_ = true;
    part_ = -1;  // created on the first facet: empty solids make no part
    solid_name_ = solid_name.empty() ? "solid" + std::to_string(solid_ordinal_) : std::string(solid_name);
  }

  void end_solid() {
    if (corners_ >= 0) error("'endsolid' inside an unfinished facet");
    in_solid_ = false;
  }

  void begin_facet() {
    if (!in_solid_) error("'facet' outside a solid");
    if (corners_ >= 0) error("'facet' before the facet of line " + std::to_string(facet_line_) + " ended");
    corners_ = 0;
    facet_line_ = lines_.line_number();
  }

  void require_facet(std::string_view keyword) {
    if (corners_ < 0) error(quoted(keyword) + " outside a facet");
  }

  void add_corner(Tokens& tokens) {
    require_facet("vertex");
    if (corners_ == 3) error("facet has more than 3 vertices");
    Vec3& p = corner_[corners_];
    std::string_view token;
    for (int c = 0; c < 3; ++c) {
      if (!tokens.next(token)) error("vertex needs 3 coordinates");
      if (!parse_double(token, p[c])) error("malformed number " + quoted(token));
    }
    if (tokens.next(token)) error("unexpected " + quoted(token) + " after the 3 vertex coordinates");
    if (!is_finite(p))
      error("vertex " + std::to_string(corners_ + 1) + " of facet " + std::to_string(mesh_.triangles.size()) +
            " has a non-finite coordinate");
    ++corners_;
  }

  void end_facet() {
    require_facet("endfacet");
    if (corners_ != 3) error("facet has " + std::to_string(corners_) + " vertices (needs 3)");
    corners_ = -1;
    check_point_count(name_, mesh_.points.size() + 3);
    uint32_t base = uint32_t(mesh_.points.size());
    mesh_.points.insert(mesh_.points.end(), corner_, corner_ + 3);
    mesh_.triangles.push_back({base, base + 1, base + 2});
    if (part_ < 0) {
      part_ = int32_t(mesh_.part_names.size());
      mesh_.part_names.push_back(solid_name_);
    }
    mesh_.triangle_part.push_back(part_);
  }

  LineReader lines_;
  const std::string& name_;
  Mesh mesh_;
  int solid_ordinal_ = 0;
  bool in_solid_ = false;
  std::string solid_name_;
  int32_t part_ = -1;
  int corners_ = -1;  // corners read in the current facet; -1 outside a facet
  size_t facet_line_ = 0;
  Vec3 corner_[3];
};

// ---- writers ------------------------------------------------------------------------------

Vec3 unit_normal(const Vec3& a, const Vec3& b, const Vec3& c) {
  Vec3 u{b[0] - a[0], b[1] - a[1], b[2] - a[2]}, v{c[0] - a[0], c[1] - a[1], c[2] - a[2]};
  Vec3 n{u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]};
  double len = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
  if (!(len > 0) || !std::isfinite(len)) return {0, 0, 0};
  return {n[0] / len, n[1] / len, n[2] / len};
}

void write_binary_stl(const Mesh& mesh, Sink& out) {
  char header[kHeaderBytes] = {};
  // Must not start with "solid", or readers could take it for ASCII.
  const char title[] = "binary STL written by vdbwrap";
  std::memcpy(header, title, sizeof title - 1);
  store_le<uint32_t>(header + 80, uint32_t(mesh.triangles.size()));
  out.put_bytes(header, sizeof header);
  char record[kRecordBytes] = {};
  for (const Tri& t : mesh.triangles) {
    const Vec3& a = mesh.points[t[0]];
    const Vec3& b = mesh.points[t[1]];
    const Vec3& c = mesh.points[t[2]];
    const Vec3 vecs[4] = {unit_normal(a, b, c), a, b, c};
    for (int v = 0; v < 4; ++v)
      for (int k = 0; k < 3; ++k) store_le<float>(record + 12 * v + 4 * k, float(vecs[v][k]));
    out.put_bytes(record, sizeof record);
  }
}

void put_vec(Sink& out, const Vec3& v) {
  for (int k = 0; k < 3; ++k) {
    out.put(' ');
    out.put_real(v[k]);
  }
}

void write_ascii_facet(const Mesh& mesh, const Tri& t, Sink& out) {
  const Vec3& a = mesh.points[t[0]];
  const Vec3& b = mesh.points[t[1]];
  const Vec3& c = mesh.points[t[2]];
  out.put("  facet normal");
  put_vec(out, unit_normal(a, b, c));
  out.put("\n    outer loop\n");
  for (const Vec3* p : {&a, &b, &c}) {
    out.put("      vertex");
    put_vec(out, *p);
    out.put('\n');
  }
  out.put("    endloop\n  endfacet\n");
}

// One solid per part, in part order (a triangle order that interleaves parts is not kept).
// A single part keeps its name; a mesh without parts is one unnamed solid.
void write_ascii_stl(const Mesh& mesh, Sink& out) {
  std::vector<std::vector<uint32_t>> by_part(std::max<size_t>(mesh.part_names.size(), 1));
  for (size_t t = 0; t < mesh.triangles.size(); ++t) by_part[mesh.part_of(t)].push_back(uint32_t(t));
  for (size_t p = 0; p < by_part.size(); ++p) {
    if (by_part[p].empty()) continue;
    std::string solid = p < mesh.part_names.size() ? one_line(mesh.part_names[p]) : "";
    out.put(solid.empty() ? std::string("solid\n") : "solid " + solid + "\n");
    for (uint32_t t : by_part[p]) write_ascii_facet(mesh, mesh.triangles[t], out);
    out.put(solid.empty() ? std::string("endsolid\n") : "endsolid " + solid + "\n");
  }
}

}  // namespace

bool is_binary_stl_size(std::string_view bytes) {
  return bytes.size() >= kHeaderBytes && bytes.size() == kHeaderBytes + kRecordBytes * declared_count(bytes);
}

// "solid" after optional whitespace, and text: no NUL byte anywhere (binary STL nearly always
// has some, e.g. in its count or in 0.0f coordinates) and no control bytes at the start.
bool looks_like_ascii_stl(std::string_view bytes) {
  std::string_view head = trim(bytes.substr(0, 512));
  if (head.substr(0, 5) != "solid" && !iequals(head.substr(0, 5), "solid")) return false;
  if (std::memchr(bytes.data(), '\0', bytes.size())) return false;
  for (char c : bytes.substr(0, 4096)) {
    unsigned char u = static_cast<unsigned char>(c);
    if (u < 32 && c != '\n' && !is_space(c)) return false;
  }
  return true;
}

Mesh read_stl(std::string_view bytes, const std::string& name) {
  if (is_binary_stl_size(bytes)) return read_binary_stl(bytes, name, size_t(declared_count(bytes)));
  if (looks_like_ascii_stl(bytes)) return AsciiStlReader(bytes, name).read();
  // More whole records after the header than it declares: a writer that left the count at 0
  // or stale. The records the file holds are read (as slicers do), and the user is told. Fewer
  // than declared is a cut file, and bytes past the last whole record are no record: errors.
  const size_t held = bytes.size() > kHeaderBytes ? (bytes.size() - kHeaderBytes) / kRecordBytes : 0;
  if (held > 0 && held > declared_count(bytes) && (bytes.size() - kHeaderBytes) % kRecordBytes == 0) {
    Mesh mesh = read_binary_stl(bytes, name, held);
    mesh.notes.push_back(name + ": binary STL declares " + std::to_string(declared_count(bytes)) +
                         " triangles but holds " + std::to_string(held) + " whole records: read all " +
                         std::to_string(held));
    return mesh;
  }
  fail_binary_size(bytes, name);
}

void write_stl(const Mesh& mesh, Sink& out, bool ascii) {
  if (ascii)
    write_ascii_stl(mesh, out);
  else
    write_binary_stl(mesh, out);
}

}  // namespace vdbwrap::io::detail
