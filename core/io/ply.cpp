// PLY: ascii, binary_little_endian and binary_big_endian. Reads vertex x/y/z, face
// vertex_indices (or vertex_index) and an optional integer face property "part", and triangle
// strips (element "tristrips", as many scanned models in the Stanford repository are stored);
// skips the rest unless asked for the other scalar vertex and face properties (MeshData).
// Part names survive a round trip through "comment vdbwrap_part INDEX NAME" header lines.
#include <algorithm>
#include <initializer_list>
#include <unordered_map>

#include "io/readers.h"
#include "io/scalar_type.h"

namespace vdbwrap::io::detail {
namespace {

using Type = ScalarType;

struct Property {
  std::string name;
  bool is_list = false;
  Type count_type = Type::U8;  // lists only
  Type type = Type::F32;       // the value, or a list's items
};

struct Element {
  std::string name;
  uint64_t count = 0;
  std::vector<Property> props;
  size_t header_line = 0;
};

enum class Encoding { Ascii, BinaryLittle, BinaryBig };

struct Header {
  Encoding encoding = Encoding::Ascii;
  std::vector<Element> elements;
  std::unordered_map<int64_t, std::string> part_names;  // from "comment vdbwrap_part" lines
  size_t body_offset = 0;
  size_t body_line = 0;  // line number of the last header line
};

bool parse_type(std::string_view s, Type& t) {
  static const std::pair<const char*, Type> kNames[] = {
      {"char", Type::I8},     {"int8", Type::I8},    {"uchar", Type::U8},   {"uint8", Type::U8},   {"short", Type::I16},
      {"int16", Type::I16},   {"ushort", Type::U16}, {"uint16", Type::U16}, {"int", Type::I32},    {"int32", Type::I32},
      {"uint", Type::U32},    {"uint32", Type::U32}, {"int64", Type::I64},  {"uint64", Type::U64}, {"float", Type::F32},
      {"float32", Type::F32}, {"double", Type::F64}, {"float64", Type::F64}};
  for (const auto& [n, type] : kNames)
    if (s == n) {
      t = type;
      return true;
    }
  return false;
}

// ---- header -------------------------------------------------------------------------------

class HeaderParser {
 public:
  HeaderParser(std::string_view bytes, const std::string& name) : lines_(bytes), name_(name) {}

  Header parse() {
    std::string_view line;
    if (!lines_.next(line) || trim(line) != "ply") fail(name_, "not a PLY file (no 'ply' first line)");
    while (lines_.next(line)) {
      Tokens tokens(line);
      std::string_view keyword;
      if (!tokens.next(keyword)) continue;
      if (keyword == "end_header") {
        header_.body_offset = lines_.offset();
        header_.body_line = lines_.line_number();
        return std::move(header_);
      }
      handle(keyword, tokens);
    }
    fail(name_, "PLY header has no end_header line (truncated)");
  }

 private:
  [[noreturn]] void error(const std::string& what) { fail_line(name_, lines_.line_number(), what); }

  void handle(std::string_view keyword, Tokens& tokens) {
    if (keyword == "format") return format(tokens);
    if (keyword == "element") return element(tokens);
    if (keyword == "property") return property(tokens);
    if (keyword == "comment") return comment(tokens);
    if (keyword == "obj_info") return;
    error("unexpected PLY header line starting with " + quoted(keyword));
  }

  void format(Tokens& tokens) {
    std::string_view f;
    tokens.next(f);
    if (f == "ascii")
      header_.encoding = Encoding::Ascii;
    else if (f == "binary_little_endian")
      header_.encoding = Encoding::BinaryLittle;
    else if (f == "binary_big_endian")
      header_.encoding = Encoding::BinaryBig;
    else
      error("unsupported PLY format " + quoted(f));
  }

  void element(Tokens& tokens) {
    std::string_view name, count;
    Element e;
    if (!tokens.next(name) || !tokens.next(count)) error("element line needs a name and a count");
    int64_t n = -1;
    if (!parse_int(count, n) || n < 0) error("malformed element count " + quoted(count));
    e.name = std::string(name);
    e.count = uint64_t(n);
    e.header_line = lines_.line_number();
    header_.elements.push_back(std::move(e));
  }

  void property(Tokens& tokens) {
    if (header_.elements.empty()) error("property before any element");
    Property p;
    std::string_view word;
    tokens.next(word);
    if (word == "list") {
      p.is_list = true;
      if (!tokens.next(word) || !parse_type(word, p.count_type)) error("unknown PLY type " + quoted(word));
      if (!is_integer(p.count_type)) error("list count type must be an integer type");
      tokens.next(word);
    }
    if (!parse_type(word, p.type)) error("unknown PLY type " + quoted(word));
    if (!tokens.next(word)) error("property has no name");
    p.name = std::string(word);
    header_.elements.back().props.push_back(std::move(p));
  }

  void comment(Tokens& tokens) {
    std::string_view tag, index;
    int64_t i = 0;
    if (tokens.next(tag) && tag == "vdbwrap_part" && tokens.next(index) && parse_int(index, i))
      header_.part_names[i] = std::string(tokens.rest());
  }

  LineReader lines_;
  const std::string& name_;
  Header header_;
};

// ---- body sources: same interface for ASCII tokens and binary bytes ------------------------

// Where the reader is, for error messages: element name and index.
struct Position {
  const std::string* element = nullptr;
  uint64_t index = 0;
  std::string label() const { return element ? *element + " " + std::to_string(index) : "data"; }
};

class BinarySource {
 public:
  BinarySource(std::string_view body, bool little, const std::string& name)
      : p_(body.data()), end_(body.data() + body.size()), little_(little), name_(name) {}

  double real(Type t) {
    need(scalar_size(t));
    const double v = load_scalar<double>(p_, t, little_);
    p_ += scalar_size(t);
    return v;
  }

  // Only called for integer types (checked on the header).
  int64_t integer(Type t) {
    need(scalar_size(t));
    const int64_t v = load_scalar<int64_t>(p_, t, little_);
    p_ += scalar_size(t);
    return v;
  }

  void skip(Type t) {
    need(scalar_size(t));
    p_ += scalar_size(t);
  }

  // True when n values of type t could still be in the data (guards list allocations).
  bool can_hold(uint64_t n, Type t) const { return n <= uint64_t(end_ - p_) / scalar_size(t); }

  std::string where() const { return ""; }
  uint64_t remaining() const { return uint64_t(end_ - p_); }

  // Trailing bytes other than whitespace mean the header's counts do not match the data.
  void check_end() const {
    for (const char* q = p_; q < end_; ++q)
      if (!is_space(*q) && *q != '\n')
        fail(name_, std::to_string(end_ - p_) +
                        " bytes after the last element declared by the header "
                        "(the counts do not match the data)");
  }

  Position at;

 private:
  void need(size_t n) {
    if (size_t(end_ - p_) < n) fail(name_, "unexpected end of data in " + at.label() + " (truncated)");
  }

  const char* p_;
  const char* end_;
  bool little_;
  const std::string& name_;
};

class AsciiSource {
 public:
  AsciiSource(std::string_view body, size_t first_line, const std::string& name)
      : p_(body.data()), end_(body.data() + body.size()), line_(first_line), name_(name) {}

  double real(Type) {
    std::string_view token = next();
    double v = 0;
    if (!parse_double(token, v)) error("malformed number " + quoted(token));
    return v;
  }

  int64_t integer(Type) {
    std::string_view token = next();
    int64_t v = 0;
    if (!parse_int(token, v)) error("malformed integer " + quoted(token));
    return v;
  }

  void skip(Type) { next(); }

  bool can_hold(uint64_t n, Type) const { return n <= uint64_t(end_ - p_); }  // >= 1 byte each

  std::string where() const { return "line " + std::to_string(line_) + ": "; }
  uint64_t remaining() const { return uint64_t(end_ - p_); }

  void check_end() {
    skip_space();
    if (p_ < end_) fail_line(name_, line_, "more data than the header declares");
  }

  Position at;

 private:
  [[noreturn]] void error(const std::string& what) { fail_line(name_, line_, at.label() + ": " + what); }

  void skip_space() {
    while (p_ < end_ && (is_space(*p_) || *p_ == '\n')) {
      if (*p_ == '\n') ++line_;
      ++p_;
    }
  }

  std::string_view next() {
    skip_space();
    if (p_ == end_) fail(name_, "unexpected end of data in " + at.label() + " (truncated)");
    const char* start = p_;
    while (p_ < end_ && !is_space(*p_) && *p_ != '\n') ++p_;
    return std::string_view(start, size_t(p_ - start));
  }

  const char* p_;
  const char* end_;
  size_t line_;
  const std::string& name_;
};

// ---- body ---------------------------------------------------------------------------------

int find_property(const Element& e, std::string_view name, bool list) {
  for (size_t i = 0; i < e.props.size(); ++i)
    if (e.props[i].name == name && e.props[i].is_list == list) return int(i);
  return -1;
}

// Smallest number of bytes one element can take; 0 for an element without properties.
// ASCII: each value is at least one character plus a separator.
uint64_t min_element_bytes(const Element& e, bool binary) {
  uint64_t n = 0;
  for (const Property& p : e.props) n += binary ? scalar_size(p.is_list ? p.count_type : p.type) : 2;
  return n;
}

template <class Source>
class BodyReader {
 public:
  BodyReader(const Header& h, Source& src, const std::string& name, MeshData* data)
      : h_(h), src_(src), name_(name), data_(data) {}

  Mesh read() {
    const Element* vertices = find("vertex");
    if (!vertices) fail(name_, "PLY file has no vertex element");
    vertex_count_ = vertices->count;
    check_point_count(name_, vertex_count_);
    for (const Element& e : h_.elements) {
      if (&e == vertices)
        read_vertices(e);
      else if (e.name == "face")
        read_faces(e);
      else if (e.name == "tristrips")
        read_strips(e);
      else
        skip_element(e);
    }
    src_.check_end();
    name_parts();
    pad_mesh_data(data_, mesh_);
    return std::move(mesh_);
  }

 private:
  const Element* find(std::string_view element) const {
    for (const Element& e : h_.elements)
      if (e.name == element) return &e;
    return nullptr;
  }

  // Per property of `e`: the array its values go to (scalar properties, when arrays are asked
  // for), else nullptr. New arrays are NaN up to `size`.
  std::vector<DataArray*> scalar_arrays(const Element& e, std::vector<DataArray>* out, size_t size,
                                        std::initializer_list<int> coordinates = {}) {
    std::vector<DataArray*> arrays(e.props.size(), nullptr);
    if (!out) return arrays;
    auto wanted = [&](size_t j) {
      return !e.props[j].is_list && std::find(coordinates.begin(), coordinates.end(), int(j)) == coordinates.end();
    };
    for (size_t j = 0; j < e.props.size(); ++j)  // all added first: adding may move the earlier ones
      if (wanted(j)) data_array(*out, e.props[j].name, data_type(e.props[j].type), size);
    for (size_t j = 0; j < e.props.size(); ++j)
      if (wanted(j)) arrays[j] = &data_array(*out, e.props[j].name, data_type(e.props[j].type), size);
    return arrays;
  }

  [[noreturn]] void error(const Element& e, uint64_t i, const std::string& what) {
    fail(name_, src_.where() + e.name + " " + std::to_string(i) + " " + what);
  }

  void skip_property(const Property& p) {
    if (!p.is_list) return src_.skip(p.type);
    int64_t n = src_.integer(p.count_type);
    if (n < 0 || !src_.can_hold(uint64_t(n), p.type)) error(*elem_, src_.at.index, "has a bad list length");
    for (int64_t k = 0; k < n; ++k) src_.skip(p.type);
  }

  void begin(const Element& e, uint64_t i) {
    elem_ = &e;
    src_.at = {&e.name, i};
  }

  void read_vertices(const Element& e) {
    const int axis[3] = {find_property(e, "x", false), find_property(e, "y", false), find_property(e, "z", false)};
    if (axis[0] < 0 || axis[1] < 0 || axis[2] < 0)
      fail_line(name_, e.header_line, "vertex element lacks an x, y or z property");
    mesh_.points.resize(size_t(e.count));  // count checked against the data size already
    const std::vector<DataArray*> arrays =
        scalar_arrays(e, data_ ? &data_->point_data : nullptr, 0, {axis[0], axis[1], axis[2]});
    for (uint64_t i = 0; i < e.count; ++i) {
      begin(e, i);
      Vec3& p = mesh_.points[size_t(i)];
      for (size_t j = 0; j < e.props.size(); ++j) {
        int c = int(j) == axis[0] ? 0 : int(j) == axis[1] ? 1 : int(j) == axis[2] ? 2 : -1;
        if (c >= 0)
          p[c] = src_.real(e.props[j].type);
        else if (arrays[j])
          arrays[j]->values.push_back(src_.real(e.props[j].type));
        else
          skip_property(e.props[j]);
      }
      if (!is_finite(p)) error(e, i, "has a non-finite coordinate");
    }
    vertices_read_ = true;
  }

  // The element's list of vertex indices (vertex_indices, or vertex_index as some exporters
  // write): its property number; an error naming `what` when there is none or it is not integer.
  int index_list(const Element& e, const std::string& what) {
    int list = find_property(e, "vertex_indices", true);
    if (list < 0) list = find_property(e, "vertex_index", true);
    if (list < 0) fail_line(name_, e.header_line, what + " element has no vertex_indices list");
    if (!is_integer(e.props[size_t(list)].type))
      fail_line(name_, e.header_line, what + " vertex indices must have an integer type");
    return list;
  }

  void read_faces(const Element& e) {
    const int list = index_list(e, "face");
    int part = find_property(e, "part", false);
    if (part >= 0 && !is_integer(e.props[size_t(part)].type)) part = -1;  // not ours: skip it
    if (e.count > 0 && !vertices_read_)
      fail_line(name_, e.header_line, "face element before the vertex element is not supported");
    // A triangle face takes at least 4 bytes in any encoding; a lying count reserves no more.
    mesh_.triangles.reserve(size_t(std::min<uint64_t>(e.count, src_.remaining() / 4)));
    const std::vector<DataArray*> arrays =
        scalar_arrays(e, data_ ? &data_->cell_data : nullptr, mesh_.triangles.size());
    std::vector<double> values(e.props.size(), 0.0);
    for (uint64_t i = 0; i < e.count; ++i) {
      begin(e, i);
      int64_t part_value = 0;
      for (size_t j = 0; j < e.props.size(); ++j) {
        if (int(j) == list)
          read_polygon(e, i, e.props[j]);
        else if (int(j) == part)
          values[j] = double(part_value = src_.integer(e.props[j].type));
        else if (arrays[j])
          values[j] = src_.real(e.props[j].type);
        else
          skip_property(e.props[j]);
      }
      add_face(part >= 0, part_value);
      // The face's values go to each of its triangles.
      for (size_t j = 0; j < arrays.size(); ++j)
        if (arrays[j]) arrays[j]->values.resize(mesh_.triangles.size(), values[j]);
    }
  }

  // Each element is one list of vertex indices: a strip, where -1 starts a new strip. Triangle
  // k of a strip is (k, k+1, k+2), every other one turned so that all keep one orientation.
  // Triangles that repeat an index are the strip's joins, not geometry: they are dropped but
  // still count for the turn.
  void read_strips(const Element& e) {
    const int list = index_list(e, "tristrips");
    if (e.count > 0 && !vertices_read_)
      fail_line(name_, e.header_line, "tristrips element before the vertex element is not supported");
    for (uint64_t i = 0; i < e.count; ++i) {
      begin(e, i);
      for (size_t j = 0; j < e.props.size(); ++j) {
        if (int(j) != list) {
          skip_property(e.props[j]);
          continue;
        }
        const Property& p = e.props[j];
        const int64_t n = src_.integer(p.count_type);
        if (n < 0 || !src_.can_hold(uint64_t(n), p.type)) error(e, i, "has a list longer than the file (truncated)");
        uint32_t a = 0, b = 0;
        int64_t in_strip = 0;
        for (int64_t k = 0; k < n; ++k) {
          const int64_t v = src_.integer(p.type);
          if (v == -1) {
            in_strip = 0;
            continue;
          }
          if (v < 0 || uint64_t(v) >= vertex_count_)
            error(e, i,
                  "has out-of-range vertex index " + std::to_string(v) + " (the file has " +
                      std::to_string(vertex_count_) + " vertices)");
          const uint32_t c = uint32_t(v);
          if (in_strip >= 2 && a != b && b != c && a != c)
            mesh_.triangles.push_back(in_strip % 2 == 0 ? Tri{a, b, c} : Tri{b, a, c});
          a = b;
          b = c;
          ++in_strip;
        }
      }
    }
    if (!mesh_.triangle_part.empty()) mesh_.triangle_part.resize(mesh_.triangles.size(), 0);
  }

  void read_polygon(const Element& e, uint64_t i, const Property& p) {
    int64_t n = src_.integer(p.count_type);
    if (n < 3) error(e, i, "has " + std::to_string(n) + " vertices (needs at least 3)");
    if (!src_.can_hold(uint64_t(n), p.type)) error(e, i, "has a list longer than the file (truncated)");
    polygon_.resize(size_t(n));
    for (int64_t k = 0; k < n; ++k) {
      int64_t v = src_.integer(p.type);
      if (v < 0 || uint64_t(v) >= vertex_count_)
        error(e, i,
              "has out-of-range vertex index " + std::to_string(v) + " (the file has " + std::to_string(vertex_count_) +
                  " vertices)");
      polygon_[size_t(k)] = uint32_t(v);
    }
  }

  // Triangulates the face just read; parts are numbered in order of first appearance.
  void add_face(bool has_part, int64_t part_value) {
    triangulator_.run(mesh_.points, polygon_.data(), polygon_.size(), mesh_.triangles);
    if (!has_part) return;
    if (part_value != last_value_ || last_part_ < 0) {
      auto [it, inserted] = part_index_.emplace(part_value, int32_t(part_values_.size()));
      if (inserted) part_values_.push_back(part_value);
      last_value_ = part_value;
      last_part_ = it->second;
    }
    mesh_.triangle_part.resize(mesh_.triangles.size(), last_part_);
  }

  void name_parts() {
    for (int64_t value : part_values_) {
      auto it = h_.part_names.find(value);
      mesh_.part_names.push_back(it != h_.part_names.end() ? it->second : "part" + std::to_string(value));
    }
  }

  void skip_element(const Element& e) {
    if (e.props.empty()) return;
    for (uint64_t i = 0; i < e.count; ++i) {
      begin(e, i);
      for (const Property& p : e.props) skip_property(p);
    }
  }

  const Header& h_;
  Source& src_;
  const std::string& name_;
  MeshData* data_;
  Mesh mesh_;
  const Element* elem_ = nullptr;
  uint64_t vertex_count_ = 0;
  bool vertices_read_ = false;
  std::vector<uint32_t> polygon_;
  PolygonTriangulator triangulator_;
  std::unordered_map<int64_t, int32_t> part_index_;
  std::vector<int64_t> part_values_;
  int64_t last_value_ = 0;
  int32_t last_part_ = -1;
};

// Rejects counts the data cannot possibly hold before anything is allocated from them.
void check_counts(const Header& h, uint64_t body_bytes, const std::string& name) {
  const bool binary = h.encoding != Encoding::Ascii;
  uint64_t left = body_bytes + 1;  // the last ASCII value needs no separator
  for (const Element& e : h.elements) {
    uint64_t each = min_element_bytes(e, binary);
    if (each == 0) continue;
    if (e.count > left / each)
      fail(name, "header declares " + std::to_string(e.count) + " " + e.name + " elements but the data has only " +
                     std::to_string(body_bytes) + " bytes (truncated or wrong count)");
    left -= e.count * each;
  }
}

}  // namespace

Mesh read_ply(std::string_view bytes, const std::string& name, MeshData* data) {
  Header h = HeaderParser(bytes, name).parse();
  std::string_view body = bytes.substr(h.body_offset);
  check_counts(h, body.size(), name);
  if (h.encoding == Encoding::Ascii) {
    AsciiSource src(body, h.body_line + 1, name);
    return BodyReader<AsciiSource>(h, src, name, data).read();
  }
  BinarySource src(body, h.encoding == Encoding::BinaryLittle, name);
  return BodyReader<BinarySource>(h, src, name, data).read();
}

namespace {

// One value of an extra array, at p; returns the bytes written.
size_t store_value(char* p, DataArray::Type t, double v) {
  v = storable(t, v);
  switch (t) {
    case DataArray::Type::Int32:
      store_le<int32_t>(p, int32_t(v));
      return 4;
    case DataArray::Type::UInt8:
      *p = char(uint8_t(v));
      return 1;
    case DataArray::Type::Float64:
      break;
  }
  store_le<double>(p, v);
  return 8;
}

}  // namespace

// Binary little-endian, double coordinates (lossless), int indices, int "part" when parts exist,
// then the extra arrays as vertex and face properties.
void write_ply(const Mesh& mesh, Sink& out, const MeshData* data) {
  const bool parts = !mesh.part_names.empty();
  const std::vector<DataArray> none;
  const std::vector<DataArray>& point_data = data ? data->point_data : none;
  const std::vector<DataArray>& cell_data = data ? data->cell_data : none;
  out.put("ply\nformat binary_little_endian 1.0\ncomment written by vdbwrap\n");
  for (size_t p = 0; parts && p < mesh.part_names.size(); ++p)
    out.put("comment vdbwrap_part " + std::to_string(p) + " " + one_line(mesh.part_names[p]) + "\n");
  out.put("element vertex " + std::to_string(mesh.points.size()) + "\n");
  out.put("property double x\nproperty double y\nproperty double z\n");
  for (const DataArray& a : point_data)
    out.put(std::string("property ") + written_type(a.type).ply + " " + a.name + "\n");
  out.put("element face " + std::to_string(mesh.triangles.size()) + "\n");
  out.put(mesh.points.size() <= uint64_t(INT32_MAX) ? "property list uchar int vertex_indices\n"
                                                    : "property list uchar uint vertex_indices\n");
  if (parts) out.put("property int part\n");
  for (const DataArray& a : cell_data)
    out.put(std::string("property ") + written_type(a.type).ply + " " + a.name + "\n");
  out.put("end_header\n");

  std::vector<char> record(24 + 8 * point_data.size());
  for (size_t i = 0; i < mesh.points.size(); ++i) {
    size_t used = 0;
    for (int k = 0; k < 3; ++k) store_le<double>(record.data() + 8 * k, mesh.points[i][k]), used += 8;
    for (const DataArray& a : point_data) used += store_value(record.data() + used, a.type, a.values[i]);
    out.put_bytes(record.data(), used);
  }
  record.assign(1 + 12 + 4 + 8 * cell_data.size(), 0);
  char* face = record.data();
  face[0] = 3;
  for (size_t t = 0; t < mesh.triangles.size(); ++t) {
    for (int k = 0; k < 3; ++k) store_le<uint32_t>(face + 1 + 4 * k, mesh.triangles[t][k]);
    size_t used = 13;
    if (parts) store_le<int32_t>(face + 13, mesh.part_of(t)), used += 4;
    for (const DataArray& a : cell_data) used += store_value(face + used, a.type, a.values[t]);
    out.put_bytes(face, used);
  }
}

}  // namespace vdbwrap::io::detail
