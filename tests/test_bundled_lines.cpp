// Feature lines of a part placed more than once a hair apart (mesh/bundled_lines.h): each
// bundle of parallel lines keeps its outermost, and the wrap of a real part placed three times
// is as clean as the part's own; so is the wrap of a part tessellated twice, whose faces lie on
// one another (mesh/feature_edges.h).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <ostream>

#include "common/vec.h"
#include "mesh/bundled_lines.h"
#include "post/quality.h"
#include "test_meshes.h"
#include "vdbwrap/io.h"
#include "vdbwrap/wrap.h"

using namespace vdbwrap;
using namespace vdbwrap::testing;

namespace {

const Vec3 kOut = normalized(Vec3{1, 1, 0});  // an edge along z between faces facing +x and +y

// A line along z from z0 to z1 through (x, y).
mesh::OrientedLine along_z(double x, double y, double z0, double z1, const Vec3& out = kOut) {
  return {{x, y, z0}, {x, y, z1}, out};
}

size_t count(const std::vector<uint8_t>& flags) {
  size_t n = 0;
  for (uint8_t f : flags) n += f != 0;
  return n;
}

}  // namespace

TEST(BundledLines, EachBundleKeepsItsOutermostLine) {
  // Three copies' edges 0.01 apart along the outward side, the outermost listed in the middle,
  // and a crossing line of two copies' faces level with the outermost; 0.05 wide bundles.
  const double w = 0.05;
  std::vector<mesh::OrientedLine> lines = {along_z(0, 0, 0, 1), along_z(0.02, 0.02, 0, 1), along_z(0.01, 0.01, 0, 1),
                                           along_z(0.02, 0.02, 0.1, 0.9)};
  // Another bundle a cell away, whose edges face the other way (-x, -y): its outermost is the
  // line with the smaller coordinates.
  const Vec3 back = kOut * -1;
  lines.push_back(along_z(3, 3, 0, 1, back));
  lines.push_back(along_z(2.99, 2.99, 0, 1, back));
  const std::vector<uint8_t> inner = mesh::inner_lines_of_bundles(lines, w, 1.0, 10);
  EXPECT_TRUE(inner[0]);
  EXPECT_FALSE(inner[1]) << "the outermost edge";
  EXPECT_TRUE(inner[2]);
  EXPECT_TRUE(inner[3]) << "level with the outermost edge, listed after it";
  EXPECT_TRUE(inner[4]);
  EXPECT_FALSE(inner[5]);
}

TEST(BundledLines, LinesFacingApartOrFartherThanTheWidthStay) {
  const double w = 0.05;
  // The two edges of a thin plate's rim, 0.01 apart: one faces up and out, the other down and
  // out (90 degrees apart), both stay. So do parallel edges 0.06 apart, wider than a bundle,
  // and a line 20 degrees off the direction of another.
  const Vec3 up_out = normalized(Vec3{1, 0, 1}), down_out = normalized(Vec3{1, 0, -1});
  const std::vector<mesh::OrientedLine> lines = {
      {{0, 0, 0}, {0, 1, 0}, up_out},
      {{0, 0, -0.01}, {0, 1, -0.01}, down_out},
      along_z(5, 5, 0, 1),
      along_z(5.06 / std::sqrt(2) + 5 - 0.06 / std::sqrt(2), 5.06 / std::sqrt(2) + 5 - 0.06 / std::sqrt(2), 0, 1),
      along_z(8, 8, 0, 1),
      {{8.01, 8.01, 0}, {8.01 + std::sin(20 * M_PI / 180), 8.01, std::cos(20 * M_PI / 180)}, kOut},
  };
  const std::vector<uint8_t> inner = mesh::inner_lines_of_bundles(lines, w, 1.0, 10);
  EXPECT_EQ(count(inner), 0u);
}

TEST(BundledLines, ALineGoesOnlyWhereCoveredAlongItsLength) {
  const double w = 0.05;
  // A long edge with a short line farther out beside its middle only: it stays (its quarters are
  // bare). Beside its whole length in two pieces: it goes.
  std::vector<mesh::OrientedLine> lines = {along_z(0, 0, 0, 1), along_z(0.01, 0.01, 0.45, 0.55)};
  EXPECT_EQ(count(mesh::inner_lines_of_bundles(lines, w, 1.0, 10)), 0u);
  lines = {along_z(0, 0, 0, 1), along_z(0.01, 0.01, 0, 0.5), along_z(0.01, 0.01, 0.5, 1)};
  const std::vector<uint8_t> inner = mesh::inner_lines_of_bundles(lines, w, 1.0, 10);
  EXPECT_TRUE(inner[0]);
  EXPECT_FALSE(inner[1]);
  EXPECT_FALSE(inner[2]);
}

TEST(BundledLines, OfCoincidentLinesOneStaysAndUnorientedLinesAreLeftAlone) {
  const double w = 0.05;
  // One body tessellated twice: its edges coincide; the first listed stays. A line with no
  // outward side (an open sheet's) is neither dropped nor drops another.
  const std::vector<mesh::OrientedLine> lines = {along_z(0, 0, 0, 1), along_z(0, 0, 0, 1), along_z(0, 0, 0, 1),
                                                 along_z(2, 2, 0, 1), along_z(2.01, 2.01, 0, 1, Vec3{0, 0, 0})};
  const std::vector<uint8_t> inner = mesh::inner_lines_of_bundles(lines, w, 1.0, 10);
  EXPECT_FALSE(inner[0]);
  EXPECT_TRUE(inner[1]);
  EXPECT_TRUE(inner[2]);
  EXPECT_FALSE(inner[3]);
  EXPECT_FALSE(inner[4]);
}

TEST(BundledLines, TheNextPiecesOfAnEdgeAreNoBundle) {
  // A long sharp edge in pieces shorter than the width (a fine tessellation): each piece's middle
  // is within the width of the next piece's end, but no piece runs beside another.
  std::vector<mesh::OrientedLine> lines;
  for (int i = 0; i < 50; ++i) lines.push_back(along_z(0, 0, 0.01 * i, 0.01 * (i + 1)));
  EXPECT_EQ(count(mesh::inner_lines_of_bundles(lines, 0.05, 1.0, 10)), 0u);
}

TEST(BundledLines, LongLinesAcrossManyCellsAreFound) {
  // Lines far longer than the lookup grid's cell, at a slant: the grid lists each in every cell
  // it passes through, so the farther line is found beside any sample.
  const Vec3 dir = normalized(Vec3{1, 2, 3});
  const Vec3 out = normalized(cross(dir, Vec3{0, 0, 1}));
  const Vec3 a{-40, 7, 3};
  const std::vector<mesh::OrientedLine> lines = {{a, a + dir * 100, out},
                                                 {a + out * 0.01, a + out * 0.01 + dir * 100, out}};
  const std::vector<uint8_t> inner = mesh::inner_lines_of_bundles(lines, 0.05, 1.0, 10);
  EXPECT_TRUE(inner[0]);
  EXPECT_FALSE(inner[1]);
  // Lines a hundred thousand widths long, asked for cells a millionth wide: the grid widens
  // its cells (a bounded number of steps along the lines) and finds the same.
  const std::vector<mesh::OrientedLine> long_lines = {{a, a + dir * 1e5, out},
                                                      {a + out * 0.01, a + out * 0.01 + dir * 1e5, out}};
  EXPECT_EQ(mesh::inner_lines_of_bundles(long_lines, 0.05, 1e-6, 10), inner);
}

namespace {

// `input` placed three times: as given, moved by `shift` * (1, 0.5, 0), and turned by `turn`
// radians about z through the box's centre (0: moved by -shift instead).
Mesh three_copies(const Mesh& input, double shift, double turn) {
  Mesh out = input;
  Vec3 lo = input.points[0], hi = lo;
  for (const Vec3& p : input.points)
    for (int k = 0; k < 3; ++k) lo[k] = std::min(lo[k], p[k]), hi[k] = std::max(hi[k], p[k]);
  const Vec3 c = (lo + hi) * 0.5;
  for (int copy = 1; copy <= 2; ++copy) {
    const uint32_t first = uint32_t(out.points.size());
    for (const Vec3& p : input.points) {
      if (copy == 1) {
        out.points.push_back(p + Vec3{shift, 0.5 * shift, 0});
      } else if (turn == 0) {
        out.points.push_back(p - Vec3{shift, 0.5 * shift, 0});
      } else {
        const Vec3 d = p - c;
        out.points.push_back(c + Vec3{d[0] * std::cos(turn) - d[1] * std::sin(turn),
                                      d[0] * std::sin(turn) + d[1] * std::cos(turn), d[2]});
      }
    }
    for (const Tri& t : input.triangles) out.triangles.push_back({t[0] + first, t[1] + first, t[2] + first});
    if (!input.triangle_part.empty())
      out.triangle_part.insert(out.triangle_part.end(), input.triangle_part.begin(), input.triangle_part.end());
  }
  return out;
}

// Share of the wrap's triangles with an angle under 10 degrees.
double small_angle_share(const WrapResult& r) {
  const auto& p = r.surface.points;
  size_t bad = 0;
  for (const Tri& t : r.surface.triangles) bad += post::min_angle_deg(p[t[0]], p[t[1]], p[t[2]]) < 10 ? 1 : 0;
  return double(bad) / double(std::max<size_t>(1, r.surface.triangles.size()));
}

struct PlacedThrice {
  const char* file;
  double turn;  // radians; 0: moved copies only
};

void PrintTo(const PlacedThrice& p, std::ostream* os) { *os << p.file << " turned " << p.turn; }

class PartPlacedThreeTimes : public ::testing::TestWithParam<PlacedThrice> {};

// A print part written out three times a hair apart (a fiftieth of a finest cell, a hundredth
// of a percent of the diagonal): without the bundles, every sharp edge is three parallel curves
// with the lines where the copies cross beside them, and the wrap twice the part's triangles,
// three times as far from the input on average and at the 95th percentile.
TEST_P(PartPlacedThreeTimes, WrapsAsCleanlyAsThePartAlone) {
  const Mesh one = io::read_mesh(data_path(GetParam().file));
  WrapParams params;
  params.base_size = Length{1, true};
  const WrapResult single = wrap(one, params);
  const double shift = 0.02 * single.report.finest_size;
  const WrapResult thrice = wrap(three_copies(one, shift, GetParam().turn), params);
  const auto& f = thrice.report.features;
  const double d = 0.01 * single.report.diagonal;  // 1 % of the diagonal
  std::printf(
      "[%s x3] duplicate lines %zu sharp + %zu crossing; %zu triangles (alone %zu); small angles %.2f %% (alone %.2f "
      "%%); mean %.4f, p95 %.4f (alone %.4f, %.4f); sharp edges' mean %.4f (alone %.4f) %% of the diagonal\n",
      GetParam().file, f.duplicate_sharp_edges, f.duplicate_intersection_segments, thrice.surface.triangles.size(),
      single.surface.triangles.size(), 100 * small_angle_share(thrice), 100 * small_angle_share(single),
      thrice.report.output_to_input.mean / d, thrice.report.output_to_input.p95 / d,
      single.report.output_to_input.mean / d, single.report.output_to_input.p95 / d,
      thrice.report.sharp_edges_to_output.mean / d, single.report.sharp_edges_to_output.mean / d);
  const auto v = valid_closed_surface(thrice.surface);
  EXPECT_TRUE(v.ok) << v.why;
  EXPECT_GT(f.duplicate_sharp_edges + f.duplicate_intersection_segments, 0u);
  EXPECT_LE(thrice.surface.triangles.size(), 1.5 * double(single.surface.triangles.size()));
  EXPECT_LE(small_angle_share(thrice), 0.01);
  EXPECT_LE(thrice.report.output_to_input.mean, 1.5 * single.report.output_to_input.mean);
  EXPECT_LE(thrice.report.output_to_input.p95, 1.25 * single.report.output_to_input.p95);
  // The inner copies' edges lie a shift or two inside the wrap (and the turned copy's ends
  // further): the part's own distance, give or take that.
  EXPECT_LE(thrice.report.sharp_edges_to_output.mean, 1.5 * single.report.sharp_edges_to_output.mean + 3 * shift);
}

INSTANTIATE_TEST_SUITE_P(RealMeshes, PartPlacedThreeTimes,
                         ::testing::Values(PlacedThrice{"thingi_65004.stl", 0}, PlacedThrice{"thingi_65004.stl", 1e-3},
                                           PlacedThrice{"fandisk.obj", 0}),
                         [](const ::testing::TestParamInfo<PlacedThrice>& info) {
                           return test_name_of(info.param.file) + (info.param.turn != 0 ? "_turned" : "_moved");
                         });

}  // namespace

namespace {

// The part again with every triangle split in three at its centre, both kept (one CAD body
// tessellated twice): every edge of the part has four triangles. Taken for non-manifold edges,
// every edge of the part was a feature curve, the wrap three to five times the part's triangles
// and its p95 distance eight to twelve times the part's.
class PartTessellatedTwice : public ::testing::TestWithParam<const char*> {};

TEST_P(PartTessellatedTwice, WrapsAsCleanlyAsThePartAlone) {
  const Mesh one = io::read_mesh(data_path(GetParam()));
  const Mesh twice = tessellated_twice(one);
  WrapParams params;
  params.base_size = Length{1, true};
  const WrapResult single = wrap(one, params), r = wrap(twice, params);
  const double d = 0.01 * single.report.diagonal;
  std::printf(
      "[%s twice] %zu non-manifold edges; %zu triangles (alone %zu); mean %.4f, p95 %.4f (alone %.4f, %.4f) %%\n",
      GetParam(), r.report.features.nonmanifold_edges, r.surface.triangles.size(), single.surface.triangles.size(),
      r.report.output_to_input.mean / d, r.report.output_to_input.p95 / d, single.report.output_to_input.mean / d,
      single.report.output_to_input.p95 / d);
  const auto v = valid_closed_surface(r.surface);
  EXPECT_TRUE(v.ok) << v.why;
  EXPECT_EQ(r.report.features.nonmanifold_edges, 0u);
  EXPECT_LE(r.surface.triangles.size(), 1.5 * double(single.surface.triangles.size()));
  EXPECT_LE(small_angle_share(r), 0.01);
  EXPECT_LE(r.report.output_to_input.mean, 1.5 * single.report.output_to_input.mean);
  EXPECT_LE(r.report.output_to_input.p95, 1.5 * single.report.output_to_input.p95);
}

INSTANTIATE_TEST_SUITE_P(RealMeshes, PartTessellatedTwice, ::testing::Values("fandisk.obj", "angle_block.STL"),
                         [](const ::testing::TestParamInfo<const char*>& info) { return test_name_of(info.param); });

}  // namespace
