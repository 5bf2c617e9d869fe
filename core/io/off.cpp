// OFF (Object File Format), ASCII: "OFF" keyword, counts "V F E", V vertex lines, F face lines.
// Vertex and face lines may carry extra values (colours, COFF/NOFF/STOFF), which are ignored.
#include <algorithm>

#include "io/readers.h"

namespace vdbwrap::io::detail {
namespace {

class OffReader {
 public:
  OffReader(std::string_view text, const std::string& name) : lines_(text), name_(name), total_(text.size()) {}

  Mesh read() {
    read_header();
    read_vertices();
    read_faces();
    std::string_view extra;
    if (next_data_line(extra))
      error("more data than the " + std::to_string(vertex_count_) + " vertices and " + std::to_string(face_count_) +
            " faces the counts line declares");
    return std::move(mesh_);
  }

 private:
  [[noreturn]] void error(const std::string& what) { fail_line(name_, lines_.line_number(), what); }

  // Next line with content, comments ('#' to end of line) removed.
  bool next_data_line(std::string_view& line) {
    while (lines_.next(line)) {
      line = trim(line.substr(0, line.find('#')));
      if (!line.empty()) return true;
    }
    return false;
  }

  // The keyword line is optional; the counts may follow the keyword on the same line.
  void read_header() {
    std::string_view line;
    if (!next_data_line(line)) fail(name_, "OFF file has no counts line");
    Tokens tokens(line);
    std::string_view first;
    tokens.next(first);
    if (is_keyword(first)) {
      std::string_view rest = tokens.rest();
      if (rest.substr(0, 6) == "BINARY") error("binary OFF is not supported");
      if (rest.empty() && !next_data_line(line)) fail(name_, "OFF file has no counts line");
      if (!rest.empty()) line = rest;
    }
    read_counts(line);
  }

  // "OFF" with the optional ST (texture), C (colour), N (normal) prefixes we can skip over.
  bool is_keyword(std::string_view token) {
    if (token.size() < 3 || !iequals(token.substr(token.size() - 3), "OFF")) return false;
    std::string_view prefix = token.substr(0, token.size() - 3);
    if (prefix.find_first_of("4n") != std::string_view::npos)
      error(quoted(token) + " (4D or n-dimensional OFF) is not supported");
    if (prefix.find_first_not_of("STCN") != std::string_view::npos) error("unknown OFF keyword " + quoted(token));
    return true;
  }

  void read_counts(std::string_view line) {
    Tokens tokens(line);
    std::string_view v, f;
    int64_t nv = -1, nf = -1;
    if (!tokens.next(v) || !tokens.next(f) || !parse_int(v, nv) || !parse_int(f, nf) || nv < 0 || nf < 0)
      error("expected the counts line \"VERTICES FACES [EDGES]\", got " + quoted(line));
    vertex_count_ = uint64_t(nv);
    face_count_ = uint64_t(nf);
    check_point_count(name_, vertex_count_);
    // Reserve no more than the file could hold ("0 0 0\n" = 6 bytes, "3 0 1 2\n" = 8).
    mesh_.points.reserve(size_t(std::min<uint64_t>(vertex_count_, total_ / 6)));
    mesh_.triangles.reserve(size_t(std::min<uint64_t>(face_count_, total_ / 8)));
  }

  void read_vertices() {
    std::string_view line, token;
    for (uint64_t i = 0; i < vertex_count_; ++i) {
      if (!next_data_line(line))
        fail(name_, "truncated: the counts line declares " + std::to_string(vertex_count_) +
                        " vertices, the file has " + std::to_string(i));
      Tokens tokens(line);
      Vec3 p;
      for (int c = 0; c < 3; ++c) {
        if (!tokens.next(token)) error("vertex " + std::to_string(i) + " needs 3 coordinates");
        if (!parse_double(token, p[c])) error("malformed number " + quoted(token));
      }
      if (!is_finite(p)) error("vertex " + std::to_string(i) + " has a non-finite coordinate");
      mesh_.points.push_back(p);
    }
  }

  void read_faces() {
    std::string_view line;
    for (uint64_t i = 0; i < face_count_; ++i) {
      if (!next_data_line(line))
        fail(name_, "truncated: the counts line declares " + std::to_string(face_count_) + " faces, the file has " +
                        std::to_string(i));
      read_face(i, line);
    }
  }

  void read_face(uint64_t face, std::string_view line) {
    const std::string label = "face " + std::to_string(face);
    Tokens tokens(line);
    std::string_view token;
    int64_t n = 0;
    if (!tokens.next(token) || !parse_int(token, n)) error(label + ": malformed vertex count " + quoted(token));
    if (n < 3) error(label + " has " + std::to_string(n) + " vertices (needs at least 3)");
    polygon_.clear();
    for (int64_t k = 0; k < n; ++k) {
      int64_t index = 0;
      if (!tokens.next(token))
        error(label + " lists " + std::to_string(k) + " of its " + std::to_string(n) + " vertices");
      if (!parse_int(token, index)) error(label + ": malformed vertex index " + quoted(token));
      if (index < 0 || uint64_t(index) >= vertex_count_)
        error(label + " has out-of-range vertex index " + std::to_string(index) + " (the file has " +
              std::to_string(vertex_count_) + " vertices)");
      polygon_.push_back(uint32_t(index));
    }
    triangulator_.run(mesh_.points, polygon_.data(), polygon_.size(), mesh_.triangles);
  }

  LineReader lines_;
  const std::string& name_;
  uint64_t total_;  // file size, bounds what the counts may reserve
  Mesh mesh_;
  uint64_t vertex_count_ = 0, face_count_ = 0;
  std::vector<uint32_t> polygon_;
  PolygonTriangulator triangulator_;
};

}  // namespace

Mesh read_off(std::string_view bytes, const std::string& name) { return OffReader(bytes, name).read(); }

void write_off(const Mesh& mesh, Sink& out) {
  out.put("OFF\n");
  out.put_uint(mesh.points.size());
  out.put(' ');
  out.put_uint(mesh.triangles.size());
  out.put(" 0\n");
  for (const Vec3& p : mesh.points) {
    out.put_real(p[0]);
    out.put(' ');
    out.put_real(p[1]);
    out.put(' ');
    out.put_real(p[2]);
    out.put('\n');
  }
  for (const Tri& t : mesh.triangles) {
    out.put('3');
    for (uint32_t v : t) {
      out.put(' ');
      out.put_uint(v);
    }
    out.put('\n');
  }
}

}  // namespace vdbwrap::io::detail
