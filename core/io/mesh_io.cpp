// Public entry points of the mesh I/O layer: format detection, whole-file reading, final
// checks, and atomic writing. The formats themselves live in stl/obj/off/ply/vtp/nastran.cpp.
#include "vdbwrap/io.h"

#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <memory>
#include <new>
#include <string_view>
#include <system_error>

#include "common/float_round.h"
#include "io/readers.h"

namespace vdbwrap::io {
namespace detail {

void fail(const std::string& name, const std::string& what) {
  throw Error(ErrorKind::InvalidInput, name + ": " + what);
}

void fail_line(const std::string& name, size_t line, const std::string& what) {
  fail(name, "line " + std::to_string(line) + ": " + what);
}

std::string quoted(std::string_view token) {
  constexpr size_t kMax = 40;
  std::string out = "'";
  for (char c : token.substr(0, kMax)) {
    unsigned char u = static_cast<unsigned char>(c);
    out += (u < 32 || u >= 127) ? '?' : c;  // printable ASCII: messages go to logs and RPCs
  }
  return out + (token.size() > kMax ? "...'" : "'");
}

std::string file_stem(const std::string& path) {
  size_t slash = path.find_last_of("/\\");
  std::string base = slash == std::string::npos ? path : path.substr(slash + 1);
  size_t dot = base.rfind('.');
  if (dot != std::string::npos && dot > 0) base.resize(dot);
  return base;
}

// Control bytes become spaces too: an ASCII STL solid name with one is refused as text on
// reading (looks_like_ascii_stl), so a written file did not read back (found by fuzzing).
std::string one_line(const std::string& name) {
  std::string out = name;
  for (char& c : out)
    if (static_cast<unsigned char>(c) < 32) c = ' ';
  return out;
}

DataArray& data_array(std::vector<DataArray>& arrays, const std::string& name, DataArray::Type type, size_t size) {
  for (DataArray& a : arrays)
    if (a.name == name) return a;
  arrays.push_back({name, type, std::vector<double>(size, NAN)});
  return arrays.back();
}

void pad_arrays(std::vector<DataArray>& arrays, size_t size) {
  for (DataArray& a : arrays)
    if (a.values.size() < size) a.values.resize(size, NAN);
}

void pad_mesh_data(MeshData* data, const Mesh& mesh) {
  if (!data) return;
  pad_arrays(data->point_data, mesh.points.size());
  pad_arrays(data->cell_data, mesh.triangles.size());
}

void check_point_count(const std::string& name, uint64_t count) {
  if (count > uint64_t(UINT32_MAX))
    fail(name, "has " + std::to_string(count) + " vertices, more than 32-bit indices can address");
}

}  // namespace detail

namespace {

using detail::fail;

// Format from the content, for names without a known extension.
Format sniff_format(std::string_view bytes) {
  // Before the NUL test: appended raw VTP data is binary.
  if (detail::looks_like_vtp(bytes)) return Format::Vtp;
  std::string_view head = detail::trim(bytes.substr(0, 4096));
  if (head.substr(0, 3) == "ply" && head.size() > 3 && (head[3] == '\n' || head[3] == '\r')) return Format::Ply;
  if (detail::is_binary_stl_size(bytes) || detail::looks_like_ascii_stl(bytes)) return Format::Stl;
  if (std::memchr(head.data(), '\0', head.size())) return Format::Unknown;
  detail::LineReader lines(head);
  std::string_view line;
  while (lines.next(line)) {
    detail::Tokens tokens(line);
    std::string_view first;
    if (!tokens.next(first) || first[0] == '#' || first[0] == '$') continue;
    if (first.size() >= 3 && first.substr(first.size() - 3) == "OFF") return Format::Off;
    static const char* const kNastranCards[] = {"BEGIN", "GRID", "CTRIA", "CQUAD", "PSHELL"};
    for (const char* k : kNastranCards)
      if (detail::iequals(first.substr(0, std::strlen(k)), k)) return Format::Nastran;
    static const char* const kObjKeywords[] = {"v", "vt", "vn", "f", "o", "g", "mtllib", "usemtl", "s"};
    for (const char* k : kObjKeywords)
      if (first == k) return Format::Obj;
    return Format::Unknown;
  }
  return Format::Unknown;
}

// Text formats with NUL bytes are binary files with the wrong name; say so rather than
// reporting "no triangles" after skipping every line as unknown.
void reject_binary_text(std::string_view bytes, const std::string& name, const char* format) {
  const void* nul = std::memchr(bytes.data(), '\0', bytes.size());
  if (nul)
    fail(name, std::string("contains binary data (a NUL byte at offset ") +
                   std::to_string(static_cast<const char*>(nul) - bytes.data()) + "), not " + format + " text");
}

Mesh parse(std::string_view bytes, Format format, const std::string& name, MeshData* data) {
  switch (format) {
    case Format::Stl:
      return detail::read_stl(bytes, name);
    case Format::Obj:
      reject_binary_text(bytes, name, "OBJ");
      return detail::read_obj(bytes, name);
    case Format::Off:
      reject_binary_text(bytes, name, "OFF");
      return detail::read_off(bytes, name);
    case Format::Ply:
      return detail::read_ply(bytes, name, data);
    case Format::Vtp:
      return detail::read_vtp(bytes, name, data);
    case Format::Nastran:
      reject_binary_text(bytes, name, "Nastran");
      return detail::read_nastran(bytes, name);
    case Format::Unknown:
      break;
  }
  fail(name, "unknown format (expected STL, OBJ, OFF, PLY or VTP)");
}

// A file's bytes in a buffer that is never zero-filled first: the read writes every byte
// used (a std::string's resize clears the whole buffer on one core before the read fills it again).
struct FileBytes {
  std::unique_ptr<char[]> data;
  size_t size = 0;
  std::string_view view() const { return {data.get(), size}; }
};

FileBytes read_whole_file(const std::string& path) {
  std::error_code ec;
  if (std::filesystem::is_directory(path, ec)) fail(path, "cannot open: is a directory");
  std::FILE* f = std::fopen(path.c_str(), "rb");
  if (!f) fail(path, std::string("cannot open file (") + std::strerror(errno) + ")");
  // Read straight into a buffer of the expected size; keep reading in case the file grew.
  const uintmax_t expected = std::filesystem::file_size(path, ec);
  size_t capacity = ec ? size_t(1) << 16 : size_t(expected) + 1;
  FileBytes bytes;
  try {
    bytes.data.reset(new char[capacity]);
    for (;;) {
      bytes.size += std::fread(bytes.data.get() + bytes.size, 1, capacity - bytes.size, f);
      if (bytes.size < capacity) break;  // end of file or error
      std::unique_ptr<char[]> larger(new char[2 * capacity]);
      std::memcpy(larger.get(), bytes.data.get(), bytes.size);
      bytes.data = std::move(larger), capacity *= 2;
    }
  } catch (...) {
    std::fclose(f);
    throw;
  }
  bool failed = std::ferror(f);
  std::fclose(f);
  if (failed) fail(path, "read error");
  return bytes;
}

// Writers index points and parts blindly; an inconsistent mesh must not make them read
// out of bounds.
void check_writable(const Mesh& mesh, Format format, const std::string& path) {
  auto bad = [&](const std::string& what) { throw Error(ErrorKind::OutputFailed, path + ": cannot write: " + what); };
  if (mesh.triangles.size() > UINT32_MAX) bad("more than 2^32-1 triangles");
  if (format == Format::Nastran && std::max(mesh.points.size(), mesh.triangles.size()) > detail::kNastranMaxId)
    bad("Nastran IDs have 8 digits: at most " + std::to_string(detail::kNastranMaxId) +
        " grid points and triangles (the mesh has " + std::to_string(mesh.points.size()) + " and " +
        std::to_string(mesh.triangles.size()) + ")");
  for (size_t t = 0; t < mesh.triangles.size(); ++t)
    for (uint32_t v : mesh.triangles[t])
      if (v >= mesh.points.size())
        bad("triangle " + std::to_string(t) + " refers to vertex " + std::to_string(v) + " but the mesh has " +
            std::to_string(mesh.points.size()));
  if (!mesh.triangle_part.empty() && mesh.triangle_part.size() != mesh.triangles.size())
    bad("triangle_part has " + std::to_string(mesh.triangle_part.size()) + " entries for " +
        std::to_string(mesh.triangles.size()) + " triangles");
  const size_t parts = std::max<size_t>(mesh.part_names.size(), 1);
  for (size_t t = 0; t < mesh.triangle_part.size(); ++t)
    if (mesh.triangle_part[t] < 0 || size_t(mesh.triangle_part[t]) >= parts)
      bad("triangle " + std::to_string(t) + " has part " + std::to_string(mesh.triangle_part[t]) +
          " but the mesh has " + std::to_string(mesh.part_names.size()) + " part names");
}

// Arrays beside the mesh: one value per point or triangle, names the formats can carry and
// the writers do not use themselves.
void check_data(const Mesh& mesh, Format format, const MeshData& data, const std::string& path) {
  auto bad = [&](const std::string& what) { throw Error(ErrorKind::OutputFailed, path + ": cannot write: " + what); };
  if (format != Format::Vtp && format != Format::Ply) bad("only .vtp and .ply carry point and cell data");
  const bool ply = format == Format::Ply;
  auto check = [&](const std::vector<DataArray>& arrays, size_t count, const char* what,
                   std::vector<std::string> names) {
    for (const DataArray& a : arrays) {
      if (a.name.empty() || !std::all_of(a.name.begin(), a.name.end(), [](char c) {
            return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '_';
          }))
        bad(std::string(what) + " array name " + detail::quoted(a.name) + " is not letters, digits and '_'");
      if (std::find(names.begin(), names.end(), a.name) != names.end())
        bad(std::string(what) + " array name " + a.name + " is taken (by the format or another array)");
      names.push_back(a.name);
      if (a.values.size() != count)
        bad(std::string(what) + " array " + a.name + " has " + std::to_string(a.values.size()) + " values for " +
            std::to_string(count) + (std::string(what) == "point" ? " points" : " triangles"));
    }
  };
  check(data.point_data, mesh.points.size(), "point",
        ply ? std::vector<std::string>{"x", "y", "z"} : std::vector<std::string>{});
  std::vector<std::string> cell_names;
  if (ply) cell_names = {"vertex_indices", "vertex_index"};
  if (ply && !mesh.part_names.empty()) cell_names.push_back("part");
  if (!ply) cell_names.push_back("part_id");
  check(data.cell_data, mesh.triangles.size(), "cell", cell_names);
}

bool stl_is_ascii(const Mesh& mesh, StlEncoding encoding) {
  switch (encoding) {
    case StlEncoding::Ascii:
      return true;
    case StlEncoding::Binary:
      return false;
    case StlEncoding::Auto:
      break;
  }
  return mesh.part_names.size() > 1;
}

void write_to(const Mesh& mesh, Format format, const WriteOptions& options, detail::Sink& out) {
  switch (format) {
    case Format::Stl:
      return detail::write_stl(mesh, out, stl_is_ascii(mesh, options.stl));
    case Format::Obj:
      return detail::write_obj(mesh, out);
    case Format::Off:
      return detail::write_off(mesh, out);
    case Format::Ply:
      return detail::write_ply(mesh, out, options.data);
    case Format::Vtp:
      return detail::write_vtp(mesh, out, options.data);
    case Format::Nastran:
      return detail::write_nastran(mesh, out);
    case Format::Unknown:
      break;
  }
}

}  // namespace

Format format_from_extension(std::string_view path) {
  size_t dot = path.rfind('.');
  size_t slash = path.find_last_of("/\\");
  if (dot == std::string_view::npos || (slash != std::string_view::npos && dot < slash)) return Format::Unknown;
  std::string_view ext = path.substr(dot + 1);
  if (detail::iequals(ext, "stl")) return Format::Stl;
  if (detail::iequals(ext, "obj")) return Format::Obj;
  if (detail::iequals(ext, "off")) return Format::Off;
  if (detail::iequals(ext, "ply")) return Format::Ply;
  if (detail::iequals(ext, "vtp")) return Format::Vtp;
  if (detail::iequals(ext, "nas") || detail::iequals(ext, "bdf")) return Format::Nastran;
  return Format::Unknown;
}

const DataArray* MeshData::point_array(const std::string& name) const {
  for (const DataArray& a : point_data)
    if (a.name == name) return &a;
  return nullptr;
}

const DataArray* MeshData::cell_array(const std::string& name) const {
  for (const DataArray& a : cell_data)
    if (a.name == name) return &a;
  return nullptr;
}

namespace {

Mesh read_mesh_with(std::string_view bytes, Format format, const std::string& display_name, MeshData* data) {
  if (bytes.empty()) fail(display_name, "file is empty");
  if (format == Format::Unknown) format = sniff_format(bytes);
  Mesh mesh;
  try {
    mesh = parse(bytes, format, display_name, data);
  } catch (const std::bad_alloc&) {
    fail(display_name, "not enough memory to load this mesh");
  }
  if (mesh.triangles.empty()) fail(display_name, "contains no triangles");
  // A single part needs no per-triangle list ("empty means everything is part 0").
  if (mesh.part_names.size() <= 1) mesh.triangle_part.clear();
  return mesh;
}

}  // namespace

Mesh read_mesh(const std::string& path) { return read_mesh(path, nullptr); }

Mesh read_mesh(const std::string& path, MeshData* data) {
  FileBytes bytes;
  try {
    bytes = read_whole_file(path);
  } catch (const std::bad_alloc&) {
    fail(path, "too large to load into memory");
  }
  if (data) *data = MeshData();
  return read_mesh_with(bytes.view(), format_from_extension(path), path, data);
}

Mesh read_mesh_from_bytes(std::string_view bytes, Format format, const std::string& display_name) {
  return read_mesh_with(bytes, format, display_name, nullptr);
}

std::string write_mesh_to_bytes(const Mesh& mesh, Format format, const WriteOptions& options) {
  if (format == Format::Unknown) throw Error(ErrorKind::OutputFailed, "unknown output format");
  check_writable(mesh, format, "output");
  if (options.data) check_data(mesh, format, *options.data, "output");
  detail::Sink sink;
  write_to(mesh, format, options, sink);
  return sink.take();
}

void write_mesh(const Mesh& mesh, const std::string& path, const WriteOptions& options) {
  auto failed = [&](const std::string& what) { throw Error(ErrorKind::OutputFailed, path + ": " + what); };
  Format format = format_from_extension(path);
  if (format == Format::Unknown) failed("unknown output format (use .stl, .obj, .off, .ply, .vtp, .nas or .bdf)");
  check_writable(mesh, format, path);
  if (options.data) check_data(mesh, format, *options.data, path);

  // Write beside the target, then rename: readers never see a half-written file.
  const std::string tmp = path + ".tmp";
  std::FILE* f = std::fopen(tmp.c_str(), "wb");
  if (!f) failed(std::string("cannot create ") + tmp + " (" + std::strerror(errno) + ")");
  bool ok = false;
  try {
    detail::Sink sink(f);
    write_to(mesh, format, options, sink);
    sink.flush();
    ok = !sink.failed();
  } catch (...) {
    std::fclose(f);
    std::remove(tmp.c_str());
    throw;
  }
  int saved_errno = ok ? 0 : errno;  // from the failed fwrite
  if (std::fclose(f) != 0 && ok) {
    ok = false;
    saved_errno = errno;
  }
  if (!ok) {
    std::remove(tmp.c_str());
    failed(std::string("write failed (") + std::strerror(saved_errno) + ")");
  }
  if (std::rename(tmp.c_str(), path.c_str()) != 0) {
    saved_errno = errno;
    std::remove(tmp.c_str());
    failed(std::string("cannot rename ") + tmp + " to the target (" + std::strerror(saved_errno) + ")");
  }
}

Mesh rounded_to_float(const Mesh& mesh) {
  Mesh out = mesh;
  for (Vec3& p : out.points) p = round_to_float(p);
  return out;
}

}  // namespace vdbwrap::io
