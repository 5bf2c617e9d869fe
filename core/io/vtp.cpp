// VTK XML PolyData (.vtp), the format vtkXMLPolyDataReader (ParaView) reads.
// Writes Float64 points, Polys (connectivity/offsets), cell data "part_id" (Int32) and the part
// names as a String array "part_names" in the dataset's FieldData, in appended raw binary.
// Reads uncompressed files: ascii, inline binary (base64) and appended (raw or base64) arrays,
// any byte order and header type, several pieces; polygons are triangulated, triangle strips
// split, vertices and lines ignored. Compressed files are refused with a clear error.
// Extra arrays (MeshData) are written as point and cell data, and read back when asked for.
#include <algorithm>
#include <limits>
#include <type_traits>
#include <unordered_map>

#include "io/readers.h"
#include "io/scalar_type.h"

namespace vdbwrap::io::detail {
namespace {

// ---- a minimal XML tree -------------------------------------------------------------------

struct XmlElement {
  std::string_view name;
  std::vector<std::pair<std::string_view, std::string>> attributes;  // values entity-decoded
  std::string_view text;  // the character data before the first child or the end tag
  std::vector<size_t> children;
  size_t offset = 0;  // of the '<', for error messages

  const std::string* attribute(std::string_view key) const {
    for (const auto& [k, v] : attributes)
      if (k == key) return &v;
    return nullptr;
  }
};

bool is_name_char(char c) {
  return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '_' || c == ':' ||
         c == '-' || c == '.';
}

bool is_xml_space(char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\n'; }

// Parses elements, attributes and text; skips the declaration, comments, DOCTYPE and CDATA.
// Stops at <AppendedData>: what follows its '_' is binary and is kept as `appended`.
class XmlParser {
 public:
  XmlParser(std::string_view bytes, const std::string& name) : s_(bytes), name_(name) {}

  void parse() {
    std::vector<size_t> open;
    bool text_pending = false;
    size_t text_start = 0;
    while (pos_ < s_.size()) {
      size_t lt = s_.find('<', pos_);
      if (lt == std::string_view::npos) break;
      if (text_pending) elements_[open.back()].text = s_.substr(text_start, lt - text_start);
      text_pending = false;
      pos_ = lt;
      if (starts("<?")) {
        skip_past("?>", "processing instruction");
      } else if (starts("<!--")) {
        skip_past("-->", "comment");
      } else if (starts("<![CDATA[")) {
        skip_past("]]>", "CDATA section");
      } else if (starts("<!")) {
        skip_past(">", "declaration");
      } else if (starts("</")) {
        pos_ += 2;
        std::string_view closing = read_name();
        if (open.empty()) error(lt, "closing tag </" + printable(closing) + "> without an opening tag");
        if (closing != elements_[open.back()].name)
          error(lt, "closing tag </" + printable(closing) + "> does not match <" +
                        printable(elements_[open.back()].name) + ">");
        open.pop_back();
        skip_space();
        expect('>');
      } else {
        ++pos_;
        size_t index = elements_.size();
        elements_.emplace_back();
        elements_.back().offset = lt;
        elements_.back().name = read_name();
        if (elements_.back().name.empty()) error(lt, "'<' not followed by an element name");
        (open.empty() ? roots_ : elements_[open.back()].children).push_back(index);
        bool self_closing = read_attributes(elements_.back());
        if (elements_.back().name == "AppendedData") return read_appended(elements_.back());
        if (!self_closing) {
          open.push_back(index);
          text_pending = true;
          text_start = pos_;
        }
      }
    }
    if (!open.empty())
      error(s_.size(), "file ends inside <" + printable(elements_[open.back()].name) + "> (truncated)");
  }

  const std::vector<XmlElement>& elements() const { return elements_; }
  const std::vector<size_t>& roots() const { return roots_; }
  const XmlElement* appended_element() const { return appended_; }
  std::string_view appended() const { return appended_data_; }

 private:
  [[noreturn]] void error(size_t offset, const std::string& what) const {
    size_t line = 1 + size_t(std::count(s_.begin(), s_.begin() + std::min(offset, s_.size()), '\n'));
    fail_line(name_, line, what);
  }
  static std::string printable(std::string_view s) {
    std::string q = quoted(s);
    return q.substr(1, q.size() - 2);
  }

  bool starts(std::string_view prefix) const { return s_.substr(pos_, prefix.size()) == prefix; }

  void skip_past(std::string_view end, const char* what) {
    size_t at = s_.find(end, pos_);
    if (at == std::string_view::npos) error(pos_, std::string("unterminated ") + what + " (truncated)");
    pos_ = at + end.size();
  }

  void skip_space() {
    while (pos_ < s_.size() && is_xml_space(s_[pos_])) ++pos_;
  }

  void expect(char c) {
    if (pos_ >= s_.size()) error(pos_, std::string("file ends where '") + c + "' is expected (truncated)");
    if (s_[pos_] != c) error(pos_, std::string("expected '") + c + "', found " + quoted(s_.substr(pos_, 1)));
    ++pos_;
  }

  std::string_view read_name() {
    size_t start = pos_;
    while (pos_ < s_.size() && is_name_char(s_[pos_])) ++pos_;
    return s_.substr(start, pos_ - start);
  }

  // Attributes up to '>' or "/>"; true for "/>".
  bool read_attributes(XmlElement& e) {
    for (;;) {
      skip_space();
      if (starts("/>")) {
        pos_ += 2;
        return true;
      }
      if (starts(">")) {
        ++pos_;
        return false;
      }
      if (pos_ >= s_.size()) error(e.offset, "file ends inside the tag <" + printable(e.name) + "> (truncated)");
      size_t at = pos_;
      std::string_view key = read_name();
      if (key.empty()) error(at, "malformed attribute in <" + printable(e.name) + ">: " + quoted(s_.substr(at, 20)));
      skip_space();
      expect('=');
      skip_space();
      if (pos_ >= s_.size() || (s_[pos_] != '"' && s_[pos_] != '\''))
        error(at, "attribute " + printable(key) + " has no quoted value");
      char quote = s_[pos_++];
      size_t end = s_.find(quote, pos_);
      if (end == std::string_view::npos)
        error(at, "unterminated value of attribute " + printable(key) + " (truncated)");
      e.attributes.emplace_back(key, decode_entities(s_.substr(pos_, end - pos_)));
      pos_ = end + 1;
    }
  }

  static std::string decode_entities(std::string_view v) {
    static const std::pair<std::string_view, char> kEntities[] = {
        {"&amp;", '&'}, {"&lt;", '<'}, {"&gt;", '>'}, {"&quot;", '"'}, {"&apos;", '\''}};
    std::string out;
    for (size_t i = 0; i < v.size();) {
      bool replaced = false;
      if (v[i] == '&')
        for (const auto& [entity, c] : kEntities)
          if (v.substr(i, entity.size()) == entity) {
            out += c, i += entity.size(), replaced = true;
            break;
          }
      if (!replaced) out += v[i++];
    }
    return out;
  }

  // <AppendedData encoding="raw|base64"> then whitespace, '_', and the data to the end.
  void read_appended(const XmlElement& e) {
    skip_space();
    if (pos_ >= s_.size() || s_[pos_] != '_') error(pos_, "<AppendedData> must start with '_' before its data");
    appended_ = &e;
    appended_data_ = s_.substr(pos_ + 1);
  }

  std::string_view s_;
  const std::string& name_;
  size_t pos_ = 0;
  std::vector<XmlElement> elements_;
  std::vector<size_t> roots_;
  const XmlElement* appended_ = nullptr;  // points into elements_, which no longer grows
  std::string_view appended_data_;
};

// ---- base64 -------------------------------------------------------------------------------

int base64_value(char c) {
  if (c >= 'A' && c <= 'Z') return c - 'A';
  if (c >= 'a' && c <= 'z') return c - 'a' + 26;
  if (c >= '0' && c <= '9') return c - '0' + 52;
  if (c == '+') return 62;
  if (c == '/') return 63;
  return -1;
}

// Decodes until `wanted` bytes are out, the text ends, or a character outside base64
// (whitespace is skipped; '=' ends a group). Returns the number of characters consumed.
size_t decode_base64(std::string_view text, size_t wanted, std::string& out) {
  uint32_t group = 0;
  int bits = 0;
  size_t i = 0;
  for (; i < text.size() && out.size() < wanted; ++i) {
    char c = text[i];
    if (is_xml_space(c)) continue;
    if (c == '=') {  // padding: the group is complete
      group = 0, bits = 0;
      continue;
    }
    int v = base64_value(c);
    if (v < 0) break;
    group = (group << 6) | uint32_t(v);
    bits += 6;
    if (bits >= 8) {
      bits -= 8;
      out += char((group >> bits) & 0xFF);
    }
  }
  return i;
}

// ---- arrays -------------------------------------------------------------------------------

using Type = ScalarType;

struct File {
  explicit File(const std::string& file_name) : name(file_name) {}
  const std::string& name;
  bool little_endian = true;
  size_t header_bytes = 4;  // UInt32 or UInt64 block sizes
  std::string_view appended;
  bool appended_base64 = false;
};

bool parse_type(std::string_view s, Type& t) {
  static const std::pair<const char*, Type> kNames[] = {
      {"Int8", Type::I8},     {"UInt8", Type::U8},    {"Int16", Type::I16},     {"UInt16", Type::U16},
      {"Int32", Type::I32},   {"UInt32", Type::U32},  {"Int64", Type::I64},     {"UInt64", Type::U64},
      {"Float32", Type::F32}, {"Float64", Type::F64}, {"String", Type::String}, {"Char", Type::I8},
      {"UChar", Type::U8},    {"Short", Type::I16},   {"Int", Type::I32},       {"Long", Type::I64},
      {"Float", Type::F32},   {"Double", Type::F64}};
  for (const auto& [n, type] : kNames)
    if (s == n) {
      t = type;
      return true;
    }
  return false;
}

std::string array_label(const XmlElement& a) {
  const std::string* n = a.attribute("Name");
  return "DataArray " + (n ? quoted(*n) : std::string("(unnamed)"));
}

uint64_t load_header(const File& f, const char* p) {
  return f.header_bytes == 8 ? load<uint64_t>(p, f.little_endian) : load<uint32_t>(p, f.little_endian);
}

// The payload of a binary or appended array (after its byte-count header).
std::string_view binary_payload(const File& f, const XmlElement& a, const std::string& format, std::string& storage) {
  auto bad = [&](const std::string& what) { fail(f.name, array_label(a) + ": " + what); };
  if (format == "binary") {
    decode_base64(a.text, std::numeric_limits<size_t>::max(), storage);
    if (storage.size() < f.header_bytes) bad("binary data is shorter than its size header (truncated)");
    uint64_t count = load_header(f, storage.data());
    if (count > storage.size() - f.header_bytes)
      bad("declares " + std::to_string(count) + " bytes but holds " + std::to_string(storage.size() - f.header_bytes) +
          " (truncated)");
    return std::string_view(storage).substr(f.header_bytes, size_t(count));
  }
  const std::string* offset_text = a.attribute("offset");
  int64_t offset = 0;
  if (!offset_text || !parse_int(*offset_text, offset) || offset < 0) bad("appended array without a valid offset");
  if (f.appended.data() == nullptr) bad("format is appended but the file has no <AppendedData>");
  if (uint64_t(offset) > f.appended.size())
    bad("offset " + std::to_string(offset) + " is past the end of the appended data (" +
        std::to_string(f.appended.size()) + " bytes)");
  std::string_view rest = f.appended.substr(size_t(offset));
  if (f.appended_base64) {
    decode_base64(rest, f.header_bytes, storage);
    if (storage.size() < f.header_bytes) bad("appended data ends inside its size header (truncated)");
    uint64_t count = load_header(f, storage.data());
    if (count > rest.size()) bad("declares " + std::to_string(count) + " bytes, more than the file holds");
    storage.clear();
    decode_base64(rest, f.header_bytes + size_t(count), storage);
    if (storage.size() < f.header_bytes + count)
      bad("declares " + std::to_string(count) + " bytes but the appended data ends first (truncated)");
    return std::string_view(storage).substr(f.header_bytes, size_t(count));
  }
  if (rest.size() < f.header_bytes) bad("appended data ends inside its size header (truncated)");
  uint64_t count = load_header(f, rest.data());
  if (count > rest.size() - f.header_bytes)
    bad("declares " + std::to_string(count) + " bytes but only " + std::to_string(rest.size() - f.header_bytes) +
        " follow (truncated)");
  return rest.substr(f.header_bytes, size_t(count));
}

template <class T>
T load_as(const File& f, const char* p, Type t) {
  return load_scalar<T>(p, t, f.little_endian);
}

// The values of a numeric DataArray as T (int64_t for indices and ids, double for
// coordinates). Integer targets refuse floating-point arrays.
template <class T>
std::vector<T> read_array(const File& f, const XmlElement& a) {
  auto bad = [&](const std::string& what) { fail(f.name, array_label(a) + ": " + what); };
  const std::string* type_text = a.attribute("type");
  Type type = Type::F64;
  if (!type_text) bad("has no type");
  if (!parse_type(*type_text, type) || type == Type::String) bad("unsupported type " + quoted(*type_text));
  if (std::is_integral_v<T> && !is_integer(type)) bad("must have an integer type, not " + *type_text);
  const std::string* format_attr = a.attribute("format");
  const std::string format = format_attr ? *format_attr : "ascii";
  std::vector<T> values;
  if (format == "ascii") {
    std::string_view text = a.text;
    size_t i = 0;
    while (i < text.size()) {
      while (i < text.size() && is_xml_space(text[i])) ++i;
      size_t j = i;
      while (j < text.size() && !is_xml_space(text[j])) ++j;
      if (j == i) break;
      std::string_view token = text.substr(i, j - i);
      if constexpr (std::is_integral_v<T>) {
        int64_t v = 0;
        if (!parse_int(token, v)) bad("malformed integer " + quoted(token));
        values.push_back(v);
      } else {
        double v = 0;
        if (!parse_double(token, v)) bad("malformed number " + quoted(token));
        values.push_back(v);
      }
      i = j;
    }
    return values;
  }
  if (format != "binary" && format != "appended") bad("unknown format " + quoted(format));
  std::string storage;
  std::string_view payload = binary_payload(f, a, format, storage);
  const size_t size = scalar_size(type);
  if (payload.size() % size != 0)
    bad(std::to_string(payload.size()) + " bytes is not a whole number of " + *type_text + " values");
  values.resize(payload.size() / size);
  for (size_t i = 0; i < values.size(); ++i) values[i] = load_as<T>(f, payload.data() + i * size, type);
  return values;
}

// A String array: ascii holds character codes, each string ended by 0; binary holds the bytes,
// each string ended by NUL (as vtkXMLWriter writes them).
std::vector<std::string> read_strings(const File& f, const XmlElement& a) {
  const std::string* format_attr = a.attribute("format");
  const std::string format = format_attr ? *format_attr : "ascii";
  std::string bytes;
  if (format == "ascii") {
    XmlElement as_ints = a;
    as_ints.attributes = {{"type", "Int32"}, {"format", "ascii"}};
    if (const std::string* n = a.attribute("Name")) as_ints.attributes.emplace_back("Name", *n);
    for (int64_t c : read_array<int64_t>(f, as_ints)) {
      if (c < -128 || c > 255)
        fail(f.name, array_label(a) + ": character code " + std::to_string(c) + " is out of range");
      bytes += char(c);
    }
  } else {
    std::string storage;
    bytes = std::string(binary_payload(f, a, format, storage));
  }
  std::vector<std::string> strings;
  size_t start = 0;
  for (size_t i = 0; i < bytes.size(); ++i)
    if (bytes[i] == '\0') {
      strings.push_back(bytes.substr(start, i - start));
      start = i + 1;
    }
  if (start < bytes.size()) strings.push_back(bytes.substr(start));
  return strings;
}

// ---- reader -------------------------------------------------------------------------------

class VtpReader {
 public:
  VtpReader(std::string_view bytes, const std::string& name, MeshData* data)
      : xml_(bytes, name), file_{name}, file_size_(bytes.size()), data_(data) {}

  Mesh read() {
    xml_.parse();
    const XmlElement* root = nullptr;
    for (size_t r : xml_.roots())
      if (element(r).name == "VTKFile") root = &element(r);
    if (!root) fail(name(), "not a VTK XML file (no <VTKFile> element)");
    read_file_attributes(*root);
    const XmlElement* poly = child(*root, "PolyData");
    if (!poly) {
      const std::string* type = root->attribute("type");
      fail(name(), "VTKFile of type " + (type ? quoted(*type) : std::string("(none)")) +
                       " has no <PolyData> (only PolyData, .vtp, is read)");
    }
    if (const XmlElement* field = child(*poly, "FieldData"))
      for (size_t c : field->children)
        if (named(element(c), "part_names")) part_names_ = read_strings(file_, element(c));
    size_t pieces = 0;
    for (size_t c : poly->children)
      if (element(c).name == "Piece") read_piece(element(c), pieces++);
    name_parts();
    pad_mesh_data(data_, mesh_);
    return std::move(mesh_);
  }

 private:
  const std::string& name() const { return file_.name; }
  const XmlElement& element(size_t i) const { return xml_.elements()[i]; }

  const XmlElement* child(const XmlElement& e, std::string_view tag) const {
    for (size_t c : e.children)
      if (element(c).name == tag) return &element(c);
    return nullptr;
  }

  // vtkXMLWriter writes string arrays as <Array>, numeric ones as <DataArray>.
  static bool named(const XmlElement& e, std::string_view array_name) {
    const std::string* n = e.attribute("Name");
    return (e.name == "DataArray" || e.name == "Array") && n && *n == array_name;
  }

  const XmlElement* array(const XmlElement* parent, std::string_view array_name) const {
    if (parent)
      for (size_t c : parent->children)
        if (named(element(c), array_name)) return &element(c);
    return nullptr;
  }

  void read_file_attributes(const XmlElement& root) {
    if (const std::string* c = root.attribute("compressor"); c && !c->empty())
      fail(name(), "compressed VTP (" + quoted(*c) +
                       ") is not supported; save it uncompressed (ParaView: Compressor Type None)");
    if (const std::string* order = root.attribute("byte_order")) {
      if (*order == "BigEndian")
        file_.little_endian = false;
      else if (*order != "LittleEndian")
        fail(name(), "unknown byte_order " + quoted(*order));
    }
    if (const std::string* header = root.attribute("header_type")) {
      if (*header == "UInt64")
        file_.header_bytes = 8;
      else if (*header != "UInt32")
        fail(name(), "unknown header_type " + quoted(*header));
    }
    if (const XmlElement* appended = xml_.appended_element()) {
      const std::string* encoding = appended->attribute("encoding");
      if (encoding && *encoding == "base64")
        file_.appended_base64 = true;
      else if (encoding && *encoding != "raw")
        fail(name(), "unknown AppendedData encoding " + quoted(*encoding));
      file_.appended = xml_.appended();
    }
  }

  uint64_t count_attribute(const XmlElement& piece, const char* key, size_t index) const {
    const std::string* text = piece.attribute(key);
    int64_t v = 0;
    if (!text) return 0;
    if (!parse_int(*text, v) || v < 0)
      fail(name(), "Piece " + std::to_string(index) + ": " + key + " is not a count: " + quoted(*text));
    // Every point or cell takes at least one byte: larger counts are corrupt (and checking
    // here keeps the sums and products of counts below from overflowing).
    if (uint64_t(v) > file_size_)
      fail(name(), "Piece " + std::to_string(index) + ": " + key + " " + *text + " is more than a file of " +
                       std::to_string(file_size_) + " bytes can hold");
    return uint64_t(v);
  }

  void read_piece(const XmlElement& piece, size_t index) {
    const std::string where = "Piece " + std::to_string(index);
    auto bad = [&](const std::string& what) { fail(name(), where + ": " + what); };
    const uint64_t n_points = count_attribute(piece, "NumberOfPoints", index);
    const uint64_t n_verts = count_attribute(piece, "NumberOfVerts", index);
    const uint64_t n_lines = count_attribute(piece, "NumberOfLines", index);
    const uint64_t n_polys = count_attribute(piece, "NumberOfPolys", index);
    const uint64_t n_strips = count_attribute(piece, "NumberOfStrips", index);

    // Points: the first DataArray of <Points>, 3 components.
    const size_t base = mesh_.points.size();
    check_point_count(name(), base + n_points);
    if (n_points > 0) {
      const XmlElement* points = child(piece, "Points");
      const XmlElement* coords = points ? child(*points, "DataArray") : nullptr;
      if (!coords) bad("has " + std::to_string(n_points) + " points but no <Points> array");
      const std::string* components = coords->attribute("NumberOfComponents");
      if (!components || *components != "3") bad("<Points> array must have NumberOfComponents=\"3\"");
      std::vector<double> xyz = read_array<double>(file_, *coords);
      if (xyz.size() != 3 * n_points)
        bad("NumberOfPoints is " + std::to_string(n_points) + " but <Points> holds " + std::to_string(xyz.size()) +
            " values (needs " + std::to_string(3 * n_points) + ")");
      mesh_.points.reserve(base + n_points);
      for (size_t i = 0; i < n_points; ++i) {
        Vec3 p{xyz[3 * i], xyz[3 * i + 1], xyz[3 * i + 2]};
        if (!is_finite(p)) bad("point " + std::to_string(i) + " has a non-finite coordinate");
        mesh_.points.push_back(p);
      }
    }

    // Cell data are ordered verts, lines, polys, strips.
    std::vector<int64_t> part_id;
    const XmlElement* part_array = array(child(piece, "CellData"), "part_id");
    const uint64_t n_cells = n_verts + n_lines + n_polys + n_strips;
    if (part_array) {
      part_id = read_array<int64_t>(file_, *part_array);
      if (part_id.size() != n_cells)
        bad("cell data 'part_id' has " + std::to_string(part_id.size()) + " values for " + std::to_string(n_cells) +
            " cells");
      has_parts_ = true;
    }
    auto cell_part = [&](uint64_t cell) { return part_id.empty() ? 0 : part_id[cell]; };
    const size_t first_triangle = mesh_.triangles.size();
    std::vector<uint64_t> triangle_cell;  // of this piece's triangles, when arrays are read
    auto from_cell = [&](uint64_t cell) {
      if (data_) triangle_cell.resize(mesh_.triangles.size() - first_triangle, cell);
    };

    read_cells(piece, "Polys", n_polys, base, n_points, where, [&](const std::vector<uint32_t>& poly, uint64_t i) {
      if (poly.size() < 3)
        bad("polygon " + std::to_string(i) + " has " + std::to_string(poly.size()) + " points (needs at least 3)");
      triangulator_.run(mesh_.points, poly.data(), poly.size(), mesh_.triangles);
      values_.resize(mesh_.triangles.size(), cell_part(n_verts + n_lines + i));
      from_cell(n_verts + n_lines + i);
    });
    // Strip triangle k is (k, k+1, k+2), every other one turned to keep one orientation;
    // triangles that repeat a point are joins, not geometry.
    read_cells(piece, "Strips", n_strips, base, n_points, where, [&](const std::vector<uint32_t>& strip, uint64_t i) {
      for (size_t k = 2; k < strip.size(); ++k) {
        uint32_t a = strip[k - 2], b = strip[k - 1], c = strip[k];
        if (a == b || b == c || a == c) continue;
        mesh_.triangles.push_back(k % 2 == 0 ? Tri{a, b, c} : Tri{b, a, c});
      }
      values_.resize(mesh_.triangles.size(), cell_part(n_verts + n_lines + n_polys + i));
      from_cell(n_verts + n_lines + n_polys + i);
    });
    if (data_) {
      read_data(child(piece, "PointData"), data_->point_data, base, n_points, where + ": point data", {});
      read_data(child(piece, "CellData"), data_->cell_data, first_triangle, n_cells, where + ": cell data",
                triangle_cell);
    }
  }

  // The single-component numeric arrays of <PointData> or <CellData> (`count` values each),
  // appended to `arrays` from `first` on (earlier values missing are NaN): a point's value, or
  // for cells the value of the cell each new triangle came from (`triangle_cell`).
  void read_data(const XmlElement* parent, std::vector<DataArray>& arrays, size_t first, uint64_t count,
                 const std::string& where, const std::vector<uint64_t>& triangle_cell) {
    if (!parent) return;
    const bool cells = &arrays == &data_->cell_data;
    for (size_t c : parent->children) {
      const XmlElement& a = element(c);
      const std::string* array_name = a.attribute("Name");
      const std::string* type_text = a.attribute("type");
      const std::string* components = a.attribute("NumberOfComponents");
      Type type;
      if (a.name != "DataArray" || !array_name || !type_text || !parse_type(*type_text, type) || type == Type::String ||
          (components && *components != "1"))
        continue;
      const std::vector<double> values = read_array<double>(file_, a);
      if (values.size() != count)
        fail(name(), where + ": array " + quoted(*array_name) + " has " + std::to_string(values.size()) +
                         " values for " + std::to_string(count));
      const DataArray::Type kind = data_type(type);
      DataArray& out = data_array(arrays, *array_name, kind, first);
      out.values.resize(first, NAN);
      if (!cells) {
        out.values.insert(out.values.end(), values.begin(), values.end());
      } else {
        for (uint64_t cell : triangle_cell) out.values.push_back(values[size_t(cell)]);
      }
    }
    pad_arrays(arrays, first + (cells ? triangle_cell.size() : size_t(count)));
  }

  // Calls `cell(points, i)` for each of the `count` cells of <Polys> or <Strips>, with global
  // point indices.
  template <class Cell>
  void read_cells(const XmlElement& piece, const char* tag, uint64_t count, size_t base, uint64_t n_points,
                  const std::string& where, Cell&& cell) {
    auto bad = [&](const std::string& what) { fail(name(), where + ": <" + tag + ">: " + what); };
    if (count == 0) return;
    const XmlElement* cells = child(piece, tag);
    const XmlElement* connectivity = array(cells, "connectivity");
    const XmlElement* offsets = array(cells, "offsets");
    if (!connectivity || !offsets)
      bad("has " + std::to_string(count) + " cells but no connectivity and offsets arrays");
    std::vector<int64_t> ends = read_array<int64_t>(file_, *offsets);
    if (ends.size() != count)
      bad("offsets has " + std::to_string(ends.size()) + " values for " + std::to_string(count) + " cells");
    std::vector<int64_t> ids = read_array<int64_t>(file_, *connectivity);
    std::vector<uint32_t> points;
    int64_t start = 0;
    for (uint64_t i = 0; i < count; ++i) {
      const int64_t end = ends[i];
      if (end < start || uint64_t(end) > ids.size())
        bad("offset " + std::to_string(end) + " of cell " + std::to_string(i) +
            (end < start ? " is smaller than the one before"
                         : " is past the connectivity's " + std::to_string(ids.size()) + " values"));
      points.clear();
      for (int64_t k = start; k < end; ++k) {
        const int64_t v = ids[size_t(k)];
        if (v < 0 || uint64_t(v) >= n_points)
          bad("cell " + std::to_string(i) + " refers to point " + std::to_string(v) + " but the piece has " +
              std::to_string(n_points));
        points.push_back(uint32_t(base + size_t(v)));
      }
      cell(points, i);
      start = end;
    }
  }

  // part_id values become parts in order of first appearance, named by "part_names".
  void name_parts() {
    if (!has_parts_) return;
    std::unordered_map<int64_t, int32_t> index;
    mesh_.triangle_part.resize(values_.size());
    for (size_t t = 0; t < values_.size(); ++t) {
      const int64_t v = values_[t];
      auto [it, inserted] = index.emplace(v, int32_t(mesh_.part_names.size()));
      if (inserted)
        mesh_.part_names.push_back(v >= 0 && uint64_t(v) < part_names_.size() ? part_names_[size_t(v)]
                                                                              : "part" + std::to_string(v));
      mesh_.triangle_part[t] = it->second;
    }
  }

  XmlParser xml_;
  File file_;
  size_t file_size_;
  Mesh mesh_;
  std::vector<std::string> part_names_;
  std::vector<int64_t> values_;  // part_id of each triangle
  bool has_parts_ = false;
  MeshData* data_;
  PolygonTriangulator triangulator_;
};

// ---- writer -------------------------------------------------------------------------------

// Appends one raw block (UInt64 byte count, then the values) of the appended data.
template <class T, class Values>
void put_block(Sink& out, size_t count, Values&& value_at) {
  char header[8];
  store_le<uint64_t>(header, uint64_t(count) * sizeof(T));
  out.put_bytes(header, sizeof header);
  char buffer[8192];
  size_t used = 0;
  for (size_t i = 0; i < count; ++i) {
    store_le<T>(buffer + used, value_at(i));
    used += sizeof(T);
    if (used == sizeof buffer) out.put_bytes(buffer, used), used = 0;
  }
  out.put_bytes(buffer, used);
}

}  // namespace

bool looks_like_vtp(std::string_view bytes) {
  std::string_view head = bytes.substr(0, 1024);
  size_t tag = head.find("<VTKFile");
  return trim(head).substr(0, 1) == "<" && tag != std::string_view::npos &&
         head.find("PolyData", tag) != std::string_view::npos;
}

Mesh read_vtp(std::string_view bytes, const std::string& name, MeshData* data) {
  return VtpReader(bytes, name, data).read();
}

void write_vtp(const Mesh& mesh, Sink& out, const MeshData* data) {
  const size_t n_points = mesh.points.size(), n_tris = mesh.triangles.size();
  const std::vector<DataArray> none;
  const std::vector<DataArray>& point_data = data ? data->point_data : none;
  const std::vector<DataArray>& cell_data = data ? data->cell_data : none;
  const bool parts = !mesh.part_names.empty();
  // 32-bit cell arrays when the values fit (half the size), else 64-bit.
  const bool wide = 3 * uint64_t(n_tris) > uint64_t(INT32_MAX) || n_points > size_t(INT32_MAX);
  const char* index_type = wide ? "Int64" : "Int32";
  const size_t index_size = wide ? 8 : 4;

  const size_t points_offset = 0;
  const size_t connectivity_offset = points_offset + 8 + 24 * n_points;
  const size_t offsets_offset = connectivity_offset + 8 + 3 * n_tris * index_size;
  const size_t part_offset = offsets_offset + 8 + n_tris * index_size;
  // The extra arrays follow: point data, then cell data.
  std::vector<size_t> data_offsets;
  size_t next_offset = part_offset + (parts ? 8 + 4 * n_tris : 0);
  for (const auto* arrays : {&point_data, &cell_data})
    for (const DataArray& a : *arrays) {
      data_offsets.push_back(next_offset);
      next_offset += 8 + a.values.size() * written_type(a.type).bytes;
    }
  size_t next_array = 0;
  auto declare = [&](const DataArray& a) {
    out.put(std::string("        <DataArray type=\"") + written_type(a.type).vtk + "\" Name=\"" + a.name +
            "\" format=\"appended\" offset=\"");
    out.put_uint(data_offsets[next_array++]);
    out.put("\"/>\n");
  };

  out.put("<?xml version=\"1.0\"?>\n");
  out.put("<VTKFile type=\"PolyData\" version=\"1.0\" byte_order=\"LittleEndian\" header_type=\"UInt64\">\n");
  out.put("  <PolyData>\n");
  if (parts) {
    out.put("    <FieldData>\n");
    out.put("      <DataArray type=\"String\" Name=\"part_names\" NumberOfTuples=\"");
    out.put_uint(mesh.part_names.size());
    out.put("\" format=\"ascii\">\n       ");
    for (const std::string& part : mesh.part_names) {
      for (char c : part) {
        out.put(' ');
        out.put(std::to_string(int(c == '\0' ? '?' : c)));  // a NUL would split the name
      }
      out.put(" 0");
    }
    out.put("\n      </DataArray>\n    </FieldData>\n");
  }
  out.put("    <Piece NumberOfPoints=\"");
  out.put_uint(n_points);
  out.put("\" NumberOfVerts=\"0\" NumberOfLines=\"0\" NumberOfStrips=\"0\" NumberOfPolys=\"");
  out.put_uint(n_tris);
  out.put("\">\n");
  if (!point_data.empty()) {
    out.put("      <PointData Scalars=\"" + point_data.front().name + "\">\n");
    for (const DataArray& a : point_data) declare(a);
    out.put("      </PointData>\n");
  }
  if (parts || !cell_data.empty()) {
    out.put(std::string("      <CellData Scalars=\"") + (parts ? "part_id" : cell_data.front().name.c_str()) + "\">\n");
    if (parts) {
      out.put("        <DataArray type=\"Int32\" Name=\"part_id\" format=\"appended\" offset=\"");
      out.put_uint(part_offset);
      out.put("\"/>\n");
    }
    for (const DataArray& a : cell_data) declare(a);
    out.put("      </CellData>\n");
  }
  out.put("      <Points>\n");
  out.put(
      "        <DataArray type=\"Float64\" Name=\"Points\" NumberOfComponents=\"3\" format=\"appended\" "
      "offset=\"0\"/>\n");
  out.put("      </Points>\n      <Polys>\n");
  out.put(std::string("        <DataArray type=\"") + index_type +
          "\" Name=\"connectivity\" format=\"appended\" offset=\"");
  out.put_uint(connectivity_offset);
  out.put(std::string("\"/>\n        <DataArray type=\"") + index_type +
          "\" Name=\"offsets\" format=\"appended\" offset=\"");
  out.put_uint(offsets_offset);
  out.put("\"/>\n      </Polys>\n    </Piece>\n  </PolyData>\n");
  out.put("  <AppendedData encoding=\"raw\">\n   _");
  put_block<double>(out, 3 * n_points, [&](size_t i) { return mesh.points[i / 3][i % 3]; });
  if (wide) {
    put_block<int64_t>(out, 3 * n_tris, [&](size_t i) { return int64_t(mesh.triangles[i / 3][i % 3]); });
    put_block<int64_t>(out, n_tris, [&](size_t i) { return int64_t(3 * (i + 1)); });
  } else {
    put_block<int32_t>(out, 3 * n_tris, [&](size_t i) { return int32_t(mesh.triangles[i / 3][i % 3]); });
    put_block<int32_t>(out, n_tris, [&](size_t i) { return int32_t(3 * (i + 1)); });
  }
  if (parts) put_block<int32_t>(out, n_tris, [&](size_t t) { return mesh.part_of(t); });
  for (const auto* arrays : {&point_data, &cell_data})
    for (const DataArray& a : *arrays) {
      auto value = [&](size_t i) { return storable(a.type, a.values[i]); };
      switch (a.type) {
        case DataArray::Type::Float64:
          put_block<double>(out, a.values.size(), value);
          break;
        case DataArray::Type::Int32:
          put_block<int32_t>(out, a.values.size(), [&](size_t i) { return int32_t(value(i)); });
          break;
        case DataArray::Type::UInt8:
          put_block<uint8_t>(out, a.values.size(), [&](size_t i) { return uint8_t(value(i)); });
          break;
      }
    }
  out.put("\n  </AppendedData>\n</VTKFile>\n");
}

}  // namespace vdbwrap::io::detail
