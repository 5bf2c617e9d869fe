// Internal helpers shared by the format readers and writers of core/io (not public API).
#pragma once
#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "vdbwrap/io.h"
#include "vdbwrap/errors.h"
#include "vdbwrap/mesh.h"

namespace vdbwrap::io::detail {

// ---- errors -------------------------------------------------------------------------------

// Throws Error(InvalidInput, "NAME: what").
[[noreturn]] void fail(const std::string& name, const std::string& what);
// Throws Error(InvalidInput, "NAME: line N: what").
[[noreturn]] void fail_line(const std::string& name, size_t line, const std::string& what);
// A token quoted for an error message, shortened so a binary blob cannot flood the message.
std::string quoted(std::string_view token);
// "dir/part.stl" -> "part": binary STL parts are named after the file.
std::string file_stem(const std::string& path);

// ---- text scanning ------------------------------------------------------------------------

inline bool is_space(char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\v' || c == '\f'; }

inline std::string_view trim(std::string_view s) {
  while (!s.empty() && (is_space(s.front()) || s.front() == '\n')) s.remove_prefix(1);
  while (!s.empty() && (is_space(s.back()) || s.back() == '\n')) s.remove_suffix(1);
  return s;
}

inline bool iequals(std::string_view a, std::string_view b) {
  if (a.size() != b.size()) return false;
  for (size_t i = 0; i < a.size(); ++i) {
    char x = a[i], y = b[i];
    if (x >= 'A' && x <= 'Z') x = char(x - 'A' + 'a');
    if (y >= 'A' && y <= 'Z') y = char(y - 'A' + 'a');
    if (x != y) return false;
  }
  return true;
}

// Walks the lines of a text buffer without copying ('\n' or "\r\n" endings).
class LineReader {
 public:
  explicit LineReader(std::string_view text) : text_(text) {}
  bool next(std::string_view& line) {
    if (pos_ >= text_.size()) return false;
    const char* start = text_.data() + pos_;
    const void* nl = std::memchr(start, '\n', text_.size() - pos_);
    size_t len = nl ? size_t(static_cast<const char*>(nl) - start) : text_.size() - pos_;
    pos_ += len + (nl ? 1 : 0);
    ++line_;
    if (len > 0 && start[len - 1] == '\r') --len;
    line = std::string_view(start, len);
    return true;
  }
  size_t line_number() const { return line_; }  // 1-based number of the last line returned
  size_t offset() const { return pos_; }        // byte offset just after that line

 private:
  std::string_view text_;
  size_t pos_ = 0;
  size_t line_ = 0;
};

// Splits one line into whitespace-separated tokens.
class Tokens {
 public:
  explicit Tokens(std::string_view s) : rest_(s) {}
  bool next(std::string_view& token) {
    size_t i = 0;
    while (i < rest_.size() && is_space(rest_[i])) ++i;
    if (i == rest_.size()) return false;
    size_t j = i;
    while (j < rest_.size() && !is_space(rest_[j])) ++j;
    token = rest_.substr(i, j - i);
    rest_.remove_prefix(j);
    return true;
  }
  std::string_view rest() const { return trim(rest_); }  // what is left, trimmed

 private:
  std::string_view rest_;
};

// Parses a whole token as a double (accepts a leading '+', "nan", "inf"). Values too large for
// a double become +-inf (so they are reported as non-finite), too small ones become 0.
inline bool parse_double(std::string_view token, double& out) {
  const char* b = token.data();
  const char* e = b + token.size();
  if (b != e && *b == '+') ++b;
  auto r = std::from_chars(b, e, out);
  if (r.ec == std::errc::result_out_of_range && r.ptr == e && token.size() < 64) {
    // from_chars leaves `out` untouched on over/underflow; strtod gives HUGE_VAL or ~0.
    char buf[64];
    std::memcpy(buf, b, size_t(e - b));
    buf[e - b] = '\0';
    out = std::strtod(buf, nullptr);
    return true;
  }
  return r.ec == std::errc() && r.ptr == e;
}

inline bool parse_int(std::string_view token, int64_t& out) {
  const char* b = token.data();
  const char* e = b + token.size();
  if (b != e && *b == '+') ++b;
  auto r = std::from_chars(b, e, out);
  return r.ec == std::errc() && r.ptr == e;
}

inline bool is_finite(const Vec3& p) { return std::isfinite(p[0]) && std::isfinite(p[1]) && std::isfinite(p[2]); }

// Triangle indices are 32-bit: a mesh with more points cannot be represented.
void check_point_count(const std::string& name, uint64_t count);

// ---- polygons -----------------------------------------------------------------------------

// Splits polygons into triangles. Reuses its scratch buffers across calls (one per reader).
class PolygonTriangulator {
 public:
  // Appends exactly n-2 triangles covering polygon poly[0..n) (indices into points, n >= 3),
  // oriented like the polygon. Ear clipping in the polygon's best-fit (Newell) plane, so
  // non-convex polygons are handled; degenerate polygons fall back to a fan.
  void run(const std::vector<Vec3>& points, const uint32_t* poly, size_t n, std::vector<Tri>& out);

 private:
  bool project(const std::vector<Vec3>& points, const uint32_t* poly, size_t n);
  void ear_clip(const uint32_t* poly, size_t n, std::vector<Tri>& out);
  bool is_ear(size_t a, size_t b, size_t c) const;

  std::vector<double> u_, v_;        // 2D coordinates in the polygon's plane
  std::vector<size_t> prev_, next_;  // the remaining polygon as a circular list
};

// ---- readers ------------------------------------------------------------------------------

bool is_binary_stl_size(std::string_view bytes);  // size == 84 + 50 * declared count
bool looks_like_ascii_stl(std::string_view bytes);
Mesh read_stl(std::string_view bytes, const std::string& name);
Mesh read_obj(std::string_view bytes, const std::string& name);
Mesh read_off(std::string_view bytes, const std::string& name);
// `data`, when given, receives the extra arrays (mesh_io.h: read_mesh).
Mesh read_ply(std::string_view bytes, const std::string& name, MeshData* data = nullptr);
bool looks_like_vtp(std::string_view bytes);  // an XML VTKFile of type PolyData
Mesh read_vtp(std::string_view bytes, const std::string& name, MeshData* data = nullptr);
Mesh read_nastran(std::string_view bytes, const std::string& name);

// ---- writers ------------------------------------------------------------------------------

// Buffered output to a FILE (flushed every few MB) or, without a file, to memory.
class Sink {
 public:
  explicit Sink(std::FILE* file = nullptr) : file_(file) {}
  void put(std::string_view s) {
    buffer_.append(s.data(), s.size());
    if (file_ && buffer_.size() >= kChunk) flush();
  }
  void put(char c) { put(std::string_view(&c, 1)); }
  // Shortest text that reads back to exactly the same double.
  void put_real(double v) {
    char tmp[32];
    auto r = std::to_chars(tmp, tmp + sizeof tmp, v);
    put(std::string_view(tmp, size_t(r.ptr - tmp)));
  }
  void put_uint(uint64_t v) {
    char tmp[24];
    auto r = std::to_chars(tmp, tmp + sizeof tmp, v);
    put(std::string_view(tmp, size_t(r.ptr - tmp)));
  }
  void put_bytes(const void* p, size_t n) { put(std::string_view(static_cast<const char*>(p), n)); }
  void flush() {
    if (!file_ || buffer_.empty()) return;
    if (std::fwrite(buffer_.data(), 1, buffer_.size(), file_) != buffer_.size()) failed_ = true;
    buffer_.clear();
  }
  bool failed() const { return failed_; }
  std::string take() { return std::move(buffer_); }

 private:
  static constexpr size_t kChunk = size_t(4) << 20;
  std::FILE* file_;
  std::string buffer_;
  bool failed_ = false;
};

// A part name on one line: writers put names on header/group lines.
std::string one_line(const std::string& name);

// Each writer expects a mesh already checked by the caller (indices and parts in range).
// Binary (one part at most) or ASCII with one solid per part, as `ascii` says.
void write_stl(const Mesh& mesh, Sink& out, bool ascii);
void write_obj(const Mesh& mesh, Sink& out);
void write_off(const Mesh& mesh, Sink& out);
// `data`: extra arrays, sizes and names checked by the caller.
void write_ply(const Mesh& mesh, Sink& out, const MeshData* data = nullptr);
void write_vtp(const Mesh& mesh, Sink& out, const MeshData* data = nullptr);
// A value of an extra array as its written type holds it: integers clamped to the type's range
// and NaN as 0 (converting them as they are would be undefined behaviour).
inline double storable(DataArray::Type t, double v) {
  if (t == DataArray::Type::Float64) return v;
  if (std::isnan(v)) return 0;
  const double lo = t == DataArray::Type::UInt8 ? 0.0 : double(INT32_MIN);
  const double hi = t == DataArray::Type::UInt8 ? 255.0 : double(INT32_MAX);
  return v < lo ? lo : v > hi ? hi : v;
}
// Finds or adds the array `name` (added arrays are NaN up to `size`).
DataArray& data_array(std::vector<DataArray>& arrays, const std::string& name, DataArray::Type type, size_t size);
// Pads every array with NaN up to `size` (values a piece or an element did not give).
void pad_arrays(std::vector<DataArray>& arrays, size_t size);
// The same for a whole read: point arrays to the mesh's points, cell arrays to its triangles.
void pad_mesh_data(MeshData* data, const Mesh& mesh);
// Grid and element IDs are 8-character fields: the caller checks the counts against this.
constexpr uint64_t kNastranMaxId = 99999999;
void write_nastran(const Mesh& mesh, Sink& out);

// Little-endian byte order helpers for the binary formats.
constexpr bool kHostLittleEndian = __BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__;

template <class T>
inline T byte_swapped(T v) {
  unsigned char b[sizeof(T)];
  std::memcpy(b, &v, sizeof(T));
  for (size_t i = 0; i < sizeof(T) / 2; ++i) std::swap(b[i], b[sizeof(T) - 1 - i]);
  std::memcpy(&v, b, sizeof(T));
  return v;
}

template <class T>
inline T load(const char* p, bool little_endian) {
  T v;
  std::memcpy(&v, p, sizeof(T));
  return little_endian == kHostLittleEndian ? v : byte_swapped(v);
}

template <class T>
inline void store_le(char* p, T v) {
  if (!kHostLittleEndian) v = byte_swapped(v);
  std::memcpy(p, &v, sizeof(T));
}

}  // namespace vdbwrap::io::detail
