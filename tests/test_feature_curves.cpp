// The input's feature curves as a file (`wrap --features FILE.obj|.eMesh`, WrapResult::feature_curves):
// written by the CLI, read back with the right points and edges, and lying on the input's
// sharp edges.
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "common/vec.h"
#include "vdbwrap/io.h"
#include "vdbwrap/wrap.h"

#ifndef VDBWRAP_CLI
#define VDBWRAP_CLI "vdbwrap"
#endif

using namespace vdbwrap;
namespace fs = std::filesystem;

namespace {

using Key = std::array<double, 3>;
Key key(const Vec3& p) { return {p[0], p[1], p[2]}; }

struct EdgeFile {
  std::vector<Vec3> points;
  std::vector<std::array<size_t, 2>> edges;  // 0-based
};

std::string slurp(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

// OBJ: `v x y z` and `l i j k ...` (1-based), each polyline split into its edges.
EdgeFile read_obj_lines(const std::string& text) {
  EdgeFile f;
  std::istringstream in(text);
  std::string line;
  while (std::getline(in, line)) {
    std::istringstream ls(line);
    std::string tag;
    ls >> tag;
    if (tag == "v") {
      Vec3 p;
      ls >> p[0] >> p[1] >> p[2];
      f.points.push_back(p);
    } else if (tag == "l") {
      std::vector<size_t> ids;
      for (size_t i = 0; ls >> i;) ids.push_back(i - 1);
      for (size_t i = 0; i + 1 < ids.size(); ++i) f.edges.push_back({ids[i], ids[i + 1]});
    }
  }
  return f;
}

// OpenFOAM featureEdgeMesh: the FoamFile header, then N ( (x y z) ... ) and M ( (a b) ... ).
EdgeFile read_emesh(const std::string& text) {
  EdgeFile f;
  const size_t header_end = text.find('}');
  EXPECT_EQ(text.rfind("FoamFile", 0), 0u);
  EXPECT_NE(text.find("class       featureEdgeMesh;"), std::string::npos);
  std::string body = text.substr(header_end + 1);
  // Comments out, brackets as blanks: what is left is N, N triples, M, M pairs.
  std::string clean;
  for (size_t i = 0; i < body.size(); ++i) {
    if (body.compare(i, 2, "//") == 0) {
      i = body.find('\n', i);
      if (i == std::string::npos) break;
    }
    clean += (body[i] == '(' || body[i] == ')') ? ' ' : body[i];
  }
  std::istringstream in(clean);
  size_t n = 0, m = 0;
  in >> n;
  f.points.resize(n);
  for (Vec3& p : f.points) in >> p[0] >> p[1] >> p[2];
  in >> m;
  f.edges.resize(m);
  for (auto& e : f.edges) in >> e[0] >> e[1];
  EXPECT_FALSE(in.fail()) << "eMesh body did not parse";
  return f;
}

// The input's sharp edges (dihedral angle over `angle_deg`) and its open or non-manifold
// edges, with the points welded by exact coordinates as STL repeats them per triangle.
std::vector<std::array<Vec3, 2>> sharp_edges(const Mesh& m, double angle_deg) {
  std::map<Key, uint32_t> weld;
  std::vector<uint32_t> id(m.points.size());
  for (size_t i = 0; i < m.points.size(); ++i)
    id[i] = weld.try_emplace(key(m.points[i]), uint32_t(weld.size())).first->second;
  std::map<std::pair<uint32_t, uint32_t>, std::vector<Vec3>> normals;
  std::map<std::pair<uint32_t, uint32_t>, std::array<Vec3, 2>> ends;
  for (const Tri& t : m.triangles) {
    const Vec3 n = normalized(cross(m.points[t[1]] - m.points[t[0]], m.points[t[2]] - m.points[t[0]]));
    for (int k = 0; k < 3; ++k) {
      uint32_t a = id[t[k]], b = id[t[(k + 1) % 3]];
      std::array<Vec3, 2> e{m.points[t[k]], m.points[t[(k + 1) % 3]]};
      if (a > b) std::swap(a, b);
      normals[{a, b}].push_back(n);
      ends[{a, b}] = e;
    }
  }
  std::vector<std::array<Vec3, 2>> out;
  const double cos_limit = std::cos(angle_deg * M_PI / 180.0);
  for (const auto& [edge, ns] : normals)
    if (ns.size() != 2 || dot(ns[0], ns[1]) < cos_limit) out.push_back(ends[edge]);
  return out;
}

double distance_to_segment(const Vec3& p, const std::array<Vec3, 2>& s) {
  const Vec3 d = s[1] - s[0];
  const double len2 = dot(d, d);
  const double t = len2 > 0 ? std::clamp(dot(p - s[0], d) / len2, 0.0, 1.0) : 0.0;
  const Vec3 q = s[0] + d * t;
  return std::sqrt(dot(p - q, p - q));
}

double distance_to_edges(const Vec3& p, const std::vector<std::array<Vec3, 2>>& edges) {
  double best = INFINITY;
  for (const auto& e : edges) best = std::min(best, distance_to_segment(p, e));
  return best;
}

class FeatureCurvesFile : public ::testing::Test {
 protected:
  void SetUp() override {
    dir = fs::temp_directory_path() / ("vdbwrap_features_" + std::to_string(::getpid()) + "_" +
                                       ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::create_directories(dir);
  }
  void TearDown() override { fs::remove_all(dir); }
  int cli(const std::string& args, std::string* err = nullptr) {
    const fs::path err_path = dir / "stderr.txt";
    const int status = std::system((std::string(VDBWRAP_CLI) + " " + args + " 2> " + err_path.string()).c_str());
    if (err) *err = slurp(err_path);
    return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  }
  fs::path dir;
};

TEST(FeatureCurvesText, SharedPointsOnceAndEveryConsecutivePairAnEdge) {
  // Two open curves meeting at a corner, and a closed triangle (its last point is its first).
  const std::vector<std::vector<Vec3>> curves = {
      {{0, 0, 0}, {1, 0, 0}, {2, 0, 0}},
      {{2, 0, 0}, {2, 1, 0}},
      {{5, 5, 5}, {6, 5, 5}, {5, 6, 5}, {5, 5, 5}},
      {{9, 9, 9}},  // a lone point: no edge, not written
  };
  const EdgeFile obj = read_obj_lines(io::feature_curves_to_text(curves, io::CurveFormat::Obj));
  const EdgeFile foam = read_emesh(io::feature_curves_to_text(curves, io::CurveFormat::EMesh));
  for (const EdgeFile* f : {&obj, &foam}) {
    EXPECT_EQ(f->points.size(), 7u);  // 3 + 1 new + 3
    ASSERT_EQ(f->edges.size(), 6u);   // 2 + 1 + 3
    std::set<std::pair<Key, Key>> edges;
    for (const auto& e : f->edges) {
      ASSERT_LT(e[0], f->points.size());
      ASSERT_LT(e[1], f->points.size());
      edges.insert(std::minmax(key(f->points[e[0]]), key(f->points[e[1]])));
    }
    EXPECT_TRUE(edges.count(std::minmax(Key{5, 6, 5}, Key{5, 5, 5}))) << "the closed curve's last edge";
    EXPECT_TRUE(edges.count(std::minmax(Key{2, 0, 0}, Key{2, 1, 0})));
  }
  EXPECT_EQ(io::curve_format_from_extension("a/b.EMESH"), io::CurveFormat::EMesh);
  EXPECT_EQ(io::curve_format_from_extension("b.Obj"), io::CurveFormat::Obj);
  EXPECT_EQ(io::curve_format_from_extension("b.obj/x"), io::CurveFormat::Unknown);
  EXPECT_THROW(io::write_feature_curves((fs::temp_directory_path() / "x.stl").string(), curves), Error);
}

TEST_F(FeatureCurvesFile, CliWritesTheCurvesOfACadPartOnItsSharpEdges) {
  const std::string input = std::string(VDBWRAP_TEST_DATA_DIR) + "/angle_block.STL";
  const Mesh mesh = io::read_mesh(input);
  // The curves the wrap snaps to, from the library with the command line's defaults (a coarse
  // cell for speed: the curves come from the input alone).
  WrapParams params;
  params.base_size = Length::parse("3%");
  params.compute_distances = false;
  const WrapResult result = wrap(mesh, params);
  ASSERT_FALSE(result.feature_curves.empty());
  std::set<Key> expected_points;
  size_t expected_edges = 0;
  for (const auto& c : result.feature_curves) {
    for (const Vec3& p : c) expected_points.insert(key(p));
    expected_edges += c.size() - 1;
  }

  const fs::path obj = dir / "angle_block_features.obj", foam = dir / "angle_block_features.eMesh";
  ASSERT_EQ(cli("wrap " + input + " -o " + (dir / "w.stl").string() + " -q --no-distances --base-size 3% --features " +
                obj.string()),
            0);
  ASSERT_EQ(cli("wrap " + input + " -o " + (dir / "w.stl").string() + " -q --no-distances --base-size 3% --features " +
                foam.string()),
            0);
  const EdgeFile from_obj = read_obj_lines(slurp(obj)), from_foam = read_emesh(slurp(foam));

  const double diagonal = std::sqrt(dot(result.report.input.bbox_max - result.report.input.bbox_min,
                                        result.report.input.bbox_max - result.report.input.bbox_min));
  const auto sharp = sharp_edges(mesh, 25.0);  // a little under the default 30: the prepared input's normals may differ
  ASSERT_FALSE(sharp.empty());
  std::set<std::pair<Key, Key>> obj_edges;
  for (const EdgeFile* f : {&from_obj, &from_foam}) {
    SCOPED_TRACE(f == &from_obj ? "obj" : "eMesh");
    EXPECT_EQ(f->points.size(), expected_points.size());
    EXPECT_EQ(f->edges.size(), expected_edges);
    std::set<std::pair<Key, Key>> edges;
    double worst = 0;
    for (const Vec3& p : f->points) {
      EXPECT_TRUE(expected_points.count(key(p))) << "a point that is not on a curve";
      worst = std::max(worst, distance_to_edges(p, sharp));
    }
    for (const auto& e : f->edges) {
      ASSERT_LT(std::max(e[0], e[1]), f->points.size());
      // The edge runs along a sharp edge, not across a face: its midpoint is on one too.
      worst = std::max(worst, distance_to_edges((f->points[e[0]] + f->points[e[1]]) * 0.5, sharp));
      edges.insert(std::minmax(key(f->points[e[0]]), key(f->points[e[1]])));
    }
    EXPECT_LT(worst, 1e-6 * diagonal) << "a curve point off the input's sharp edges";
    EXPECT_EQ(edges.size(), f->edges.size()) << "an edge written twice";
    if (f == &from_obj)
      obj_edges = edges;
    else
      EXPECT_EQ(edges, obj_edges) << "OBJ and eMesh hold different edges";
  }
}

TEST_F(FeatureCurvesFile, CliRefusesAnUnknownExtensionAndNoFeaturesBeforeTheWrap) {
  const std::string input = std::string(VDBWRAP_TEST_DATA_DIR) + "/angle_block.STL";
  const std::string out = (dir / "w.stl").string();
  std::string err;
  EXPECT_EQ(cli("wrap " + input + " -o " + out + " -q --features " + (dir / "f.vtk").string(), &err), 2);
  EXPECT_NE(err.find(".obj or .eMesh"), std::string::npos) << err;
  EXPECT_EQ(cli("wrap " + input + " -o " + out + " -q --no-features --features " + (dir / "f.obj").string(), &err), 2);
  EXPECT_NE(err.find("--no-features"), std::string::npos) << err;
  EXPECT_EQ(cli("wrap " + input + " -o " + out + " -q --features " + (dir / "missing" / "f.obj").string(), &err), 2);
  EXPECT_FALSE(fs::exists(out)) << "no wrap ran";
}

}  // namespace
