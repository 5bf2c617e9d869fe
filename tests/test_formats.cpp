// Tests of the CFD exchange formats of core/io: VTK XML PolyData (.vtp, read and write),
// Nastran bulk data (.nas/.bdf, write), STL solid names and encoding choice, OBJ groups.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "vdbwrap/io.h"
#include "vdbwrap/errors.h"
#include "vdbwrap/mesh.h"

namespace {

namespace fs = std::filesystem;
using vdbwrap::Error;
using vdbwrap::ErrorKind;
using vdbwrap::Mesh;
using vdbwrap::Tri;
using vdbwrap::Vec3;
using vdbwrap::io::Format;
using vdbwrap::io::read_mesh;
using vdbwrap::io::read_mesh_from_bytes;
using vdbwrap::io::StlEncoding;
using vdbwrap::io::write_mesh;
using vdbwrap::io::write_mesh_to_bytes;
using vdbwrap::io::WriteOptions;

// ---- helpers ------------------------------------------------------------------------------

class FormatsTest : public ::testing::Test {
 protected:
  void SetUp() override {
    std::random_device rd;
    dir_ = fs::temp_directory_path() /
           ("vdbwrap_test_formats_" + std::string(::testing::UnitTest::GetInstance()->current_test_info()->name()) +
            "_" + std::to_string(rd()));
    fs::create_directories(dir_);
  }
  void TearDown() override {
    std::error_code ec;
    fs::remove_all(dir_, ec);
  }
  std::string path(const std::string& name) const { return (dir_ / name).string(); }
  std::string write_file(const std::string& name, const std::string& bytes) const {
    std::string p = path(name);
    std::ofstream(p, std::ios::binary).write(bytes.data(), std::streamsize(bytes.size()));
    return p;
  }
  fs::path dir_;
};

std::string read_file(const std::string& p) {
  std::ifstream in(p, std::ios::binary);
  return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

bool contains(const std::string& text, const std::string& part) { return text.find(part) != std::string::npos; }

// Reading `file` fails with InvalidInput; the message starts with "FILE: " and holds `part`.
void expect_read_error(const std::string& file, const std::string& part) {
  try {
    read_mesh(file);
    ADD_FAILURE() << file << ": no error thrown (expected '" << part << "')";
  } catch (const Error& e) {
    EXPECT_EQ(int(e.kind()), int(ErrorKind::InvalidInput)) << e.what();
    EXPECT_EQ(std::string(e.what()).rfind(file + ": ", 0), 0u) << e.what();
    EXPECT_TRUE(contains(e.what(), part)) << "message: " << e.what() << "\nlacks: " << part;
  } catch (const std::exception& e) {
    ADD_FAILURE() << "unexpected exception: " << e.what();
  }
}

// Two parts, interleaved in triangle order, with coordinates that need all 17 digits.
Mesh interleaved_mesh() {
  Mesh m;
  m.points = {{0.1, 0.2, 0.3},      {1.0 / 3.0, -2.5e-7, 12345.678901234},
              {-7.25, 1e-300, 2.0}, {3.0, 4.0, -5.0},
              {10, 10, 10},         {11, 10, 10},
              {11, 11, 10},         {10, 11, 10}};
  m.triangles = {{0, 1, 2}, {4, 5, 6}, {0, 3, 1}, {4, 6, 7}, {1, 3, 2}, {2, 3, 0}};
  m.triangle_part = {0, 1, 0, 1, 0, 0};
  m.part_names = {"inlet duct", "wall <&\"'> \xc3\xa9"};  // XML specials and UTF-8
  return m;
}

// The mesh's triangles and parts with the faces stably sorted by part.
Mesh sorted_by_part(const Mesh& m) {
  std::vector<size_t> order(m.triangles.size());
  for (size_t i = 0; i < order.size(); ++i) order[i] = i;
  std::stable_sort(order.begin(), order.end(), [&](size_t a, size_t b) { return m.part_of(a) < m.part_of(b); });
  Mesh s = m;
  for (size_t i = 0; i < order.size(); ++i) {
    s.triangles[i] = m.triangles[order[i]];
    if (!m.triangle_part.empty()) s.triangle_part[i] = m.triangle_part[order[i]];
  }
  return s;
}

std::string base64(const std::string& bytes) {
  static const char* kAlphabet = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  for (size_t i = 0; i < bytes.size(); i += 3) {
    uint32_t group = uint32_t(uint8_t(bytes[i])) << 16;
    if (i + 1 < bytes.size()) group |= uint32_t(uint8_t(bytes[i + 1])) << 8;
    if (i + 2 < bytes.size()) group |= uint32_t(uint8_t(bytes[i + 2]));
    out += kAlphabet[(group >> 18) & 63];
    out += kAlphabet[(group >> 12) & 63];
    out += i + 1 < bytes.size() ? kAlphabet[(group >> 6) & 63] : '=';
    out += i + 2 < bytes.size() ? kAlphabet[group & 63] : '=';
  }
  return out;
}

// Bytes of `values` in big-endian order after a UInt32 big-endian byte count (VTK's default
// header type), as an inline "binary" array holds them before base64.
template <class T>
std::string big_endian_block(const std::vector<T>& values) {
  auto be = [](const void* p, size_t n) {
    std::string s(static_cast<const char*>(p), n);
    std::reverse(s.begin(), s.end());  // the test machine is little-endian (x86-64, arm64)
    return s;
  };
  uint32_t size = uint32_t(values.size() * sizeof(T));
  std::string out = be(&size, 4);
  for (const T& v : values) out += be(&v, sizeof(T));
  return out;
}

// ---- VTP: structure of what we write ------------------------------------------------------

// The XML header of a written VTP (everything before the appended data's '_').
struct VtpLayout {
  std::string xml;
  std::string appended;  // the bytes after '_'
};

VtpLayout split_vtp(const std::string& file) {
  size_t start = file.find("<AppendedData encoding=\"raw\">");
  EXPECT_NE(start, std::string::npos);
  size_t underscore = file.find('_', start);
  return {file.substr(0, underscore), file.substr(underscore + 1)};
}

// The attribute values of the first DataArray whose Name is `name`.
std::string array_tag(const std::string& xml, const std::string& name) {
  size_t at = xml.find("Name=\"" + name + "\"");
  if (at == std::string::npos) return "";
  size_t open = xml.rfind('<', at), close = xml.find('>', at);
  return xml.substr(open, close - open + 1);
}

uint64_t attribute_u64(const std::string& tag, const std::string& key) {
  size_t at = tag.find(key + "=\"");
  EXPECT_NE(at, std::string::npos) << key << " in " << tag;
  return std::strtoull(tag.c_str() + at + key.size() + 2, nullptr, 10);
}

uint64_t le_u64(const std::string& s, size_t at) {
  uint64_t v = 0;
  for (int i = 7; i >= 0; --i) v = (v << 8) | uint8_t(s[at + size_t(i)]);
  return v;
}

// Checks the file against the VTK XML PolyData layout that vtkXMLPolyDataReader expects,
// without our reader: root attributes, the arrays' types and names, appended blocks that
// are contiguous, sized by their UInt64 headers and hold the mesh's values.
TEST_F(FormatsTest, VtpFileHasTheVtkXmlPolyDataLayout) {
  const Mesh m = interleaved_mesh();
  write_mesh(m, path("m.vtp"));
  const std::string file = read_file(path("m.vtp"));
  const VtpLayout v = split_vtp(file);
  EXPECT_EQ(v.xml.rfind("<?xml version=\"1.0\"?>\n<VTKFile type=\"PolyData\"", 0), 0u);
  EXPECT_TRUE(contains(v.xml, "byte_order=\"LittleEndian\" header_type=\"UInt64\""));
  EXPECT_FALSE(contains(v.xml, "compressor"));
  EXPECT_TRUE(contains(v.xml, "NumberOfPoints=\"8\""));
  EXPECT_TRUE(contains(v.xml, "NumberOfPolys=\"6\""));

  const std::string points = array_tag(v.xml, "Points");
  EXPECT_TRUE(contains(points, "type=\"Float64\"") && contains(points, "NumberOfComponents=\"3\"")) << points;
  const std::string connectivity = array_tag(v.xml, "connectivity");
  const std::string offsets = array_tag(v.xml, "offsets");
  const std::string part_id = array_tag(v.xml, "part_id");
  EXPECT_TRUE(contains(part_id, "type=\"Int32\"")) << part_id;
  // The arrays sit in the elements VTK looks them up in.
  EXPECT_LT(v.xml.find("<Points>"), v.xml.find(points));
  EXPECT_LT(v.xml.find("<Polys>"), v.xml.find(connectivity));
  EXPECT_LT(v.xml.find("<CellData"), v.xml.find(part_id));
  EXPECT_LT(v.xml.find("<FieldData>"), v.xml.find("<Piece"));

  // Blocks: UInt64 byte count then the data, back to back from offset 0.
  const std::string* tags[] = {&points, &connectivity, &offsets, &part_id};
  const bool wide = contains(connectivity, "Int64");
  const size_t index_size = wide ? 8 : 4;
  const uint64_t sizes[] = {24 * 8, 3 * 6 * index_size, 6 * index_size, 4 * 6};
  uint64_t expected_offset = 0;
  for (int i = 0; i < 4; ++i) {
    const uint64_t offset = attribute_u64(*tags[i], "offset");
    EXPECT_EQ(offset, expected_offset) << *tags[i];
    ASSERT_LE(offset + 8, v.appended.size());
    EXPECT_EQ(le_u64(v.appended, offset), sizes[i]) << *tags[i];
    expected_offset = offset + 8 + sizes[i];
  }
  EXPECT_EQ(v.appended.substr(expected_offset), "\n  </AppendedData>\n</VTKFile>\n");

  // The values: doubles bit for bit, connectivity, offsets 3, 6, ..., part ids.
  for (size_t i = 0; i < 24; ++i) {
    double d;
    uint64_t bits = le_u64(v.appended, 8 + 8 * i);
    std::memcpy(&d, &bits, 8);
    EXPECT_EQ(d, m.points[i / 3][i % 3]) << i;
  }
  auto index_at = [&](uint64_t block, size_t i) {
    uint64_t value = 0;
    for (size_t b = index_size; b-- > 0;) value = (value << 8) | uint8_t(v.appended[block + 8 + i * index_size + b]);
    return value;
  };
  const uint64_t c0 = attribute_u64(connectivity, "offset"), o0 = attribute_u64(offsets, "offset");
  for (size_t t = 0; t < 6; ++t) {
    for (size_t k = 0; k < 3; ++k) EXPECT_EQ(index_at(c0, 3 * t + k), m.triangles[t][k]);
    EXPECT_EQ(index_at(o0, t), 3 * (t + 1));
  }

  // Part names: a String array of character codes, each name ended by 0.
  std::string names_tag = array_tag(v.xml, "part_names");
  EXPECT_TRUE(contains(names_tag, "type=\"String\"") && contains(names_tag, "NumberOfTuples=\"2\""));
  std::istringstream codes(v.xml.substr(v.xml.find('>', v.xml.find("Name=\"part_names\"")) + 1));
  std::vector<std::string> names(1);
  int code;
  while (names.size() <= 2 && codes >> code) {
    if (code == 0)
      names.emplace_back();
    else
      names.back() += char(code);
  }
  names.pop_back();
  EXPECT_EQ(names, m.part_names);
}

// ---- VTP: VTK's own reader ----------------------------------------------------------------

// VTK's Python reader, when Debian's python3-vtk9 is installed (a test-only check; the core does not
// use VTK). Prints points, cells, part_id values and part names.
const char* kVtkReadScript = R"(import sys
import vtk
r = vtk.vtkXMLPolyDataReader()
r.SetFileName(sys.argv[1])
r.Update()
if r.GetErrorCode() != 0:
    sys.exit(3)
d = r.GetOutput()
print(d.GetNumberOfPoints(), d.GetNumberOfPolys())
for i in range(d.GetNumberOfPoints()):
    print(*[repr(c) for c in d.GetPoint(i)])
ids = vtk.vtkIdList()
polys = d.GetPolys()
polys.InitTraversal()
while polys.GetNextCell(ids):
    print(*[ids.GetId(k) for k in range(ids.GetNumberOfIds())])
part = d.GetCellData().GetArray("part_id")
print(*[int(part.GetValue(i)) for i in range(part.GetNumberOfTuples())])
names = d.GetFieldData().GetAbstractArray("part_names")
print(names.GetNumberOfValues())
for i in range(names.GetNumberOfValues()):
    print(names.GetValue(i))
)";

TEST_F(FormatsTest, VtpIsReadByVtksXmlPolyDataReader) {
  if (std::system("/usr/bin/python3 -c 'import vtk' >/dev/null 2>&1") != 0)
    GTEST_SKIP() << "python3-vtk9 (Debian) not installed: only the structural check ran";
  const Mesh m = interleaved_mesh();
  write_mesh(m, path("m.vtp"));
  write_file("read.py", kVtkReadScript);
  const std::string command =
      "/usr/bin/python3 " + path("read.py") + " " + path("m.vtp") + " > " + path("out.txt") + " 2> " + path("err.txt");
  ASSERT_EQ(std::system(command.c_str()), 0) << read_file(path("err.txt"));
  // VTK's warnings and errors go to stderr (vtkOutputWindow) even when it returns data.
  EXPECT_EQ(read_file(path("err.txt")), "");
  std::istringstream out(read_file(path("out.txt")));
  size_t points = 0, polys = 0;
  out >> points >> polys;
  ASSERT_EQ(points, m.points.size());
  ASSERT_EQ(polys, m.triangles.size());
  for (const Vec3& p : m.points)
    for (double c : p) {
      std::string text;
      out >> text;
      EXPECT_EQ(std::strtod(text.c_str(), nullptr), c);  // Python's repr is exact
    }
  for (const Tri& t : m.triangles)
    for (uint32_t v : t) {
      uint32_t id = 0;
      out >> id;
      EXPECT_EQ(id, v);
    }
  for (int32_t part : m.triangle_part) {
    int32_t id = -1;
    out >> id;
    EXPECT_EQ(id, part);
  }
  size_t names = 0;
  out >> names;
  ASSERT_EQ(names, m.part_names.size());
  std::string line;
  std::getline(out, line);
  for (const std::string& name : m.part_names) {
    std::getline(out, line);
    EXPECT_EQ(line, name);
  }
}

// Files VTK's vtkXMLPolyDataWriter writes uncompressed in each of its data modes read back
// with their quad triangulated, their part_id values and their part names; its default
// (zlib-compressed) files are refused with a clear error.
const char* kVtkWriteScript = R"(import sys
import vtk
points = vtk.vtkPoints()
points.SetDataTypeToDouble()
for p in [(0, 0, 0), (1, 0, 0), (1, 1, 0), (0, 1, 0), (0.5, 0.5, 1.0 / 3.0)]:
    points.InsertNextPoint(p)
polys = vtk.vtkCellArray()
polys.InsertNextCell(4, [0, 1, 2, 3])
polys.InsertNextCell(3, [0, 1, 4])
polys.InsertNextCell(3, [1, 2, 4])
data = vtk.vtkPolyData()
data.SetPoints(points)
data.SetPolys(polys)
part = vtk.vtkIntArray()
part.SetName("part_id")
for v in [1, 0, 1]:
    part.InsertNextValue(v)
data.GetCellData().AddArray(part)
names = vtk.vtkStringArray()
names.SetName("part_names")
names.InsertNextValue("floor")
names.InsertNextValue("roof top")
data.GetFieldData().AddArray(names)
for mode in ["ascii", "binary", "raw", "base64", "zlib"]:
    w = vtk.vtkXMLPolyDataWriter()
    w.SetInputData(data)
    w.SetFileName(sys.argv[1] + "/" + mode + ".vtp")
    if mode != "zlib":
        w.SetCompressorTypeToNone()
    if mode == "ascii":
        w.SetDataModeToAscii()
    elif mode == "binary":
        w.SetDataModeToBinary()
    else:
        w.SetDataModeToAppended()
        w.SetEncodeAppendedData(mode == "base64")
    if w.Write() != 1:
        sys.exit(3)
)";

TEST_F(FormatsTest, VtpWrittenByVtkIsRead) {
  if (std::system("/usr/bin/python3 -c 'import vtk' >/dev/null 2>&1") != 0)
    GTEST_SKIP() << "python3-vtk9 (Debian) not installed";
  write_file("write.py", kVtkWriteScript);
  const std::string command = "/usr/bin/python3 " + path("write.py") + " " + dir_.string() + " 2> " + path("err.txt");
  ASSERT_EQ(std::system(command.c_str()), 0) << read_file(path("err.txt"));
  for (const char* mode : {"ascii", "binary", "raw", "base64"}) {
    SCOPED_TRACE(mode);
    const Mesh m = read_mesh(path(std::string(mode) + ".vtp"));
    ASSERT_EQ(m.points.size(), 5u);
    EXPECT_EQ(m.points[4], (Vec3{0.5, 0.5, 1.0 / 3.0}));
    ASSERT_EQ(m.triangles.size(), 4u);  // the quad makes two
    EXPECT_EQ(m.triangles[2], (Tri{0, 1, 4}));
    EXPECT_EQ(m.part_names, (std::vector<std::string>{"roof top", "floor"}));  // first appearance
    EXPECT_EQ(m.triangle_part, (std::vector<int32_t>{0, 0, 1, 0}));
  }
  expect_read_error(path("zlib.vtp"), "compressed VTP ('vtkZLibDataCompressor') is not supported");
}

// ---- VTP: round trips ---------------------------------------------------------------------

TEST_F(FormatsTest, VtpRoundTripKeepsPointsTrianglesPartsAndNames) {
  const Mesh m = interleaved_mesh();
  write_mesh(m, path("m.vtp"));
  const Mesh r = read_mesh(path("m.vtp"));
  EXPECT_EQ(r.points, m.points);  // Float64: exact
  EXPECT_EQ(r.triangles, m.triangles);
  EXPECT_EQ(r.part_names, m.part_names);
  EXPECT_EQ(r.triangle_part, m.triangle_part);
  EXPECT_EQ(read_file(path("m.vtp")), write_mesh_to_bytes(m, Format::Vtp));
}

TEST_F(FormatsTest, VtpRoundTripOfOnePartAndOfNoParts) {
  Mesh one = interleaved_mesh();
  one.triangle_part.clear();
  one.part_names = {"fluid"};
  Mesh r = read_mesh(write_file("one.vtp", write_mesh_to_bytes(one, Format::Vtp)));
  EXPECT_EQ(r.triangles, one.triangles);
  EXPECT_EQ(r.part_names, std::vector<std::string>{"fluid"});
  EXPECT_TRUE(r.triangle_part.empty());

  Mesh none = one;
  none.part_names.clear();
  const std::string bytes = write_mesh_to_bytes(none, Format::Vtp);
  EXPECT_FALSE(contains(bytes, "part_id"));
  r = read_mesh(write_file("none.vtp", bytes));
  EXPECT_EQ(r.points, none.points);
  EXPECT_EQ(r.triangles, none.triangles);
  EXPECT_TRUE(r.part_names.empty());
}

TEST_F(FormatsTest, VtpIsDetectedByExtensionAndByContent) {
  EXPECT_EQ(vdbwrap::io::format_from_extension("a/b.VTP"), Format::Vtp);
  EXPECT_EQ(vdbwrap::io::format_from_extension("model.Nas"), Format::Nastran);
  EXPECT_EQ(vdbwrap::io::format_from_extension("model.BDF"), Format::Nastran);
  const Mesh m = interleaved_mesh();
  const Mesh r = read_mesh(write_file("upload.bin", write_mesh_to_bytes(m, Format::Vtp)));
  EXPECT_EQ(r.triangles, m.triangles);
  EXPECT_EQ(r.part_names, m.part_names);
}

// ---- VTP: files from other tools ----------------------------------------------------------

// ASCII arrays, Float32 points, a quad and a non-convex pentagon, a triangle strip, a vertex
// and a line cell before them (they shift the cell data), part_id without part names.
TEST_F(FormatsTest, VtpAsciiWithPolygonsStripsAndCellDataFromAnotherTool) {
  const std::string text = R"(<?xml version="1.0"?>
<!-- written by hand, like a small script would -->
<VTKFile type='PolyData' version="0.1" byte_order="LittleEndian">
  <PolyData>
    <Piece NumberOfPoints="9" NumberOfVerts="1" NumberOfLines="1" NumberOfStrips="1" NumberOfPolys="2">
      <Points>
        <DataArray type="Float32" NumberOfComponents="3" format="ascii">
          0 0 0  1 0 0  1 1 0  0 1 0
          2 0 0  4 0 0  4 2 0  3 1 0  2 2 0
        </DataArray>
      </Points>
      <CellData Scalars="part_id">
        <DataArray type="Int32" Name="part_id" format="ascii">9 9 7 3 5</DataArray>
      </CellData>
      <Verts>
        <DataArray type="Int32" Name="connectivity" format="ascii">0</DataArray>
        <DataArray type="Int32" Name="offsets" format="ascii">1</DataArray>
      </Verts>
      <Lines>
        <DataArray type="Int32" Name="connectivity" format="ascii">0 1</DataArray>
        <DataArray type="Int32" Name="offsets" format="ascii">2</DataArray>
      </Lines>
      <Strips>
        <DataArray type="Int64" Name="connectivity" format="ascii">0 1 3 2</DataArray>
        <DataArray type="Int64" Name="offsets" format="ascii">4</DataArray>
      </Strips>
      <Polys>
        <DataArray type="Int64" Name="connectivity" format="ascii">0 1 2 3  4 5 6 7 8</DataArray>
        <DataArray type="Int64" Name="offsets" format="ascii">4 9</DataArray>
      </Polys>
    </Piece>
  </PolyData>
</VTKFile>
)";
  const Mesh m = read_mesh(write_file("tool.vtp", text));
  ASSERT_EQ(m.points.size(), 9u);
  EXPECT_EQ(m.points[6], (Vec3{4, 2, 0}));
  // Quad: 2 triangles (part 7), pentagon: 3 (part 3), strip: 2 (part 5); vertex and line skipped.
  ASSERT_EQ(m.triangles.size(), 7u);
  EXPECT_EQ(m.part_names, (std::vector<std::string>{"part7", "part3", "part5"}));
  EXPECT_EQ(m.triangle_part, (std::vector<int32_t>{0, 0, 1, 1, 1, 2, 2}));
  // Every triangle faces +z like its polygon; the non-convex pentagon's area is kept.
  double pentagon_area = 0;
  for (size_t t = 0; t < m.triangles.size(); ++t) {
    const Vec3 &a = m.points[m.triangles[t][0]], &b = m.points[m.triangles[t][1]], &c = m.points[m.triangles[t][2]];
    const double z = (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]);
    EXPECT_GT(z, 0) << "triangle " << t;
    if (m.triangle_part[t] == 1) pentagon_area += z / 2;
  }
  EXPECT_NEAR(pentagon_area, 3.0, 1e-12);  // the 2x2 square minus the notch at (3,1): 4 - 1
}

// Inline base64 arrays, big-endian, UInt32 headers (VTK's defaults before 9), two pieces.
TEST_F(FormatsTest, VtpInlineBinaryBigEndianWithTwoPieces) {
  auto piece = [](double z) {
    return "<Piece NumberOfPoints=\"3\" NumberOfPolys=\"1\"><Points>"
           "<DataArray type=\"Float64\" NumberOfComponents=\"3\" format=\"binary\">" +
           base64(big_endian_block<double>({0, 0, z, 1, 0, z, 0, 1, z})) +
           "</DataArray></Points><Polys>"
           "<DataArray type=\"Int32\" Name=\"connectivity\" format=\"binary\">\n   " +
           base64(big_endian_block<int32_t>({0, 1, 2})) +
           "\n</DataArray><DataArray type=\"UInt8\" Name=\"offsets\" format=\"binary\">" +
           base64(big_endian_block<uint8_t>({3})) + "</DataArray></Polys></Piece>";
  };
  const std::string text = "<VTKFile type=\"PolyData\" version=\"0.1\" byte_order=\"BigEndian\"><PolyData>" +
                           piece(0.5) + piece(-1.25) + "</PolyData></VTKFile>";
  const Mesh m = read_mesh(write_file("be.vtp", text));
  ASSERT_EQ(m.points.size(), 6u);
  EXPECT_EQ(m.points[1], (Vec3{1, 0, 0.5}));
  EXPECT_EQ(m.points[5], (Vec3{0, 1, -1.25}));
  EXPECT_EQ(m.triangles, (std::vector<Tri>{{0, 1, 2}, {3, 4, 5}}));  // second piece shifted
  EXPECT_TRUE(m.part_names.empty());
}

// Appended base64 (VTK's "EncodeAppendedData"): each array is one base64 stream of header
// and data, at a character offset.
TEST_F(FormatsTest, VtpAppendedBase64) {
  auto le_block = [](auto values) {
    using T = typename decltype(values)::value_type;
    uint64_t size = values.size() * sizeof(T);
    std::string out(reinterpret_cast<const char*>(&size), 8);
    out.append(reinterpret_cast<const char*>(values.data()), size);
    return base64(out);
  };
  const std::string points = le_block(std::vector<float>{0, 0, 0, 2, 0, 0, 0, 2, 0, 2, 2, 0});
  const std::string connectivity = le_block(std::vector<int64_t>{0, 1, 3, 2});
  const std::string offsets = le_block(std::vector<int64_t>{4});
  const std::string part = le_block(std::vector<int16_t>{1});
  const std::string text =
      "<?xml version=\"1.0\"?>\n<VTKFile type=\"PolyData\" version=\"1.0\" header_type=\"UInt64\">\n"
      "<PolyData><FieldData><DataArray type=\"String\" Name=\"part_names\" NumberOfTuples=\"2\" "
      "format=\"ascii\">97 0 98 0</DataArray></FieldData>\n"
      "<Piece NumberOfPoints=\"4\" NumberOfPolys=\"1\"><CellData>"
      "<DataArray type=\"Int16\" Name=\"part_id\" format=\"appended\" offset=\"" +
      std::to_string(points.size() + connectivity.size() + offsets.size()) +
      "\"/></CellData><Points><DataArray type=\"Float32\" NumberOfComponents=\"3\" format=\"appended\" "
      "offset=\"0\"/></Points><Polys>"
      "<DataArray type=\"Int64\" Name=\"connectivity\" format=\"appended\" offset=\"" +
      std::to_string(points.size()) + "\"/><DataArray type=\"Int64\" Name=\"offsets\" format=\"appended\" offset=\"" +
      std::to_string(points.size() + connectivity.size()) +
      "\"/></Polys></Piece></PolyData>\n<AppendedData encoding=\"base64\">\n _" + points + connectivity + offsets +
      part + "\n</AppendedData></VTKFile>\n";
  const Mesh m = read_mesh(write_file("b64.vtp", text));
  ASSERT_EQ(m.points.size(), 4u);
  EXPECT_EQ(m.points[3], (Vec3{2, 2, 0}));
  EXPECT_EQ(m.triangles.size(), 2u);                       // the quad
  EXPECT_EQ(m.part_names, std::vector<std::string>{"b"});  // part_id 1 names the second entry
}

// ---- VTP: malformed input -----------------------------------------------------------------

std::string ascii_vtp(const std::string& piece_attributes, const std::string& points, const std::string& connectivity,
                      const std::string& offsets, const std::string& extra = "") {
  return "<?xml version=\"1.0\"?>\n<VTKFile type=\"PolyData\" version=\"1.0\">\n<PolyData>\n<Piece " +
         piece_attributes + ">\n" + extra +
         "<Points><DataArray type=\"Float64\" NumberOfComponents=\"3\" format=\"ascii\">" + points +
         "</DataArray></Points>\n<Polys><DataArray type=\"Int32\" Name=\"connectivity\" format=\"ascii\">" +
         connectivity + "</DataArray><DataArray type=\"Int32\" Name=\"offsets\" format=\"ascii\">" + offsets +
         "</DataArray></Polys>\n</Piece>\n</PolyData>\n</VTKFile>\n";
}

TEST_F(FormatsTest, MalformedVtpNamesTheFileAndTheProblem) {
  const std::string counts = "NumberOfPoints=\"3\" NumberOfPolys=\"1\"";
  const std::string tri = "0 0 0 1 0 0 0 1 0";
  const std::string good = ascii_vtp(counts, tri, "0 1 2", "3");
  ASSERT_EQ(read_mesh(write_file("good.vtp", good)).triangles.size(), 1u);

  const struct {
    const char* file;
    std::string text;
    const char* message;
  } cases[] = {
      {"truncated.vtp", good.substr(0, good.size() / 2), "truncated"},
      {"no_root.vtp", "<?xml version=\"1.0\"?>\n<Foo/>\n", "no <VTKFile>"},
      {"grid.vtp", "<VTKFile type=\"UnstructuredGrid\"><UnstructuredGrid/></VTKFile>", "only PolyData"},
      {"zlib.vtp", "<VTKFile type=\"PolyData\" compressor=\"vtkZLibDataCompressor\"><PolyData/></VTKFile>",
       "compressed VTP"},
      {"mismatch.vtp", "<VTKFile type=\"PolyData\"><PolyData></Piece></VTKFile>", "does not match"},
      {"attribute.vtp", "<VTKFile type=\"PolyData\" version=1.0><PolyData/></VTKFile>", "no quoted value"},
      {"points.vtp", ascii_vtp(counts, "0 0 0 1 0 0 0 1", "0 1 2", "3"), "holds 8 values (needs 9)"},
      {"number.vtp", ascii_vtp(counts, "0 0 0 1 0 0 0 1 zero", "0 1 2", "3"), "malformed number 'zero'"},
      {"nan.vtp", ascii_vtp(counts, "0 0 0 1 0 0 0 nan 0", "0 1 2", "3"), "point 2 has a non-finite"},
      {"index.vtp", ascii_vtp(counts, tri, "0 1 3", "3"), "refers to point 3 but the piece has 3"},
      {"negative.vtp", ascii_vtp(counts, tri, "0 -1 2", "3"), "refers to point -1"},
      {"offset.vtp", ascii_vtp(counts, tri, "0 1 2", "4"), "past the connectivity"},
      {"offsets.vtp", ascii_vtp(counts, tri, "0 1 2", "3 3"), "offsets has 2 values for 1 cells"},
      {"two.vtp", ascii_vtp(counts, tri, "0 1", "2"), "polygon 0 has 2 points"},
      {"float_ids.vtp", ascii_vtp(counts, tri, "0 1 2", "3").replace(good.find("Int32"), 5, "Float"),
       "must have an integer type"},
      {"count.vtp", ascii_vtp("NumberOfPoints=\"-3\" NumberOfPolys=\"1\"", tri, "0 1 2", "3"), "is not a count"},
      {"huge.vtp", ascii_vtp("NumberOfPoints=\"6148914691236517206\" NumberOfPolys=\"1\"", tri, "0 1 2", "3"),
       "more than a file of"},
      {"part_id.vtp",
       ascii_vtp(counts, tri, "0 1 2", "3",
                 "<CellData><DataArray type=\"Int32\" Name=\"part_id\" format=\"ascii\">1 2</DataArray></CellData>"),
       "'part_id' has 2 values for 1 cells"},
      {"no_appended.vtp",
       "<VTKFile type=\"PolyData\"><PolyData><Piece NumberOfPoints=\"1\"><Points><DataArray type=\"Float64\" "
       "NumberOfComponents=\"3\" format=\"appended\" offset=\"0\"/></Points></Piece></PolyData></VTKFile>",
       "has no <AppendedData>"},
      {"bad_format.vtp",
       ascii_vtp(counts, tri, "0 1 2", "3").replace(good.find("format=\"ascii\""), 14, "format=\"hex\""),
       "unknown format 'hex'"},
  };
  for (const auto& c : cases) {
    SCOPED_TRACE(c.file);
    expect_read_error(write_file(c.file, c.text), c.message);
  }
}

TEST_F(FormatsTest, MalformedAppendedVtpData) {
  const std::string good = write_mesh_to_bytes(interleaved_mesh(), Format::Vtp);
  const size_t underscore = good.find('_', good.find("<AppendedData"));
  // Cut inside the points block: its header promises more than follows.
  expect_read_error(write_file("cut.vtp", good.substr(0, underscore + 100)), "only");
  // An offset past the end.
  std::string far = good;
  far.replace(far.find("offset=\"0\""), 10, "offset=\"99999\"");
  expect_read_error(write_file("far.vtp", far), "past the end of the appended data");
  // A block size that is not a whole number of doubles.
  std::string odd = good;
  odd[underscore + 1] = char(uint8_t(odd[underscore + 1]) - 1);
  expect_read_error(write_file("odd.vtp", odd), "is not a whole number of Float64 values");
  // No '_' marker.
  std::string no_marker = good;
  no_marker[underscore] = 'x';
  expect_read_error(write_file("marker.vtp", no_marker), "must start with '_'");
}

// Every prefix and many corrupted copies of a written file: an InvalidInput error or a
// consistent mesh, never a crash or another exception (the readers are fuzzed too).
TEST_F(FormatsTest, CorruptedVtpNeverCrashes) {
  const std::string good = write_mesh_to_bytes(interleaved_mesh(), Format::Vtp);
  auto check = [&](const std::string& bytes) {
    try {
      Mesh m = read_mesh_from_bytes(bytes, Format::Vtp, "corrupt.vtp");
      for (const Tri& t : m.triangles)
        for (uint32_t v : t) ASSERT_LT(v, m.points.size());
    } catch (const Error& e) {
      ASSERT_EQ(int(e.kind()), int(ErrorKind::InvalidInput)) << e.what();
      ASSERT_EQ(std::string(e.what()).rfind("corrupt.vtp: ", 0), 0u) << e.what();
    }
  };
  for (size_t n = 0; n < good.size(); ++n) check(good.substr(0, n));
  std::mt19937 rng(42);
  for (int i = 0; i < 3000; ++i) {
    std::string bytes = good;
    for (int k = 0; k < 3; ++k) bytes[rng() % bytes.size()] = char(rng());
    check(bytes);
  }
}

// ---- Nastran ------------------------------------------------------------------------------

// A small bulk data parser for the test: GRID* (large field, "*" continuation), CTRIA3 and
// PSHELL (small field), "$ PID n: name" comments.
struct NastranDeck {
  std::map<int64_t, Vec3> grids;
  struct Element {
    int64_t id, pid, g[3];
  };
  std::vector<Element> trias;
  std::vector<int64_t> pshells;
  std::map<int64_t, std::string> pid_names;
  bool begin_bulk = false, enddata_last = false;
  std::vector<std::string> reals;  // every coordinate field as written
};

std::string field(const std::string& line, size_t start, size_t width) {
  std::string f = start < line.size() ? line.substr(start, width) : "";
  f.erase(0, f.find_first_not_of(' '));
  f.erase(f.find_last_not_of(' ') + 1);
  return f;
}

// Nastran reals: "1.5-3" means 1.5E-3.
double nastran_real(const std::string& s) {
  std::string t = s;
  for (size_t i = 1; i < t.size(); ++i)
    if ((t[i] == '+' || t[i] == '-') && t[i - 1] != 'E' && t[i - 1] != 'e') {
      t.insert(i, 1, 'E');
      break;
    }
  char* end = nullptr;
  double v = std::strtod(t.c_str(), &end);
  EXPECT_EQ(*end, '\0') << "not a real: '" << s << "'";
  return v;
}

NastranDeck parse_nastran(const std::string& text) {
  NastranDeck deck;
  std::istringstream in(text);
  std::string line, last;
  while (std::getline(in, line)) {
    EXPECT_LE(line.size(), 80u) << line;
    if (line.rfind("$ PID ", 0) == 0) {
      size_t colon = line.find(": ");
      deck.pid_names[std::stoll(line.substr(6, colon - 6))] = line.substr(colon + 2);
      continue;
    }
    if (line.empty() || line[0] == '$') continue;
    last = line;
    if (line == "BEGIN BULK") {
      EXPECT_TRUE(deck.grids.empty() && deck.trias.empty());
      deck.begin_bulk = true;
    } else if (line.rfind("GRID*", 0) == 0) {
      std::string next;
      EXPECT_TRUE(std::getline(in, next));
      EXPECT_EQ(next[0], '*') << next;
      const std::string x[3] = {field(line, 40, 16), field(line, 56, 16), field(next, 8, 16)};
      EXPECT_EQ(field(line, 24, 16), "0");  // CP: basic
      Vec3 p;
      for (int k = 0; k < 3; ++k) {
        deck.reals.push_back(x[k]);
        p[k] = nastran_real(x[k]);
      }
      deck.grids[std::stoll(field(line, 8, 16))] = p;
    } else if (line.rfind("CTRIA3", 0) == 0) {
      NastranDeck::Element e;
      e.id = std::stoll(field(line, 8, 8));
      e.pid = std::stoll(field(line, 16, 8));
      for (int k = 0; k < 3; ++k) e.g[k] = std::stoll(field(line, 24 + 8 * size_t(k), 8));
      deck.trias.push_back(e);
    } else if (line.rfind("PSHELL", 0) == 0) {
      deck.pshells.push_back(std::stoll(field(line, 8, 8)));
    } else if (line != "ENDDATA") {
      ADD_FAILURE() << "unexpected card: " << line;
    }
  }
  deck.enddata_last = last == "ENDDATA";
  return deck;
}

void expect_deck_matches(const NastranDeck& deck, const Mesh& m) {
  EXPECT_TRUE(deck.begin_bulk);
  EXPECT_TRUE(deck.enddata_last);
  ASSERT_EQ(deck.grids.size(), m.points.size());
  for (size_t i = 0; i < m.points.size(); ++i) {
    auto it = deck.grids.find(int64_t(i) + 1);
    ASSERT_NE(it, deck.grids.end()) << "GRID " << i + 1;
    for (int k = 0; k < 3; ++k) {
      const double want = m.points[i][size_t(k)], got = it->second[size_t(k)];
      // 16 characters: 1e-12 relative from 0.01 up (fixed notation holds 14 digits), and
      // 14 decimals (5e-15 absolute) below 1, where a sign and exponent take the room.
      EXPECT_LE(std::fabs(got - want), std::max(1e-12 * std::fabs(want), 5e-15))
          << "GRID " << i + 1 << " component " << k << ": " << want << " written as " << got;
    }
  }
  ASSERT_EQ(deck.trias.size(), m.triangles.size());
  for (size_t t = 0; t < m.triangles.size(); ++t) {
    EXPECT_EQ(deck.trias[t].id, int64_t(t) + 1);
    EXPECT_EQ(deck.trias[t].pid, m.part_of(t) + 1) << "CTRIA3 " << t + 1;
    for (int k = 0; k < 3; ++k) EXPECT_EQ(deck.trias[t].g[k], int64_t(m.triangles[t][size_t(k)]) + 1);
  }
  // Nastran reals need a decimal point; a 16-character field holds them.
  for (const std::string& r : deck.reals) {
    EXPECT_NE(r.find('.'), std::string::npos) << r;
    EXPECT_LE(r.size(), 16u) << r;
  }
}

TEST_F(FormatsTest, NastranHasOneGridPerPointOneCtria3PerTriangleAndPidsPerPart) {
  Mesh m = interleaved_mesh();
  m.part_names[1] = "wall";
  write_mesh(m, path("m.nas"));
  const NastranDeck deck = parse_nastran(read_file(path("m.nas")));
  expect_deck_matches(deck, m);
  EXPECT_EQ(deck.pshells, (std::vector<int64_t>{1, 2}));
  EXPECT_EQ(deck.pid_names, (std::map<int64_t, std::string>{{1, "inlet duct"}, {2, "wall"}}));
  // .bdf is the same format.
  write_mesh(m, path("m.bdf"));
  EXPECT_EQ(read_file(path("m.bdf")), read_file(path("m.nas")));
}

// Coordinates across magnitudes and signs keep 1e-12 relative precision in 16 characters.
TEST_F(FormatsTest, NastranLargeFieldKeepsDoublePrecision) {
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> mantissa(-1, 1);
  std::uniform_int_distribution<int> exponent(-12, 12);
  Mesh m;
  for (int i = 0; i < 3000; ++i) {
    Vec3 p;
    for (double& c : p) c = mantissa(rng) * std::pow(10.0, exponent(rng));
    m.points.push_back(p);
  }
  m.points.push_back({-123456789.12345678, 0.0, -0.0});
  m.points.push_back({1e15, -9.87654321e-99, 4.4e-300});
  for (uint32_t i = 0; i + 2 < m.points.size(); i += 3) m.triangles.push_back({i, i + 1, i + 2});
  const NastranDeck deck = parse_nastran(write_mesh_to_bytes(m, Format::Nastran));
  expect_deck_matches(deck, m);
  EXPECT_EQ(deck.pshells, std::vector<int64_t>{1});  // no parts: everything is PID 1
  EXPECT_TRUE(deck.pid_names.empty());
}

TEST_F(FormatsTest, NastranRoundTripKeepsPointsTrianglesAndNamedParts) {
  const Mesh m = interleaved_mesh();
  write_mesh(m, path("m.nas"));
  const Mesh r = read_mesh(path("m.nas"));
  ASSERT_EQ(r.points.size(), m.points.size());
  for (size_t i = 0; i < m.points.size(); ++i)
    for (int k = 0; k < 3; ++k)
      EXPECT_LE(std::fabs(r.points[i][k] - m.points[i][k]), std::max(1e-12 * std::fabs(m.points[i][k]), 5e-15));
  EXPECT_EQ(r.triangles, m.triangles);
  EXPECT_EQ(r.part_names, m.part_names);
  EXPECT_EQ(r.triangle_part, m.triangle_part);
}

// Small, large and free field cards, executive control before BEGIN BULK, a quad, a blank
// PID (the element ID), names from ANSA and HyperMesh comments, cards that are skipped.
TEST_F(FormatsTest, NastranFromOtherToolsInEveryFieldFormat) {
  const std::string text =
      "SOL 101\nCEND\nTITLE = from another tool\nBEGIN BULK\n"
      "$ANSA_NAME_COMMENT;7;PSHELL;floor pan;;NO;NO;NO;\n"
      "$HMNAME PROP                 9\"roof\"\n"
      "PSHELL         7       1     1.0\n"
      "MAT1           1  2.1+11              .3\n"
      "GRID           1              0.      0.      0.\n"
      "GRID,2,,1.,0.,0.\n"
      "GRID*                  3               0             1.0             1.0\n"
      "*                   -0.0\n"
      "GRID           4       0      0.     1.0     0.0       0\n"
      "GRID           5              .5      .5   1.5+0 $ an end-of-line comment\n"
      "CQUAD4        10       7       1       2       3       4\n"
      "CTRIA3        11       9       1       2       5\n"
      "CTRIA3,12,,2,3,5\n"
      "ENDDATA\n"
      "GRID          99              9.      9.      9.\n";  // after ENDDATA: ignored
  const Mesh m = read_mesh(write_file("tool.bdf", text));
  ASSERT_EQ(m.points.size(), 5u);
  EXPECT_EQ(m.points[1], (Vec3{1, 0, 0}));
  EXPECT_EQ(m.points[2], (Vec3{1, 1, 0}));
  EXPECT_EQ(m.points[4], (Vec3{0.5, 0.5, 1.5}));
  ASSERT_EQ(m.triangles.size(), 4u);  // the quad makes two
  EXPECT_EQ(m.triangles[2], (Tri{0, 1, 4}));
  EXPECT_EQ(m.part_names, (std::vector<std::string>{"floor pan", "roof", "pid12"}));
  EXPECT_EQ(m.triangle_part, (std::vector<int32_t>{0, 0, 1, 2}));
  // Detected by content too.
  EXPECT_EQ(read_mesh_from_bytes(text.substr(text.find("BEGIN BULK")), Format::Unknown, "upload").triangles.size(), 4u);
}

TEST_F(FormatsTest, MalformedNastranNamesTheFileAndTheLine) {
  const std::string grids =
      "GRID           1              0.      0.      0.\n"
      "GRID           2              1.      0.      0.\n";
  const struct {
    const char* file;
    std::string text;
    const char* message;
  } cases[] = {
      {"missing.nas", grids + "CTRIA3         1       1       1       2       3\n",
       "line 3: element 1 refers to GRID 3, which the file does not define"},
      {"twice.nas", grids + "GRID           2              1.      1.      0.\n", "line 3: GRID 2 is defined twice"},
      {"real.nas", "GRID           1              0.      x.      0.\n", "line 1: malformed coordinate 'x.'"},
      {"nan.nas", "GRID           1              0.     nan      0.\n", "non-finite coordinate"},
      {"cp.nas", "GRID           1       5      0.      0.      0.\n", "coordinate system 5"},
      {"id.nas", "GRID          -1              0.      0.      0.\n", "positive ID"},
      {"corners.nas", grids + "CTRIA3         1       1       1       2\n", "lacks grid 3"},
      {"none.nas", grids, "contains no triangles"},
  };
  for (const auto& c : cases) {
    SCOPED_TRACE(c.file);
    expect_read_error(write_file(c.file, c.text), c.message);
  }
}

// Every prefix and many corrupted copies of a written deck: an InvalidInput error naming the
// file, or a consistent mesh.
TEST_F(FormatsTest, CorruptedNastranNeverCrashes) {
  const std::string good = write_mesh_to_bytes(interleaved_mesh(), Format::Nastran);
  auto check = [&](const std::string& bytes) {
    try {
      Mesh m = read_mesh_from_bytes(bytes, Format::Nastran, "corrupt.nas");
      for (const Tri& t : m.triangles)
        for (uint32_t v : t) ASSERT_LT(v, m.points.size());
    } catch (const Error& e) {
      ASSERT_EQ(int(e.kind()), int(ErrorKind::InvalidInput)) << e.what();
      ASSERT_EQ(std::string(e.what()).rfind("corrupt.nas: ", 0), 0u) << e.what();
    }
  };
  for (size_t n = 0; n < good.size(); n += 7) check(good.substr(0, n));
  std::mt19937 rng(43);
  const char kNoise[] = "$*+,-.0123456789E \n\"";
  for (int i = 0; i < 3000; ++i) {
    std::string bytes = good;
    for (int k = 0; k < 3; ++k) bytes[rng() % bytes.size()] = kNoise[rng() % (sizeof kNoise - 1)];
    check(bytes);
  }
}

// ---- STL solid names and encoding -----------------------------------------------------------

TEST_F(FormatsTest, AsciiStlKeepsASingleSolidsName) {
  const std::string text =
      "solid inlet duct\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nvertex 0 1 0\n"
      "endloop\nendfacet\nendsolid inlet duct\n";
  Mesh m = read_mesh(write_file("in.stl", text));
  EXPECT_EQ(m.part_names, std::vector<std::string>{"inlet duct"});
  WriteOptions ascii;
  ascii.stl = StlEncoding::Ascii;
  write_mesh(m, path("out.stl"), ascii);
  const std::string written = read_file(path("out.stl"));
  EXPECT_EQ(written.rfind("solid inlet duct\n", 0), 0u);
  EXPECT_TRUE(contains(written, "endsolid inlet duct\n"));
  EXPECT_EQ(read_mesh(path("out.stl")).part_names, std::vector<std::string>{"inlet duct"});
}

TEST_F(FormatsTest, StlEncodingOption) {
  Mesh m = interleaved_mesh();
  WriteOptions binary, ascii;
  binary.stl = StlEncoding::Binary;
  ascii.stl = StlEncoding::Ascii;
  // Auto: ASCII for several parts, binary for one.
  EXPECT_EQ(write_mesh_to_bytes(m, Format::Stl).rfind("solid inlet duct\n", 0), 0u);
  // Binary even with parts (the names are lost): 84 + 50 bytes per triangle.
  EXPECT_EQ(write_mesh_to_bytes(m, Format::Stl, binary).size(), 84u + 50u * m.triangles.size());
  // ASCII keeps doubles exactly, one solid per part.
  Mesh one = m;
  one.part_names = {"only"};
  one.triangle_part.clear();
  EXPECT_EQ(write_mesh_to_bytes(one, Format::Stl).size(), 84u + 50u * m.triangles.size());
  Mesh r = read_mesh(write_file("one.stl", write_mesh_to_bytes(one, Format::Stl, ascii)));
  ASSERT_EQ(r.triangles.size(), one.triangles.size());
  for (size_t t = 0; t < r.triangles.size(); ++t)
    for (int k = 0; k < 3; ++k) EXPECT_EQ(r.points[r.triangles[t][k]], one.points[one.triangles[t][k]]);
  EXPECT_EQ(r.part_names, std::vector<std::string>{"only"});
  // A mesh without parts is one unnamed solid.
  Mesh none = one;
  none.part_names.clear();
  const std::string unnamed = write_mesh_to_bytes(none, Format::Stl, ascii);
  EXPECT_EQ(unnamed.rfind("solid\n", 0), 0u);
  EXPECT_EQ(read_mesh(write_file("none.stl", unnamed)).triangles.size(), none.triangles.size());
}

// ---- OBJ groups -----------------------------------------------------------------------------

TEST_F(FormatsTest, ObjWritesEachGroupOnceWithFacesSortedByPart) {
  Mesh m = interleaved_mesh();
  m.part_names.push_back("unused");  // a part without faces makes no group
  write_mesh(m, path("m.obj"));
  const std::string text = read_file(path("m.obj"));
  std::vector<std::string> groups;
  std::istringstream in(text);
  std::string line;
  while (std::getline(in, line))
    if (line.rfind("g ", 0) == 0) groups.push_back(line.substr(2));
  EXPECT_EQ(groups, (std::vector<std::string>{"inlet duct", "wall <&\"'> \xc3\xa9"}));
  const Mesh r = read_mesh(path("m.obj"));
  const Mesh expected = sorted_by_part(m);
  EXPECT_EQ(r.points, m.points);
  EXPECT_EQ(r.triangles, expected.triangles);  // stable: part 0's faces in their order, then part 1's
  EXPECT_EQ(r.triangle_part, (std::vector<int32_t>{0, 0, 0, 0, 1, 1}));
  EXPECT_EQ(r.part_names, (std::vector<std::string>{m.part_names[0], m.part_names[1]}));
}

}  // namespace
