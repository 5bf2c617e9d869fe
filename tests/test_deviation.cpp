// Deviation fields: per-vertex signed distances to the reference, per-triangle defect flags, the
// .vtp / .ply files that carry them, and `--deviation` through the CLI.
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>

#include "check/distance_stats.h"
#include "common/vec.h"
#include "mesh/surface_index.h"
#include "vdbwrap/io.h"
#include "test_meshes.h"
#include "vdbwrap/deviation.h"

#ifndef VDBWRAP_CLI
#define VDBWRAP_CLI "vdbwrap"
#endif

using namespace vdbwrap;
using namespace vdbwrap::testing;
namespace fs = std::filesystem;

namespace {

// One wrap of fandisk for the tests that look at a real wrap (a few seconds).
const WrapResult& fandisk_wrap() {
  static const WrapResult r = [] {
    WrapParams p;
    p.base_size = Length::parse("1%");
    return wrap(io::read_mesh(data_path("fandisk.obj")), p);
  }();
  return r;
}

const Mesh& fandisk() {
  static const Mesh m = io::read_mesh(data_path("fandisk.obj"));
  return m;
}

double longest_edge(const Mesh& m) {
  double longest = 0;
  for (const Tri& t : m.triangles)
    for (int k = 0; k < 3; ++k) longest = std::max(longest, norm(m.points[t[(k + 1) % 3]] - m.points[t[k]]));
  return longest;
}

Mesh scaled_about_centre(Mesh m, double s) {
  Vec3 c{0, 0, 0};
  for (const Vec3& p : m.points) c = c + p;
  c = c * (1.0 / double(m.points.size()));
  for (Vec3& p : m.points) p = c + (p - c) * s;
  return m;
}

class TempDir {
 public:
  TempDir() {
    // A parameterised test's name holds a '/': one directory, not a parent left behind.
    std::string name = ::testing::UnitTest::GetInstance()->current_test_info()->name();
    std::replace(name.begin(), name.end(), '/', '_');
    path_ = fs::temp_directory_path() / ("vdbwrap_deviation_" + std::to_string(::getpid()) + "_" + name);
    fs::create_directories(path_);
  }
  ~TempDir() { fs::remove_all(path_); }
  std::string file(const std::string& name) const { return (path_ / name).string(); }

 private:
  fs::path path_;
};

int run_cli(const std::string& args, const TempDir& dir, std::string* err = nullptr) {
  const std::string err_path = dir.file("stderr.txt");
  const std::string cmd = std::string(VDBWRAP_CLI) + " " + args + " > " + dir.file("stdout.txt") + " 2> " + err_path;
  const int status = std::system(cmd.c_str());
  if (err) {
    std::ifstream in(err_path);
    *err = std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  }
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

}  // namespace

TEST(Deviation, VertexDistancesAgreeWithSampledDistanceOnFandisk) {
  const WrapResult& r = fandisk_wrap();
  const DeviationField field = measure_deviation(r.surface, fandisk(), &r.triangle_flags);
  ASSERT_EQ(field.distance.size(), r.surface.points.size());
  // Every vertex's |distance| is its distance to the input's nearest point.
  const DistanceStats at_vertices = check::distances_to(r.surface.points, fandisk(), field.diagonal);
  EXPECT_NEAR(field.max_abs, at_vertices.max, 1e-12 * field.diagonal);
  EXPECT_NEAR(field.mean_abs, at_vertices.mean, 1e-9 * field.diagonal);
  EXPECT_EQ(field.max_at, r.surface.points[field.max_vertex]);
  EXPECT_NEAR(std::fabs(field.distance[field.max_vertex]), field.max_abs, 0.0);
  // The sampled distance also samples inside the triangles, every one within an edge of a vertex
  // (distance to a surface changes no faster than the point moves).
  const DistanceStats sampled = sampled_distance(r.surface, fandisk());
  EXPECT_LE(field.max_abs, sampled.max * (1 + 1e-12));
  EXPECT_LE(sampled.max, field.max_abs + longest_edge(r.surface));
  EXPECT_NEAR(field.diagonal, sampled.diagonal, 1e-12 * sampled.diagonal);
}

TEST(Deviation, ReportCarriesWhereTheMaximumIs) {
  const WrapResult& r = fandisk_wrap();
  const DistanceStats& d = r.report.output_to_input;
  ASSERT_GT(d.samples, 0u);
  // max_at is a sample on the wrap, at distance max from the input.
  mesh::SurfaceIndex input(fandisk().points, fandisk().triangles);
  mesh::SurfaceIndex wrap_index(r.surface.points, r.surface.triangles);
  EXPECT_NEAR(std::sqrt(input.squared_distance(d.max_at)), d.max, 1e-12 * d.diagonal);
  EXPECT_LT(std::sqrt(wrap_index.squared_distance(d.max_at)), 1e-9 * d.diagonal);
  const std::string json = to_json(d);
  EXPECT_NE(json.find("\"max_at\""), std::string::npos) << json;
}

// The farthest point of a square from two short segments beside it lies where the two are
// equally far, on the square's rim: between any samples (a few thousandths apart here). The
// sampled max finds it to a ten-thousandth of the diagonal (the search climbs from the
// farthest lattice points), and no more: it is a distance of a point of the square.
TEST(Deviation, SampledMaxIsFoundBetweenTheSamples) {
  const Mesh square{{{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}}, {{0, 1, 2}, {0, 2, 3}}};
  const Vec3 a{-0.01, 0.3, 0}, b{0.93, 0.37, 0.05};
  Mesh marks;  // two slivers of triangles, each nearly a point
  for (const Vec3& p : {a, b}) {
    const uint32_t k = uint32_t(marks.points.size());
    marks.points.insert(marks.points.end(), {p, p + Vec3{1e-9, 0, 0}, p + Vec3{0, 1e-9, 0}});
    marks.triangles.push_back({k, k + 1, k + 2});
  }
  // Each of the two distances is convex, so the max of the nearer is at a corner or where the
  // plane between a and b crosses the rim: |p - a|^2 = |p - b|^2 is linear along an edge.
  double truth = 0;
  auto nearer = [&](const Vec3& p) { return std::min(norm(p - a), norm(p - b)); };
  for (int e = 0; e < 4; ++e) {
    const Vec3 &p = square.points[e], &q = square.points[(e + 1) % 4];
    truth = std::max(truth, nearer(p));
    // dot(p + t (q - p), 2 (b - a)) = |b|^2 - |a|^2
    const double t = (dot(b, b) - dot(a, a) - 2 * dot(p, b - a)) / (2 * dot(q - p, b - a));
    if (t >= 0 && t <= 1) truth = std::max(truth, nearer(p + (q - p) * t));
  }
  const DistanceStats d = sampled_distance(square, marks);
  EXPECT_NEAR(d.max, truth, 1e-4 * d.diagonal);
  EXPECT_LE(d.max, truth + 1e-12);
  EXPECT_NEAR(std::min(norm(d.max_at - a), norm(d.max_at - b)), d.max, 1e-6);
  EXPECT_NEAR(d.max_at[2], 0.0, 1e-12);
}

// A part loose deep inside a round housing: every query from it opens a large share of the
// housing's index, so the search for the max skips the triangles whose samples bound them
// below the max found (distance changes no faster than the point moves). What it reports must
// still be the farthest point: a dense lattice on every triangle finds nothing farther.
TEST(Deviation, SampledMaxOfAPartDeepInsideAHousingIsTheFarthestPoint) {
  const Mesh housing = icosphere_mesh(1.0, 4);
  Mesh part = sphere_mesh(0.25, 16, 32);
  for (Vec3& p : part.points) p = p + Vec3{0.2, -0.1, 0.05};
  const DistanceStats d = sampled_distance(part, housing);
  mesh::SurfaceIndex index(housing.points, housing.triangles);
  double dense = 0;
  constexpr int kSteps = 12;
  for (const Tri& t : part.triangles)
    for (int i = 0; i <= kSteps; ++i)
      for (int j = 0; i + j <= kSteps; ++j) {
        const Vec3 &a = part.points[t[0]], &b = part.points[t[1]], &c = part.points[t[2]];
        const Vec3 p = a + (b - a) * (double(i) / kSteps) + (c - a) * (double(j) / kSteps);
        dense = std::max(dense, std::sqrt(index.squared_distance(p)));
      }
  EXPECT_GT(dense, 0.6);  // the part is far inside, as the test means
  EXPECT_GE(d.max, dense - 1e-6 * d.diagonal);
  EXPECT_NEAR(std::sqrt(index.squared_distance(d.max_at)), d.max, 1e-12 * d.diagonal);
}

// The mean and p95 weigh the surface by area, not by vertex: a fan of a thousand small
// triangles at one corner of a plate (on the plate, as far as the rest from the reference)
// does not move them. A point of the file no triangle uses is no part of the surface.
TEST(Deviation, SampledMeanWeighsByAreaAndIgnoresStrayPoints) {
  const Mesh reference{{{-1, -1, -1}, {3, -1, -1}, {3, 3, -1}, {-1, 3, -1}}, {{0, 1, 2}, {0, 2, 3}}};
  Mesh plate{{{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}}, {{0, 1, 2}, {0, 2, 3}}};
  const DistanceStats flat = sampled_distance(plate, reference);
  EXPECT_NEAR(flat.mean, 1.0, 1e-9);
  // The corner (0, 0) to (0.01, 0.01) cut into a fan of 1000 triangles, lifted 0.5 off the plate.
  Mesh fanned = plate;
  const uint32_t centre = uint32_t(fanned.points.size());
  fanned.points.push_back({0.005, 0.005, 0.5});
  for (int i = 0; i < 1000; ++i) {
    const double t0 = 2 * M_PI * i / 1000, t1 = 2 * M_PI * (i + 1) / 1000;
    const uint32_t k = uint32_t(fanned.points.size());
    fanned.points.push_back({0.005 + 0.005 * std::cos(t0), 0.005 + 0.005 * std::sin(t0), 0.5});
    fanned.points.push_back({0.005 + 0.005 * std::cos(t1), 0.005 + 0.005 * std::sin(t1), 0.5});
    fanned.triangles.push_back({centre, k, k + 1});
  }
  fanned.points.push_back({100, 100, 100});  // a stray point
  const DistanceStats d = sampled_distance(fanned, reference);
  // The fan's area is a 13 thousandth of the plate's: the mean moves by about that.
  EXPECT_NEAR(d.mean, 1.0 + 0.5 * M_PI * 0.005 * 0.005, 1e-3);
  EXPECT_NEAR(d.p95, 1.0, 1e-9);
  EXPECT_NEAR(d.max, 1.5, 1e-9);
}

TEST(Deviation, AWrapLiesOutsideAClosedModel) {
  const WrapResult& r = fandisk_wrap();
  const DeviationField field = measure_deviation(r.surface, fandisk());
  EXPECT_EQ(field.sign, DistanceSign::Outside);
  size_t outside = 0;
  for (double d : field.distance) outside += d > 0 ? 1 : 0;
  EXPECT_GT(double(outside), 0.9 * double(field.distance.size())) << outside << " of " << field.distance.size();
  // The largest deviations (the wrap bridging concave corners) are outside.
  EXPECT_GT(field.distance[field.max_vertex], 0.0);
}

TEST(Deviation, SignFollowsTheClosedReferenceWhateverItsOrientation) {
  const Mesh sphere = icosphere_mesh(1.0, 3);
  const Mesh inner = scaled_about_centre(sphere, 0.8), outer = scaled_about_centre(sphere, 1.25);
  Mesh inward_mesh = sphere;  // closed, consistently oriented, facing in: + is still outside
  for (Tri& t : inward_mesh.triangles) std::swap(t[1], t[2]);
  const Mesh& inward = inward_mesh;
  for (const Mesh* ref : {&sphere, &inward}) {
    const DeviationField in = measure_deviation(inner, *ref), out = measure_deviation(outer, *ref);
    EXPECT_EQ(in.sign, DistanceSign::Outside);
    for (double d : in.distance) EXPECT_LT(d, -0.1);
    for (double d : out.distance) EXPECT_GT(d, 0.1);
  }
}

TEST(Deviation, OpenAndInconsistentReferencesSaySoInTheSign) {
  const Mesh sphere = icosphere_mesh(1.0, 3);
  const Mesh outer = scaled_about_centre(sphere, 1.25);
  Mesh open = sphere;
  open.triangles.resize(open.triangles.size() - 10);
  const DeviationField front = measure_deviation(outer, open);
  EXPECT_EQ(front.sign, DistanceSign::FrontSide);
  size_t positive = 0;
  for (double d : front.distance) positive += d > 0 ? 1 : 0;
  EXPECT_GT(double(positive), 0.9 * double(front.distance.size()));

  Mesh mixed = sphere;  // every other triangle turned: no orientation to trust
  for (size_t t = 0; t < mixed.triangles.size(); t += 2) std::swap(mixed.triangles[t][1], mixed.triangles[t][2]);
  const DeviationField unsigned_field = measure_deviation(outer, mixed);
  EXPECT_EQ(unsigned_field.sign, DistanceSign::Unsigned);
  for (double d : unsigned_field.distance) EXPECT_GE(d, 0.0);
  EXPECT_NEAR(unsigned_field.max_abs, measure_deviation(outer, sphere).max_abs, 1e-12);  // same geometry
}

TEST(Deviation, WrapFlagsAreTheFinalQualityAnalysis) {
  const WrapResult& r = fandisk_wrap();
  ASSERT_EQ(r.triangle_flags.size(), r.surface.triangles.size());
  size_t slivers = 0, small = 0, normals = 0, held = 0;
  for (uint8_t f : r.triangle_flags) {
    slivers += (f & kDefectSliver) ? 1 : 0;
    small += (f & kDefectSmallArea) ? 1 : 0;
    normals += (f & kDefectNormalDeviation) ? 1 : 0;
    held += (f & kDefectHeldBack) ? 1 : 0;
  }
  const QualityCounts& q = r.report.quality.after;
  EXPECT_EQ(slivers, q.slivers);
  EXPECT_EQ(small, q.small_area);
  EXPECT_EQ(normals, q.normal_deviation);
  if (r.report.nodes_held_back == 0) EXPECT_EQ(held, 0u);
}

TEST(Deviation, GeometricFlagsFindSliversAndDegenerateTriangles) {
  Mesh m = box_mesh({0, 0, 0}, {1, 1, 1});
  const uint32_t n = uint32_t(m.points.size());
  m.points.push_back({3, 0, 0});
  m.points.push_back({4, 0, 0});
  m.points.push_back({3.5, 0.001, 0});  // a needle: smallest angle far under 5 degrees
  m.points.push_back({5, 0, 0});        // with 3 and 4: on one line, zero area
  m.triangles.push_back({n, n + 1, n + 2});
  m.triangles.push_back({n, n + 1, n + 3});
  const std::vector<uint8_t> flags = geometric_defect_flags(m);
  ASSERT_EQ(flags.size(), m.triangles.size());
  for (size_t t = 0; t + 2 < m.triangles.size(); ++t) EXPECT_EQ(flags[t] & kDefectSliver, 0) << t;
  EXPECT_TRUE(flags[m.triangles.size() - 2] & kDefectSliver);
  EXPECT_TRUE(flags.back() & kDefectSelfIntersecting);
  EXPECT_EQ(defect_flag_names(kDefectSliver | kDefectHeldBack), (std::vector<std::string>{"sliver", "held_back"}));
}

TEST(Deviation, BadInputIsAClearError) {
  const Mesh sphere = icosphere_mesh(1.0, 2);
  std::vector<uint8_t> wrong(sphere.triangles.size() + 1, 0);
  try {
    measure_deviation(sphere, sphere, &wrong);
    FAIL() << "no error for flags of the wrong size";
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::InvalidArgument);
  }
  Mesh broken = sphere;
  broken.triangles.push_back({0, 1, uint32_t(broken.points.size())});
  EXPECT_THROW(measure_deviation(broken, sphere), Error);
  EXPECT_THROW(measure_deviation(sphere, broken), Error);
  // An empty reference: zero distances, no sign.
  const DeviationField none = measure_deviation(sphere, Mesh());
  EXPECT_EQ(none.sign, DistanceSign::Unsigned);
  EXPECT_EQ(none.max_abs, 0.0);

  TempDir dir;
  DeviationField field = measure_deviation(sphere, sphere);
  EXPECT_THROW(write_deviation(dir.file("a.stl"), sphere, field), Error);
  field.distance.pop_back();
  EXPECT_THROW(write_deviation(dir.file("a.vtp"), sphere, field), Error);
  EXPECT_FALSE(fs::exists(dir.file("a.vtp")));
  io::MeshData data;
  data.point_data.push_back({"distance", io::DataArray::Type::Float64, std::vector<double>(sphere.points.size(), 1.0)});
  io::WriteOptions options;
  options.data = &data;
  EXPECT_THROW(io::write_mesh(sphere, dir.file("a.obj"), options), Error);  // OBJ has no point data
  data.point_data.back().values.pop_back();
  EXPECT_THROW(io::write_mesh(sphere, dir.file("a.vtp"), options), Error);  // one value short
}

class DeviationFile : public ::testing::TestWithParam<std::string> {};

// The field written and read back by the project's own readers: the same mesh, parts and arrays.
TEST_P(DeviationFile, RoundTripsWithItsArrays) {
  const WrapResult& r = fandisk_wrap();
  const DeviationField field = measure_deviation(r.surface, fandisk(), &r.triangle_flags);
  TempDir dir;
  const std::string path = dir.file("field." + GetParam());
  write_deviation(path, r.surface, field);
  io::MeshData data;
  const Mesh back = io::read_mesh(path, &data);
  ASSERT_EQ(back.points, r.surface.points);
  ASSERT_EQ(back.triangles, r.surface.triangles);
  EXPECT_EQ(back.part_names, r.surface.part_names);
  const io::DataArray* distance = data.point_array("distance");
  const io::DataArray* percent = data.point_array("distance_percent_of_diagonal");
  const io::DataArray* part = data.cell_array("part");
  const io::DataArray* defects = data.cell_array("defects");
  ASSERT_TRUE(distance && percent && part && defects);
  EXPECT_EQ(distance->values, field.distance);
  ASSERT_EQ(percent->values.size(), field.distance.size());
  for (size_t i = 0; i < field.distance.size(); ++i)
    EXPECT_NEAR(percent->values[i], 100 * field.distance[i] / field.diagonal, 1e-12);
  ASSERT_EQ(part->values.size(), r.surface.triangles.size());
  ASSERT_EQ(defects->values.size(), r.surface.triangles.size());
  for (size_t t = 0; t < r.surface.triangles.size(); ++t) {
    EXPECT_EQ(part->values[t], r.surface.part_of(t));
    EXPECT_EQ(defects->values[t], r.triangle_flags[t]);
  }
}

INSTANTIATE_TEST_SUITE_P(Formats, DeviationFile, ::testing::Values("vtp", "ply"));

// ParaView's reader (VTK's vtkXMLPolyDataReader) finds the arrays, when python3-vtk9 is there.
TEST(Deviation, VtkReadsTheArrays) {
  if (std::system("/usr/bin/python3 -c 'import vtk' > /dev/null 2>&1") != 0) GTEST_SKIP() << "no python3-vtk9";
  const Mesh sphere = icosphere_mesh(1.0, 2);
  const Mesh outer = scaled_about_centre(sphere, 1.5);
  TempDir dir;
  const std::string path = dir.file("field.vtp");
  write_deviation(path, outer, measure_deviation(outer, sphere));
  const std::string script = dir.file("read.py");
  std::ofstream(script) << "import sys, vtk\n"
                           "r = vtk.vtkXMLPolyDataReader(); r.SetFileName(sys.argv[1]); r.Update()\n"
                           "o = r.GetOutput()\n"
                           "assert o.GetNumberOfPoints() == "
                        << outer.points.size()
                        << "\n"
                           "assert o.GetNumberOfCells() == "
                        << outer.triangles.size()
                        << "\n"
                           "d = o.GetPointData().GetArray('distance')\n"
                           "lo, hi = d.GetRange()\n"
                           "assert 0.4 < lo <= hi < 0.55, (lo, hi)\n"
                           "assert o.GetPointData().GetArray('distance_percent_of_diagonal') is not None\n"
                           "for name in ('part', 'defects'):\n"
                           "    a = o.GetCellData().GetArray(name)\n"
                           "    assert a is not None and a.GetNumberOfTuples() == o.GetNumberOfCells(), name\n";
  EXPECT_EQ(std::system(("/usr/bin/python3 " + script + " " + path).c_str()), 0);
}

TEST(Deviation, CheckWritesTheFieldThroughTheCli) {
  TempDir dir;
  const std::string field = dir.file("tray.vtp");
  const std::string tray = data_path("1002_tray_bottom.STL");
  // The tray against itself shifted a little: every distance is within the shift.
  Mesh shifted = io::read_mesh(tray);
  for (Vec3& p : shifted.points) p[2] += 0.5;
  io::write_mesh(shifted, dir.file("shifted.stl"));
  std::string err;
  ASSERT_EQ(run_cli("check " + dir.file("shifted.stl") + " --against " + tray + " --deviation " + field, dir, &err), 0)
      << err;
  io::MeshData data;
  const Mesh back = io::read_mesh(field, &data);
  const io::DataArray* distance = data.point_array("distance");
  ASSERT_TRUE(distance);
  ASSERT_EQ(distance->values.size(), back.points.size());
  for (double d : distance->values) EXPECT_LE(std::fabs(d), 0.5 + 1e-3);  // STL stores floats
}

TEST(Deviation, CliRefusesABadDeviationPathBeforeTheWork) {
  TempDir dir;
  const std::string out = dir.file("wrap.obj");
  std::string err;
  EXPECT_EQ(run_cli("wrap " + data_path("fandisk.obj") + " -o " + out + " --deviation " + dir.file("missing/field.vtp"),
                    dir, &err),
            2);
  EXPECT_NE(err.find("--deviation"), std::string::npos) << err;
  EXPECT_FALSE(fs::exists(out));  // refused before the wrap ran
  EXPECT_EQ(
      run_cli("wrap " + data_path("fandisk.obj") + " -o " + out + " --deviation " + dir.file("field.stl"), dir, &err),
      2);
  EXPECT_NE(err.find(".vtp or .ply"), std::string::npos) << err;
  EXPECT_FALSE(fs::exists(out));
  EXPECT_EQ(run_cli("check " + data_path("fandisk.obj") + " --deviation " + dir.file("field.vtp"), dir, &err), 2);
  EXPECT_NE(err.find("--against"), std::string::npos) << err;
  EXPECT_EQ(run_cli("check " + data_path("fandisk.obj") + " --against " + data_path("fandisk.obj") + " --deviation " +
                        dir.file("missing/field.ply"),
                    dir, &err),
            2);
}

// Around a box every nearest point is inside a face, on an edge or at a corner: the sign is
// exactly "outside the box" and |distance| the box's own distance, everywhere off the surface.
TEST(Deviation, SignIsExactAtFacesEdgesAndCorners) {
  const Mesh box = box_mesh({0, 0, 0}, {1, 1, 1});
  Mesh probes;
  for (int i = 0; i <= 10; ++i)
    for (int j = 0; j <= 10; ++j)
      for (int k = 0; k <= 10; ++k) {
        const Vec3 q{-0.55 + 0.21 * i, -0.55 + 0.21 * j, -0.55 + 0.21 * k};
        probes.points.push_back(q);
      }
  const DeviationField field = measure_deviation(probes, box);
  ASSERT_EQ(field.sign, DistanceSign::Outside);
  for (size_t i = 0; i < probes.points.size(); ++i) {
    const Vec3& q = probes.points[i];
    double outside = 0, inside = 1;
    for (int a = 0; a < 3; ++a) {
      const double off = std::max({0.0, -q[a], q[a] - 1});
      outside += off * off;
      inside = std::min({inside, q[a], 1 - q[a]});
    }
    const double expected = outside > 0 ? std::sqrt(outside) : -inside;
    EXPECT_NEAR(field.distance[i], expected, 1e-12) << "at " << q[0] << ", " << q[1] << ", " << q[2];
  }
}
