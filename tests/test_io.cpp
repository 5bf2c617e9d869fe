// Tests of the mesh file I/O layer (core/io): round trips, format features, every kind of bad
// input, and the real-world corpus in tests/data.
#include <gtest/gtest.h>

#include <cctype>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <initializer_list>
#include <random>
#include <string>
#include <vector>

#include "vdbwrap/io.h"
#include "vdbwrap/errors.h"
#include "vdbwrap/mesh.h"
#include "vdbwrap/source.h"

#ifndef VDBWRAP_TEST_DATA_DIR
#define VDBWRAP_TEST_DATA_DIR "tests/data"
#endif

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
using vdbwrap::io::write_mesh;

// ---- helpers ------------------------------------------------------------------------------

// Each test gets its own temporary directory (bad files are generated, never committed).
class IoTest : public ::testing::Test {
 protected:
  void SetUp() override {
    std::random_device rd;
    dir_ = fs::temp_directory_path() /
           ("vdbwrap_test_io_" + std::string(::testing::UnitTest::GetInstance()->current_test_info()->name()) + "_" +
            std::to_string(rd()));
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

bool contains(const std::string& text, const std::string& part) { return text.find(part) != std::string::npos; }

// Runs f, expects an Error of `kind` whose message contains every one of `parts`.
template <class F>
void expect_error(F&& f, ErrorKind kind, std::initializer_list<std::string> parts) {
  try {
    f();
    ADD_FAILURE() << "no error thrown";
  } catch (const Error& e) {
    EXPECT_EQ(int(e.kind()), int(kind)) << e.what();
    for (const std::string& p : parts)
      EXPECT_TRUE(contains(e.what(), p)) << "message: " << e.what() << "\nlacks: " << p;
  } catch (const std::exception& e) {
    ADD_FAILURE() << "unexpected exception: " << e.what();
  }
}

// Reading `file` must fail with InvalidInput; the message starts with the file name.
void expect_read_error(const std::string& file, std::initializer_list<std::string> parts) {
  expect_error([&] { read_mesh(file); }, ErrorKind::InvalidInput, parts);
  try {
    read_mesh(file);
  } catch (const Error& e) {
    EXPECT_EQ(std::string(e.what()).rfind(file + ": ", 0), 0u) << e.what();
  }
}

Vec3 corner(const Mesh& m, size_t t, int k) { return m.points[m.triangles[t][k]]; }

Vec3 sub(const Vec3& a, const Vec3& b) { return {a[0] - b[0], a[1] - b[1], a[2] - b[2]}; }
Vec3 cross(const Vec3& a, const Vec3& b) {
  return {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
}
double dot(const Vec3& a, const Vec3& b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }
double norm(const Vec3& a) { return std::sqrt(dot(a, a)); }
Vec3 tri_normal(const Mesh& m, size_t t) {  // twice the vector area
  return cross(sub(corner(m, t, 1), corner(m, t, 0)), sub(corner(m, t, 2), corner(m, t, 0)));
}

Vec3 as_float(const Vec3& p) {
  // volatile: keeps the compiler from folding the double->float->double round trip away.
  volatile float x = float(p[0]), y = float(p[1]), z = float(p[2]);
  return {double(x), double(y), double(z)};
}

// Two parts with awkward coordinates: a tetrahedron ("alpha") and a square ("beta").
Mesh two_part_mesh() {
  Mesh m;
  m.points = {{0.1, 0.2, 0.3},      {1.0 / 3.0, -2.5e-7, 12345.678901234},
              {-7.25, 1e-300, 2.0}, {3.0, 4.0, -5.0},
              {10, 10, 10},         {11, 10, 10},
              {11, 11, 10},         {10, 11, 10}};
  m.triangles = {{0, 1, 2}, {0, 3, 1}, {1, 3, 2}, {2, 3, 0}, {4, 5, 6}, {4, 6, 7}};
  m.triangle_part = {0, 0, 0, 0, 1, 1};
  m.part_names = {"alpha", "beta"};
  return m;
}

// Same, with the parts interleaved in triangle order.
Mesh interleaved_mesh() {
  Mesh m = two_part_mesh();
  m.triangle_part = {0, 1, 0, 1, 1, 0};
  return m;
}

void expect_same_indexed_mesh(const Mesh& a, const Mesh& b) {
  ASSERT_EQ(a.points.size(), b.points.size());
  for (size_t i = 0; i < a.points.size(); ++i) EXPECT_EQ(a.points[i], b.points[i]) << "point " << i;
  EXPECT_EQ(a.triangles, b.triangles);
}

// ---- round trips --------------------------------------------------------------------------

// OBJ groups each part's faces under one "g" line: interleaved parts come back sorted by part.
TEST_F(IoTest, ObjRoundTripKeepsPointsAndPartsWithFacesGroupedByPart) {
  Mesh m = interleaved_mesh();
  write_mesh(m, path("m.obj"));
  Mesh r = read_mesh(path("m.obj"));
  Mesh grouped = m;  // parts {0, 1, 0, 1, 1, 0}: part 0's faces, then part 1's, in order
  grouped.triangles = {m.triangles[0], m.triangles[2], m.triangles[5], m.triangles[1], m.triangles[3], m.triangles[4]};
  expect_same_indexed_mesh(grouped, r);
  EXPECT_EQ(r.part_names, m.part_names);
  EXPECT_EQ(r.triangle_part, (std::vector<int32_t>{0, 0, 0, 1, 1, 1}));
  EXPECT_FALSE(fs::exists(path("m.obj.tmp")));
}

TEST_F(IoTest, OffRoundTrip) {
  Mesh m = two_part_mesh();
  write_mesh(m, path("m.off"));
  Mesh r = read_mesh(path("m.off"));
  expect_same_indexed_mesh(m, r);
  EXPECT_TRUE(r.part_names.empty());  // OFF has no parts
}

TEST_F(IoTest, PlyRoundTripKeepsPartsAndNames) {
  Mesh m = interleaved_mesh();
  write_mesh(m, path("m.ply"));
  Mesh r = read_mesh(path("m.ply"));
  expect_same_indexed_mesh(m, r);
  EXPECT_EQ(r.part_names, m.part_names);
  EXPECT_EQ(r.triangle_part, m.triangle_part);
}

TEST_F(IoTest, PlyRoundTripWithoutParts) {
  Mesh m = two_part_mesh();
  m.part_names.clear();
  m.triangle_part.clear();
  write_mesh(m, path("m.ply"));
  Mesh r = read_mesh(path("m.ply"));
  expect_same_indexed_mesh(m, r);
  EXPECT_TRUE(r.part_names.empty());
  EXPECT_TRUE(r.triangle_part.empty());
}

TEST_F(IoTest, BinaryStlRoundTripIsUnweldedFloatAndNamedAfterTheFile) {
  Mesh m = two_part_mesh();
  m.part_names = {"only"};
  m.triangle_part.clear();
  write_mesh(m, path("single.stl"));
  // Binary: 84 + 50 bytes per triangle.
  EXPECT_EQ(fs::file_size(path("single.stl")), 84u + 50u * m.triangles.size());
  Mesh r = read_mesh(path("single.stl"));
  ASSERT_EQ(r.triangles.size(), m.triangles.size());
  EXPECT_EQ(r.points.size(), 3 * m.triangles.size());  // not welded
  for (size_t t = 0; t < m.triangles.size(); ++t)
    for (int k = 0; k < 3; ++k) EXPECT_EQ(corner(r, t, k), as_float(corner(m, t, k)));
  EXPECT_EQ(r.part_names, std::vector<std::string>{"single"});
  EXPECT_TRUE(r.triangle_part.empty());
}

TEST_F(IoTest, MultiPartStlRoundTripIsAsciiWithOneSolidPerPart) {
  Mesh m = two_part_mesh();
  write_mesh(m, path("parts.stl"));
  std::ifstream in(path("parts.stl"));
  std::string first_line;
  std::getline(in, first_line);
  EXPECT_EQ(first_line, "solid alpha");
  Mesh r = read_mesh(path("parts.stl"));
  ASSERT_EQ(r.triangles.size(), m.triangles.size());
  for (size_t t = 0; t < m.triangles.size(); ++t)
    for (int k = 0; k < 3; ++k) EXPECT_EQ(corner(r, t, k), corner(m, t, k));  // exact text
  EXPECT_EQ(r.part_names, m.part_names);
  EXPECT_EQ(r.triangle_part, m.triangle_part);
}

TEST_F(IoTest, WriteToBytesMatchesTheFile) {
  Mesh m = two_part_mesh();
  for (const char* name : {"b.stl", "b.obj", "b.off", "b.ply"}) {
    write_mesh(m, path(name));
    std::ifstream in(path(name), std::ios::binary);
    std::string file((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    EXPECT_EQ(file, vdbwrap::io::write_mesh_to_bytes(m, vdbwrap::io::format_from_extension(name))) << name;
  }
}

TEST_F(IoTest, WriteReplacesAnExistingFile) {
  write_file("m.off", "old content");
  write_mesh(two_part_mesh(), path("m.off"));
  EXPECT_EQ(read_mesh(path("m.off")).triangles.size(), 6u);
}

// ---- format features ----------------------------------------------------------------------

TEST(FormatTest, FromExtensionIsCaseInsensitive) {
  EXPECT_EQ(vdbwrap::io::format_from_extension("a/b.STL"), Format::Stl);
  EXPECT_EQ(vdbwrap::io::format_from_extension("x.Obj"), Format::Obj);
  EXPECT_EQ(vdbwrap::io::format_from_extension("x.off"), Format::Off);
  EXPECT_EQ(vdbwrap::io::format_from_extension("x.ply"), Format::Ply);
  EXPECT_EQ(vdbwrap::io::format_from_extension("x.stl.gz"), Format::Unknown);
  EXPECT_EQ(vdbwrap::io::format_from_extension("dir.stl/file"), Format::Unknown);
  EXPECT_EQ(vdbwrap::io::format_from_extension("noext"), Format::Unknown);
}

TEST(FormatTest, UnknownFormatIsDetectedFromContent) {
  const std::string obj = "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n";
  const std::string off = "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n";
  const std::string ply =
      "ply\nformat ascii 1.0\n"
      "element vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
      "element face 1\nproperty list uchar int vertex_indices\nend_header\n"
      "0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n";
  const std::string stl =
      "solid t\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nvertex 0 1 0\nendloop\n"
      "endfacet\nendsolid t\n";
  for (const std::string* text : {&obj, &off, &ply, &stl}) {
    Mesh m = read_mesh_from_bytes(*text, Format::Unknown, "upload");
    EXPECT_EQ(m.triangles.size(), 1u) << *text;
  }
}

TEST_F(IoTest, MultiSolidAsciiStlMakesOnePartPerSolid) {
  const std::string text =
      "solid first part\n"
      " facet normal 0 0 1\n  outer loop\n   vertex 0 0 0\n   vertex 1 0 0\n   vertex 0 1 0\n"
      "  endloop\n endfacet\n"
      "endsolid first part\n"
      "solid\n"  // unnamed: "solid2"
      " facet normal nan nan nan\n  outer loop\n   vertex 0 0 1\n   vertex 1 0 1\n   vertex 0 1 1\n"
      "  endloop\n endfacet\n"
      " facet normal 0 0 1\n  outer loop\n   vertex 0 0 2\n   vertex 1 0 2\n   vertex 0 1 2\n"
      "  endloop\n endfacet\n"
      "endsolid\n"
      "solid empty\nendsolid empty\n"  // no facets: no part
      "SOLID Upper\r\n FACET NORMAL 0 0 1\r\n  OUTER LOOP\r\n   VERTEX +1.5e+000 0 3\r\n"
      "   VERTEX 2 0 3\r\n   VERTEX 2 1 3\r\n  ENDLOOP\r\n ENDFACET\r\nENDSOLID Upper\r\n";
  Mesh m = read_mesh(write_file("multi.stl", text));
  ASSERT_EQ(m.triangles.size(), 4u);
  EXPECT_EQ(m.points.size(), 12u);
  EXPECT_EQ(m.part_names, (std::vector<std::string>{"first part", "solid2", "Upper"}));
  EXPECT_EQ(m.triangle_part, (std::vector<int32_t>{0, 1, 1, 2}));
  EXPECT_EQ(corner(m, 3, 0), (Vec3{1.5, 0, 3}));
}

TEST_F(IoTest, BinaryStlWhoseHeaderStartsWithSolidIsStillBinary) {
  Mesh m = two_part_mesh();
  m.part_names.clear();
  m.triangle_part.clear();
  std::string bytes = vdbwrap::io::write_mesh_to_bytes(m, Format::Stl);
  std::memcpy(&bytes[0], "solid trap", 10);
  Mesh r = read_mesh(write_file("trap.stl", bytes));
  EXPECT_EQ(r.triangles.size(), m.triangles.size());
  EXPECT_EQ(r.part_names, std::vector<std::string>{"trap"});
}

// The L-shaped hexagon (2,0) (2,1) (1,1) (1,2) (0,2) (0,0), area 3, counter-clockwise, in a
// tilted plane. A fan from its first vertex would make a flipped triangle.
TEST_F(IoTest, ObjGroupsAndNonConvexPolygon) {
  const double s = 1 / std::sqrt(2.0), t = 1 / std::sqrt(6.0);
  const Vec3 e1{s, s, 0}, e2{-t, t, 2 * t}, origin{5, -3, 2};
  const double l_shape[6][2] = {{2, 0}, {2, 1}, {1, 1}, {1, 2}, {0, 2}, {0, 0}};
  std::string text = "# test\nmtllib x.mtl\n";
  for (const auto& q : l_shape) {
    Vec3 p;
    for (int k = 0; k < 3; ++k) p[k] = origin[k] + q[0] * e1[k] + q[1] * e2[k];
    char line[200];
    std::snprintf(line, sizeof line, "v %.17g %.17g %.17g\n", p[0], p[1], p[2]);
    text += line;
  }
  text +=
      "v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nvn 0 0 1\n"
      "f 7 8 9\n"  // before any group: "default"
      "g empty\n"  // no faces: no part
      "o thing\n"
      "g L shape\nusemtl red\ns 1\n"
      "f 1/1/1 2/1/1 3//1 4 5 6\n"
      "g other\nf 9 8 7\n"
      "g L shape\nf 7 9 8\n"  // a group reopened keeps its part
      "l 1 2\n";
  Mesh m = read_mesh(write_file("groups.obj", text));
  EXPECT_EQ(m.part_names, (std::vector<std::string>{"default", "L shape", "other"}));
  ASSERT_EQ(m.triangles.size(), 7u);
  EXPECT_EQ(m.triangle_part, (std::vector<int32_t>{0, 1, 1, 1, 1, 2, 1}));

  const Vec3 polygon_normal = cross(e1, e2);
  double area = 0;
  for (size_t i = 1; i <= 4; ++i) {
    Vec3 n = tri_normal(m, i);
    EXPECT_GT(dot(n, polygon_normal), 1e-9) << "triangle " << i << " is flipped or degenerate";
    EXPECT_NEAR(norm(n), std::abs(dot(n, polygon_normal)), 1e-9);  // lies in the plane
    area += norm(n) / 2;
    for (uint32_t v : m.triangles[i]) EXPECT_LT(v, 6u);
  }
  EXPECT_NEAR(area, 3.0, 1e-9);
}

// A clockwise five-pointed star (10 vertices, 5 reflex): every triangle must face -z and the
// areas must add up to the star's.
TEST_F(IoTest, ObjStarPolygonTriangulatesWithItsOwnOrientation) {
  const double kPi = std::acos(-1.0);
  std::string text;
  std::vector<std::array<double, 2>> star;
  for (int i = 0; i < 10; ++i) {
    double r = i % 2 ? 0.4 : 1.0, a = -i * kPi / 5;  // clockwise
    star.push_back({r * std::cos(a), r * std::sin(a)});
    text += "v " + std::to_string(star.back()[0]) + " " + std::to_string(star.back()[1]) + " 0\n";
  }
  text += "f 1 2 3 4 5 6 7 8 9 10\n";
  Mesh m = read_mesh(write_file("star.obj", text));
  ASSERT_EQ(m.triangles.size(), 8u);
  double expected = 0;  // shoelace, on the values as written
  for (size_t i = 0; i < 10; ++i) {
    const Vec3& a = m.points[i];
    const Vec3& b = m.points[(i + 1) % 10];
    expected += (a[0] * b[1] - b[0] * a[1]) / 2;
  }
  double area = 0;
  for (size_t i = 0; i < m.triangles.size(); ++i) {
    Vec3 n = tri_normal(m, i);
    EXPECT_LT(n[2], 0) << "triangle " << i;
    area += n[2] / 2;
  }
  EXPECT_LT(expected, 0);
  EXPECT_NEAR(area, expected, 1e-12);
}

TEST_F(IoTest, DegeneratePolygonFallsBackToAFan) {
  Mesh m = read_mesh(write_file("line.obj", "v 0 0 0\nv 1 0 0\nv 2 0 0\nv 3 0 0\nv 4 0 0\nf 1 2 3 4 5\n"));
  EXPECT_EQ(m.triangles, (std::vector<Tri>{{0, 1, 2}, {0, 2, 3}, {0, 3, 4}}));
}

TEST_F(IoTest, ObjNegativeIndicesAreRelative) {
  Mesh m = read_mesh(write_file("neg.obj",
                                "v 0 0 0\nv 1 0 0\nv 0 1 0\nf -3 -2 -1\n"
                                "v 0 0 1\nf -4/1 -1//2 -3/3/3\n"));
  EXPECT_EQ(m.triangles, (std::vector<Tri>{{0, 1, 2}, {0, 3, 1}}));
  EXPECT_EQ(m.points[3], (Vec3{0, 0, 1}));
  EXPECT_EQ(m.part_names, std::vector<std::string>{"default"});
}

TEST_F(IoTest, ObjVertexColorsAndCrlfAreAccepted) {
  Mesh m = read_mesh(write_file("c.obj", "v 0 0 0 1 0 0\r\nv 1 0 0 0 1 0\r\nv 0 1 0 0 0 1\r\nf 1 2 3\r\n"));
  EXPECT_EQ(m.points[1], (Vec3{1, 0, 0}));
  EXPECT_EQ(m.triangles.size(), 1u);
}

TEST_F(IoTest, OffWithCommentsColorsAndPolygons) {
  const std::string text =
      "# comment before the keyword\n"
      "COFF 5 2 0  # counts on the keyword line\n"
      "\n"
      "0 0 0 255 0 0 255\n1 0 0 255 0 0 255\n1 1 0 255 0 0 255\n"
      "0 1 0 255 0 0 255  # last of the quad\n"
      "0.5 0.5 1 0 0 0 255\n"
      "4 0 1 2 3 1 0 0\n"
      "3 0 1 4\n"
      "# trailing comment\n";
  Mesh m = read_mesh(write_file("c.off", text));
  EXPECT_EQ(m.points.size(), 5u);
  EXPECT_EQ(m.triangles, (std::vector<Tri>{{0, 1, 2}, {0, 2, 3}, {0, 1, 4}}));
}

TEST_F(IoTest, OffCountsOnTheirOwnLineOrWithoutKeyword) {
  for (const std::string& header : {std::string("OFF\n3 1 3\n"), std::string("3 1 0\n")}) {
    Mesh m = read_mesh(write_file("t.off", header + "0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n"));
    EXPECT_EQ(m.triangles.size(), 1u) << header;
  }
}

// Big-endian binary PLY written byte by byte, with properties of many types to skip.
std::string big_endian_ply() {
  std::string out =
      "ply\n"
      "format binary_big_endian 1.0\n"
      "comment written by hand\n"
      "element vertex 4\n"
      "property int flags\n"
      "property float x\n"
      "property float32 y\n"
      "property double z\n"
      "property list uchar float extra\n"
      "element face 2\n"
      "property float quality\n"
      "property list ushort uint vertex_indices\n"
      "property short part\n"
      "element edge 1\n"
      "property int a\n"
      "property list int uchar b\n"
      "end_header\n";
  auto be = [&](auto v) {
    char b[sizeof v];
    std::memcpy(b, &v, sizeof v);
    for (size_t i = sizeof v; i-- > 0;) out += b[i];  // tests run on little-endian hosts
  };
  const float xy[4][2] = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
  for (int i = 0; i < 4; ++i) {
    be(int32_t(-1));
    be(xy[i][0]);
    be(xy[i][1]);
    be(double(0.25 * i));
    out += char(2);  // a list of two floats
    be(1.5f);
    be(2.5f);
  }
  be(0.5f);  // quad, part 7
  be(uint16_t(4));
  for (uint32_t v : {0u, 1u, 2u, 3u}) be(v);
  be(int16_t(7));
  be(0.5f);  // triangle, part 3
  be(uint16_t(3));
  for (uint32_t v : {0u, 2u, 1u}) be(v);
  be(int16_t(3));
  be(int32_t(5));  // the edge
  be(int32_t(2));
  out += "\x01\x02";
  return out;
}

TEST_F(IoTest, PlyBigEndianBinaryWrittenByHand) {
  static_assert(__BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__, "big_endian_ply() assumes a little-endian host");
  Mesh m = read_mesh(write_file("be.ply", big_endian_ply()));
  ASSERT_EQ(m.points.size(), 4u);
  EXPECT_EQ(m.points[2], (Vec3{1, 1, 0.5}));
  EXPECT_EQ(m.points[3], (Vec3{0, 1, 0.75}));
  EXPECT_EQ(m.triangles, (std::vector<Tri>{{0, 1, 2}, {0, 2, 3}, {0, 2, 1}}));
  EXPECT_EQ(m.part_names, (std::vector<std::string>{"part7", "part3"}));
  EXPECT_EQ(m.triangle_part, (std::vector<int32_t>{0, 0, 1}));
}

TEST_F(IoTest, PlyAsciiWithMixedTypesAndNamedParts) {
  const std::string text =
      "ply\r\n"
      "format ascii 1.0\r\n"
      "comment vdbwrap_part 4 lid\r\n"
      "element vertex 4\r\n"
      "property int x\r\nproperty float32 y\r\nproperty float64 z\r\nproperty uchar red\r\n"
      "element face 2\r\n"
      "property list uchar int vertex_index\r\n"
      "property uint part\r\n"
      "end_header\r\n"
      "0 0 0 255\r\n1 0 0 255\r\n1 1.5 0 255\r\n0 1 -2e-3 255\r\n"
      "3 0 1 2 4\r\n3 0 2 3 9\r\n";
  Mesh m = read_mesh(write_file("a.ply", text));
  EXPECT_EQ(m.points[3], (Vec3{0, 1, -2e-3}));
  EXPECT_EQ(m.triangles, (std::vector<Tri>{{0, 1, 2}, {0, 2, 3}}));
  EXPECT_EQ(m.part_names, (std::vector<std::string>{"lid", "part9"}));
  EXPECT_EQ(m.triangle_part, (std::vector<int32_t>{0, 1}));
}

// ---- bad input ----------------------------------------------------------------------------

std::string binary_stl_header(uint32_t count) {
  std::string out(80, ' ');
  out.append(reinterpret_cast<const char*>(&count), 4);
  return out;
}

std::string binary_stl_record(float x) {
  float values[12] = {0, 0, 1, x, 0, 0, 1, 0, 0, 0, 1, 0};
  std::string out(reinterpret_cast<const char*>(values), sizeof values);
  return out + std::string(2, '\0');
}

const char* const kTriangleStl =
    "solid t\n"
    "facet normal 0 0 1\n"
    "outer loop\n"
    "vertex 0 0 0\n"
    "vertex %s 0 0\n"  // line 5
    "vertex 0 1 0\n"
    "endloop\n"
    "endfacet\n"
    "endsolid t\n";

std::string triangle_stl(const char* x) {
  char buf[512];
  std::snprintf(buf, sizeof buf, kTriangleStl, x);
  return buf;
}

TEST_F(IoTest, MissingFile) { expect_read_error(path("nope.stl"), {"cannot open", "No such file"}); }

TEST_F(IoTest, DirectoryInsteadOfFile) { expect_read_error(dir_.string(), {"is a directory"}); }

TEST_F(IoTest, EmptyFile) {
  for (const char* name : {"e.stl", "e.obj", "e.off", "e.ply", "e.xyz"})
    expect_read_error(write_file(name, ""), {"empty"});
}

TEST_F(IoTest, TruncatedBinaryStl) {
  std::string bytes = binary_stl_header(10);
  for (int i = 0; i < 5; ++i) bytes += binary_stl_record(1);
  expect_read_error(write_file("t.stl", bytes),
                    {"binary STL declares 10 triangles (needs 584 bytes) but the file has 334 bytes", "truncated"});
  expect_read_error(write_file("short.stl", std::string(40, '\x01')), {"truncated", "84"});
}

// A writer that left the count at 0 or stale: the whole records the file holds are read (as
// slicers do), and the mesh says so. Bytes past the last whole record stay an error, and so
// does a count above the records held (TruncatedBinaryStl).
TEST_F(IoTest, BinaryStlWithAStaleCountReadsTheRecordsItHolds) {
  for (uint32_t declared : {0u, 2u}) {
    std::string bytes = binary_stl_header(declared);
    for (int i = 0; i < 3; ++i) bytes += binary_stl_record(float(i + 1));
    const std::string path = write_file("stale.stl", bytes);
    const Mesh m = vdbwrap::io::read_mesh(path);
    EXPECT_EQ(m.triangles.size(), 3u);
    EXPECT_FLOAT_EQ(float(m.points[6][0]), 3.0f);
    ASSERT_EQ(m.notes.size(), 1u);
    EXPECT_NE(m.notes[0].find("declares " + std::to_string(declared) + " triangles but holds 3"), std::string::npos)
        << m.notes[0];
    EXPECT_NE(m.notes[0].find("stale.stl"), std::string::npos) << m.notes[0];
    // The report names it.
    const std::string json = vdbwrap::with_source("{}", vdbwrap::source_of(path, m));
    EXPECT_NE(json.find("holds 3 whole records"), std::string::npos) << json;
  }
  std::string bytes = binary_stl_header(2);
  for (int i = 0; i < 3; ++i) bytes += binary_stl_record(1);
  expect_read_error(write_file("long.stl", bytes + "tail"),
                    {"declares 2 triangles (needs 184 bytes)", "has 238 bytes", "too long"});
  // A file read as it says carries no note.
  EXPECT_TRUE(vdbwrap::io::read_mesh(write_file("ok.stl", binary_stl_header(3) + bytes.substr(84))).notes.empty());
}

TEST_F(IoTest, HugeCountsAreErrorsNotAllocations) {
  std::string stl = binary_stl_header(4000000000u) + std::string(1000, '\x01');
  expect_read_error(write_file("huge.stl", stl), {"declares 4000000000 triangles", "truncated"});

  const std::string ply =
      "ply\nformat binary_little_endian 1.0\nelement vertex 4000000000\nproperty float x\n"
      "property float y\nproperty float z\nelement face 1\nproperty list uchar int vertex_indices\n"
      "end_header\n" +
      std::string(1000, '\x01');
  expect_read_error(write_file("huge.ply", ply), {"declares 4000000000 vertex elements", "1000 bytes"});

  const std::string ascii_ply =
      "ply\nformat ascii 1.0\n"
      "element vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
      "element face 1\nproperty list uint int vertex_indices\nend_header\n"
      "0 0 0\n1 0 0\n0 1 0\n4000000000 0 1 2\n";
  expect_read_error(write_file("huge_list.ply", ascii_ply), {"line 13", "face 0", "truncated"});

  const std::string off = "OFF\n4000000000 4000000000 0\n0 0 0\n";
  expect_read_error(write_file("huge.off", off), {"truncated", "declares 4000000000 vertices"});
}

TEST_F(IoTest, NonFiniteCoordinatesInAsciiStl) {
  for (const char* bad : {"nan", "inf", "-inf", "1e999"})
    expect_read_error(write_file("nan.stl", triangle_stl(bad)), {"line 5:", "non-finite coordinate"});
}

TEST_F(IoTest, NonFiniteCoordinatesInBinaryStl) {
  std::string bytes = binary_stl_header(2) + binary_stl_record(1) + binary_stl_record(std::nanf(""));
  expect_read_error(write_file("nan_bin.stl", bytes), {"triangle 1 has a non-finite coordinate"});
  // Records are parsed in parallel chunks: of several bad triangles far apart, the first in
  // the file is named.
  std::string many = binary_stl_header(60000);
  for (int t = 0; t < 60000; ++t)
    many += binary_stl_record(t == 20001 || t == 55555 || t == 41000 ? std::nanf("") : 1.0f);
  expect_read_error(write_file("nan_many.stl", many), {"triangle 20001 has a non-finite coordinate"});
}

TEST_F(IoTest, NonFiniteCoordinatesInObj) {
  expect_read_error(write_file("nan.obj", "v 0 0 0\nv 1 0 0\nv 0 NaN 0\nf 1 2 3\n"),
                    {"line 3: vertex 3 has a non-finite coordinate"});
  expect_read_error(write_file("inf.obj", "# c\nv inf 0 0\n"), {"line 2: vertex 1 has a non-finite coordinate"});
}

TEST_F(IoTest, NonFiniteCoordinatesInOffAndPly) {
  expect_read_error(write_file("nan.off", "OFF\n3 1 0\n0 0 0\n1 inf 0\n0 1 0\n3 0 1 2\n"),
                    {"line 4: vertex 1 has a non-finite coordinate"});
  std::string ply =
      "ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\n"
      "property float y\nproperty float z\nend_header\n";
  const float v[9] = {0, 0, 0, 1, 0, 0, 0, 1, INFINITY};
  ply.append(reinterpret_cast<const char*>(v), sizeof v);
  expect_read_error(write_file("inf.ply", ply), {"vertex 2 has a non-finite coordinate"});
}

TEST_F(IoTest, MalformedNumbers) {
  expect_read_error(write_file("bad.obj", "v 0 0 0\nv 1 abc 0\n"), {"line 2", "malformed number 'abc'"});
  expect_read_error(write_file("bad.stl", triangle_stl("1.0.0")), {"line 5", "malformed number '1.0.0'"});
  expect_read_error(write_file("bad.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 x 2\n"),
                    {"line 6", "face 0", "malformed vertex index 'x'"});
  expect_read_error(write_file("bad.ply",
                               "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\n"
                               "property float z\nend_header\n0 0 zz\n"),
                    {"line 8", "vertex 0", "malformed number 'zz'"});
}

TEST_F(IoTest, ZeroTriangles) {
  expect_read_error(write_file("z.obj", "v 0 0 0\nv 1 0 0\n"), {"contains no triangles"});
  expect_read_error(write_file("z.stl", "solid z\nendsolid z\n"), {"contains no triangles"});
  expect_read_error(write_file("zb.stl", binary_stl_header(0)), {"contains no triangles"});
  expect_read_error(write_file("z.off", "OFF\n1 0 0\n0 0 0\n"), {"contains no triangles"});
}

TEST_F(IoTest, ObjFaceIndexOutOfRangeNamesTheLine) {
  const std::string head = "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n";
  expect_read_error(write_file("r.obj", head + "f 1 2 4\n"), {"line 5:", "face index 4 is out of range", "3 vertices"});
  expect_read_error(write_file("n.obj", head + "\n\nf 1 2 -4\n"), {"line 7:", "face index -4 is out of range"});
  expect_read_error(write_file("0.obj", head + "f 0 1 2\n"), {"line 5:", "face index 0"});
  expect_read_error(write_file("2.obj", head + "f 1 2\n"), {"line 5:", "face has 2 vertices"});
  expect_read_error(write_file("m.obj", head + "f 1 2 x/1\n"), {"line 5:", "malformed face index 'x/1'"});
}

TEST_F(IoTest, OffAndPlyIndexOutOfRange) {
  expect_read_error(write_file("r.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 3\n"),
                    {"line 6", "face 0 has out-of-range vertex index 3"});
  std::string ply =
      "ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\n"
      "property float y\nproperty float z\nelement face 2\n"
      "property list uchar int vertex_indices\nend_header\n";
  const float v[9] = {0, 0, 0, 1, 0, 0, 0, 1, 0};
  ply.append(reinterpret_cast<const char*>(v), sizeof v);
  const int32_t f0[3] = {0, 1, 2}, f1[3] = {0, -1, 2};
  ply += char(3);
  ply.append(reinterpret_cast<const char*>(f0), sizeof f0);
  ply += char(3);
  ply.append(reinterpret_cast<const char*>(f1), sizeof f1);
  expect_read_error(write_file("r.ply", ply), {"face 1 has out-of-range vertex index -1"});
}

TEST_F(IoTest, TruncatedTextFiles) {
  std::string stl = triangle_stl("1");
  expect_read_error(write_file("t.stl", stl.substr(0, stl.find("vertex 0 1 0"))), {"truncated", "line 5"});
  expect_read_error(write_file("t.off", "OFF\n4 1 0\n0 0 0\n1 0 0\n0 1 0\n"),
                    {"truncated", "declares 4 vertices, the file has 3"});
  expect_read_error(write_file("f.off", "OFF\n3 2 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n"),
                    {"truncated", "declares 2 faces, the file has 1"});
  expect_read_error(write_file("t.ply",
                               "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
                               "property float z\nelement face 1\nproperty list uchar int vertex_indices\n"
                               "end_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1\n"),
                    {"face 0", "truncated"});
  expect_read_error(write_file("h.ply", "ply\nformat ascii 1.0\nelement vertex 3\n"), {"end_header"});
}

TEST_F(IoTest, TruncatedBinaryPly) {
  std::string bytes = vdbwrap::io::write_mesh_to_bytes(two_part_mesh(), Format::Ply);
  expect_read_error(write_file("t.ply", bytes.substr(0, bytes.size() - 7)), {"face 5", "truncated"});
}

TEST_F(IoTest, CountMismatchInTextFiles) {
  expect_read_error(write_file("m.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n3 0 2 1\n"),
                    {"line 7", "more data than", "1 faces"});
  expect_read_error(write_file("m.ply",
                               "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
                               "property float z\nelement face 1\nproperty list uchar int vertex_indices\n"
                               "end_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n3 0 2 1\n"),
                    {"line 14", "more data than the header declares"});
}

TEST_F(IoTest, StlFacetWithWrongVertexCount) {
  std::string two = triangle_stl("1");
  two.erase(two.find("vertex 0 1 0\n"), 13);
  expect_read_error(write_file("two.stl", two), {"line 7", "facet has 2 vertices"});
}

TEST_F(IoTest, GarbageBytes) {
  std::mt19937 rng(1234);
  std::string garbage(1000, '\0');
  for (char& c : garbage) c = char(rng());
  garbage[0] = '\x01';  // never "solid" or "ply" by chance
  garbage[500] = '\0';  // binary for sure
  expect_read_error(write_file("g.bin", garbage), {"unknown format"});
  expect_read_error(write_file("g.stl", garbage), {"binary STL declares", "but the file has 1000 bytes"});
  expect_read_error(write_file("g.obj", garbage), {"binary data"});
  expect_read_error(write_file("g.off", garbage), {"binary data"});
  expect_read_error(write_file("g.ply", garbage), {"not a PLY file"});
  expect_read_error(write_file("g.txt", "hello world\nthis is not a mesh\n"), {"unknown format"});
  expect_read_error(write_file("text.stl", "solid x\nhello world\n"), {"line 2", "unexpected 'hello'"});
}

TEST_F(IoTest, FromBytesUsesTheDisplayName) {
  expect_error([] { read_mesh_from_bytes("", Format::Stl, "upload #3"); }, ErrorKind::InvalidInput,
               {"upload #3: file is empty"});
  expect_error([] { read_mesh_from_bytes("v 0 0 0\nf 1 1 2\n", Format::Obj, "upload #4"); }, ErrorKind::InvalidInput,
               {"upload #4: line 2: face index 2 is out of range"});
}

TEST_F(IoTest, WriteErrors) {
  Mesh m = two_part_mesh();
  const std::string unknown = path("out.xyz");
  expect_error([&] { write_mesh(m, unknown); }, ErrorKind::OutputFailed, {unknown, "unknown output format"});
  const std::string unwritable = path("no/such/dir/out.stl");
  expect_error([&] { write_mesh(m, unwritable); }, ErrorKind::OutputFailed, {unwritable, "cannot create"});
  Mesh broken = m;
  broken.triangles[2][1] = 99;
  expect_error([&] { write_mesh(broken, path("broken.obj")); }, ErrorKind::OutputFailed,
               {"triangle 2 refers to vertex 99"});
  EXPECT_FALSE(fs::exists(path("broken.obj")));
  EXPECT_FALSE(fs::exists(path("broken.obj.tmp")));
}

// ---- corpus -------------------------------------------------------------------------------

struct CorpusCase {
  const char* file;
  size_t triangles;  // raw triangles: tests/data/CORPUS.md's count (quads of quadknot.obj and suzanne.ply
                     // split in 2)
  std::vector<std::string> parts;
};

class CorpusTest : public ::testing::TestWithParam<CorpusCase> {};

TEST_P(CorpusTest, TriangleCountAndParts) {
  const CorpusCase& c = GetParam();
  Mesh m = read_mesh(std::string(VDBWRAP_TEST_DATA_DIR) + "/" + c.file);
  EXPECT_EQ(m.triangles.size(), c.triangles);
  EXPECT_EQ(m.part_names, c.parts);
  const std::string name = c.file;
  const std::string ext = name.substr(name.rfind('.') + 1);
  if (ext == "stl" || ext == "STL") {
    EXPECT_EQ(m.points.size(), 3 * m.triangles.size());  // unwelded
  }
  for (const Tri& t : m.triangles)
    for (uint32_t v : t) ASSERT_LT(v, m.points.size());
}

std::vector<std::string> stem(const char* s) { return {s}; }
const std::vector<std::string> kDefault{"default"};

const CorpusCase kCorpus[] = {
    {"1002_tray_bottom.STL", 4520, stem("1002_tray_bottom")},  // ASCII, CRLF
    {"20mm-xyz-cube.stl", 260, stem("20mm-xyz-cube")},
    {"angle_block.STL", 704, stem("angle_block")},  // binary with a "solid" header
    {"box.STL", 8954, stem("box")},
    {"busted.STL", 3878, stem("busted")},
    {"capsule.obj", 10200, kDefault},
    {"fandisk.obj", 5750, kDefault},
    {"featuretype.STL", 3476, stem("featuretype")},
    {"fuze.obj", 1000, kDefault},
    {"idler_riser.STL", 1572, stem("idler_riser")},
    {"multibody.stl", 32, {"bodyB", "bodyA"}},  // ASCII, CRLF, 2 solids
    {"not_convex.obj", 96, kDefault},
    {"octagonal_pocket.stl", 3262, stem("octagonal_pocket")},
    {"plate_holes.STL", 1252, stem("plate_holes")},
    {"quadknot.obj", 2880, kDefault},  // 1440 quads
    {"round.stl", 1120, stem("round")},
    {"soup.stl", 100, stem("soup")},
    {"suzanne.ply", 968, {}},  // 468 quads + 32 triangles
    {"teapot.stl", 894, stem("teapot")},
    {"torus.STL", 8700, stem("torus")},
    {"tube.obj", 120, {"1"}},  // "g 0" has no faces
    {"two_objects_mixed_case_names.stl", 24, {"CubeExportedFromCAD", "TranslatedCubeExportedFromCAD"}},
    {"unit_sphere.STL", 1280, stem("unit_sphere")},
};

std::string corpus_test_name(const ::testing::TestParamInfo<CorpusCase>& param_info) {
  std::string n = param_info.param.file;
  for (char& ch : n)
    if (!std::isalnum(static_cast<unsigned char>(ch))) ch = '_';
  return n;
}

INSTANTIATE_TEST_SUITE_P(Files, CorpusTest, ::testing::ValuesIn(kCorpus), corpus_test_name);

}  // namespace
