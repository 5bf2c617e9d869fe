// Wavefront OBJ: positions, faces (any polygon) and o/g groups as parts. A line ending in a
// backslash continues on the next, as the OBJ specification allows (long faces are split so).
#include <unordered_map>

#include "io/readers.h"

namespace vdbwrap::io::detail {
namespace {

class ObjReader {
 public:
  ObjReader(std::string_view text, const std::string& name) : lines_(text), name_(name) {}

  Mesh read() {
    std::string_view line;
    while (lines_.next(line)) {
      first_line_ = lines_.line_number();
      if (!continued(line)) {
        handle(line);
        continue;
      }
      joined_.assign(line);
      bool more = true;
      while (more && lines_.next(line)) {
        more = continued(line);
        joined_ += ' ';
        joined_.append(line);
      }
      handle(joined_);
    }
    return std::move(mesh_);
  }

 private:
  // Errors name the line where the statement starts (a continued one spans several).
  [[noreturn]] void error(const std::string& what) { fail_line(name_, first_line_, what); }

  // Does the line end in a continuation backslash? If so, drops it from `line`. Comments never
  // continue: a Windows path at the end of one must not swallow the next statement.
  static bool continued(std::string_view& line) {
    size_t end = line.size();
    while (end > 0 && is_space(line[end - 1])) --end;
    if (end == 0 || line[end - 1] != '\\') return false;
    size_t start = 0;
    while (start < end && is_space(line[start])) ++start;
    if (line[start] == '#') return false;
    line = line.substr(0, end - 1);
    return true;
  }

  void handle(std::string_view line) {
    Tokens tokens(line);
    std::string_view keyword;
    if (!tokens.next(keyword)) return;
    if (keyword == "v") return add_vertex(tokens);
    if (keyword == "f") return add_face(tokens);
    if (keyword == "g" || keyword == "o") return begin_group(tokens.rest());
    // Everything else (vt, vn, usemtl, mtllib, s, l, comments...) carries no geometry we use.
  }

  void add_vertex(Tokens& tokens) {
    Vec3 p;
    std::string_view token;
    for (int c = 0; c < 3; ++c) {
      if (!tokens.next(token)) error("vertex needs 3 coordinates");
      if (!parse_double(token, p[c])) error("malformed number " + quoted(token));
    }
    // Extra values (w, or r g b vertex colours) are ignored.
    if (!is_finite(p)) error("vertex " + std::to_string(mesh_.points.size() + 1) + " has a non-finite coordinate");
    check_point_count(name_, mesh_.points.size() + 1);
    mesh_.points.push_back(p);
  }

  // "12", "12/3", "12//7", "12/3/7" or negative (relative to the vertices read so far).
  uint32_t face_index(std::string_view token) {
    std::string_view number = token.substr(0, token.find('/'));
    int64_t value = 0;
    if (!parse_int(number, value)) error("malformed face index " + quoted(token));
    const int64_t count = int64_t(mesh_.points.size());
    int64_t index = value > 0 ? value - 1 : count + value;
    if (value == 0 || index < 0 || index >= count)
      error("face index " + std::to_string(value) + " is out of range (" + std::to_string(count) +
            " vertices defined so far)");
    return uint32_t(index);
  }

  void add_face(Tokens& tokens) {
    polygon_.clear();
    std::string_view token;
    while (tokens.next(token)) polygon_.push_back(face_index(token));
    if (polygon_.size() < 3) error("face has " + std::to_string(polygon_.size()) + " vertices (needs at least 3)");
    if (part_ < 0) part_ = part_for(group_);
    triangulator_.run(mesh_.points, polygon_.data(), polygon_.size(), mesh_.triangles);
    mesh_.triangle_part.resize(mesh_.triangles.size(), part_);
  }

  void begin_group(std::string_view group) {
    group_ = group.empty() ? "default" : std::string(group);
    part_ = -1;  // the part is created by the group's first face
  }

  // Same name, same part: a group may be reopened later in the file.
  int32_t part_for(const std::string& group) {
    auto [it, inserted] = part_index_.emplace(group, int32_t(mesh_.part_names.size()));
    if (inserted) mesh_.part_names.push_back(group);
    return it->second;
  }

  LineReader lines_;
  size_t first_line_ = 0;
  std::string joined_;  // a statement continued over several lines
  const std::string& name_;
  Mesh mesh_;
  std::string group_ = "default";
  int32_t part_ = -1;
  std::unordered_map<std::string, int32_t> part_index_;
  std::vector<uint32_t> polygon_;
  PolygonTriangulator triangulator_;
};

}  // namespace

Mesh read_obj(std::string_view bytes, const std::string& name) { return ObjReader(bytes, name).read(); }

// Vertices, then faces grouped by part: each part's "g" line appears once (readers that make
// one group per "g" line would otherwise split a part), in part order; within a part the
// faces keep their order.
void write_obj(const Mesh& mesh, Sink& out) {
  out.put("# written by vdbwrap\n");
  for (const Vec3& p : mesh.points) {
    out.put('v');
    for (double c : p) {
      out.put(' ');
      out.put_real(c);
    }
    out.put('\n');
  }
  auto put_face = [&](const Tri& tri) {
    out.put('f');
    for (uint32_t v : tri) {
      out.put(' ');
      out.put_uint(uint64_t(v) + 1);
    }
    out.put('\n');
  };
  if (mesh.part_names.empty()) {
    for (const Tri& tri : mesh.triangles) put_face(tri);
    return;
  }
  // Counting sort by part: stable, linear.
  std::vector<size_t> start(mesh.part_names.size() + 1, 0);
  for (size_t t = 0; t < mesh.triangles.size(); ++t) ++start[size_t(mesh.part_of(t)) + 1];
  for (size_t p = 1; p < start.size(); ++p) start[p] += start[p - 1];
  std::vector<uint32_t> order(mesh.triangles.size());
  std::vector<size_t> next(start.begin(), start.end() - 1);
  for (size_t t = 0; t < mesh.triangles.size(); ++t) order[next[size_t(mesh.part_of(t))]++] = uint32_t(t);
  for (size_t p = 0; p < mesh.part_names.size(); ++p) {
    if (start[p] == start[p + 1]) continue;  // a part without faces makes no group
    std::string group = one_line(mesh.part_names[p]);
    // A name ending in a backslash would continue the group line onto the next statement.
    while (!group.empty() && (group.back() == ' ' || group.back() == '\t')) group.pop_back();
    if (!group.empty() && group.back() == '\\') group.back() = '/';
    out.put("g " + (group.empty() ? std::string("default") : group) + "\n");
    for (size_t i = start[p]; i < start[p + 1]; ++i) put_face(mesh.triangles[order[i]]);
  }
}

}  // namespace vdbwrap::io::detail
