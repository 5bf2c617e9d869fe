// The public mesh readers and writers: STL (binary and ASCII), OBJ, OFF, PLY (ASCII and
// binary), VTK XML PolyData (.vtp) and Nastran bulk data (.nas, .bdf).
#pragma once
#include <string>
#include <string_view>
#include <vector>

#include "vdbwrap/mesh.h"

namespace vdbwrap::io {

// New formats go at the end: the values are logged and picked by byte in the fuzzer.
enum class Format { Unknown, Stl, Obj, Off, Ply, Vtp, Nastran };

// How STL is written. Auto: binary (float coordinates), ASCII when the mesh has several parts
// (binary STL has no solids). Ascii always keeps the solid names and the doubles; Binary
// always writes floats and drops the part names.
enum class StlEncoding { Auto, Ascii, Binary };

// A named value per point or per triangle, carried beside a mesh by the VTP writer (point and
// cell data) and the PLY writer (vertex and face properties), and read back from those formats.
// Values are held as doubles (integer types exactly); `type` is how they are written.
struct DataArray {
  enum class Type { Float64, Int32, UInt8 };
  std::string name;  // letters, digits and '_'
  Type type = Type::Float64;
  std::vector<double> values;
};

struct MeshData {
  std::vector<DataArray> point_data;  // one value per point
  std::vector<DataArray> cell_data;   // one value per triangle
  // The array of that name, nullptr when there is none.
  const DataArray* point_array(const std::string& name) const;
  const DataArray* cell_array(const std::string& name) const;
};

// Per-format choices of the writers; formats without a choice ignore it.
struct WriteOptions {
  StlEncoding stl = StlEncoding::Auto;
  // Arrays written with the mesh: .vtp and .ply only (other formats refuse them). Names the
  // writer uses itself are refused: x, y, z, vertex_indices and (with parts) part in PLY,
  // part_id in VTP.
  const MeshData* data = nullptr;
};

// Format from a file name's extension (case-insensitive); Unknown when none matches.
Format format_from_extension(std::string_view path);

// Reads a mesh: format by extension, by content when the extension is unknown.
// Throws vdbwrap::Error(InvalidInput) with a message naming the file and, where it applies,
// the line (text formats) or the triangle / element index (binary), for: missing or empty
// file, unknown format, truncated data, counts that do not match the file size, NaN or
// infinite coordinates, out-of-range face indices, zero triangles.
// Line numbers count from 1; element and triangle indices of binary data count from 0.
// STL points are not welded (3 per facet); OBJ/OFF/PLY keep their indexing and polygons are
// triangulated (ear clipping). Parts: one per ASCII STL solid, one named after the file for
// binary STL, one per OBJ o/g group ("default" before any), one per distinct PLY face "part"
// value or VTP cell "part_id" value (named by the VTP's "part_names" field data), one per
// Nastran PID (named by "$ PID n: name", ANSA or HyperMesh comments); OFF, and PLY or VTP
// without those, have none. Nastran: GRID, CTRIA3/6, CQUAD4/8 in the basic coordinate system. Parts are in order of
// first appearance and only parts with triangles exist. With at most one part, triangle_part is left empty.
Mesh read_mesh(const std::string& path);
// The same, with the single-component numeric arrays of a .vtp (point and cell data) or the
// scalar properties of a .ply (vertex and face, besides x, y, z) in `data`; cell values follow
// their polygon onto each of its triangles; values missing from a piece are NaN. Other formats
// leave `data` empty.
Mesh read_mesh(const std::string& path, MeshData* data);

// The same from bytes already in memory (the server receives uploads this way).
// display_name is used in error messages.
Mesh read_mesh_from_bytes(std::string_view bytes, Format format, const std::string& display_name);

// Writes by the path's extension (.stl binary, .obj, .off, .ply binary little-endian, .vtp
// appended raw binary, .nas/.bdf Nastran bulk data with GRID* and CTRIA3).
// Part names are kept as STL solids (ASCII STL), OBJ groups (faces sorted by part, each group
// once), a per-face "part" property in PLY, cell data "part_id" plus field data "part_names"
// in VTP, and PIDs (part index + 1) with "$ PID n: name" comments in Nastran.
// Throws vdbwrap::Error(OutputFailed). The file is written to PATH.tmp, then renamed to PATH.
void write_mesh(const Mesh& mesh, const std::string& path, const WriteOptions& options = {});

// The same into memory (the server sends results this way). Throws Error(OutputFailed) for
// Format::Unknown or an inconsistent mesh.
std::string write_mesh_to_bytes(const Mesh& mesh, Format format, const WriteOptions& options = {});

// The mesh as binary STL stores it: every coordinate rounded to single precision (to check
// a result's validity as it will be written).
Mesh rounded_to_float(const Mesh& mesh);

// The input's feature curves (the polylines the wrap snaps to, WrapResult::feature_curves) as
// a file: OBJ lines or OpenFOAM's edge mesh (.eMesh, what snappyHexMesh and
// surfaceFeatureExtract read), for checking them or meshing with the same features.
enum class CurveFormat { Unknown, Obj, EMesh };

// From the extension, case-insensitive: .obj, .eMesh.
CurveFormat curve_format_from_extension(const std::string& path);

// Points shared by curves (corners, a closed curve's ends) are written once, so the edges form
// one connected graph; every consecutive pair of a curve's points is an edge.
// OBJ: `v` lines, then one `l` line per curve. eMesh: FoamFile header (class
// featureEdgeMesh), the points as a pointField, then the edges as an edgeList.
std::string feature_curves_to_text(const std::vector<std::vector<Vec3>>& curves, CurveFormat format);

// Writes the file (beside, then renamed). Throws Error(InvalidArgument) for another extension,
// Error(OutputFailed) when it cannot be written.
void write_feature_curves(const std::string& path, const std::vector<std::vector<Vec3>>& curves);

}  // namespace vdbwrap::io
