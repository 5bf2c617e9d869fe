// Sharp edges that are a rough surface's noise (mesh/short_feature_runs.h): runs shorter than the
// wrap can follow are dropped before the feature curves are built; creases stay.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <random>

#include "common/vec.h"
#include "fit/features.h"
#include "mesh/short_feature_runs.h"
#include "pipeline/stage_params.h"
#include "prep/prepare.h"
#include "test_meshes.h"
#include "vdbwrap/check.h"
#include "vdbwrap/wrap.h"

using namespace vdbwrap;
using namespace vdbwrap::testing;

namespace {

size_t sharp(const std::vector<mesh::FeatureEdge>& edges) {
  size_t n = 0;
  for (const auto& e : edges) n += e.kind == mesh::FeatureKind::Sharp;
  return n;
}

// A sphere whose vertices are pushed in and out along the normal at random: a raw scan's rough
// surface, whose triangles turn by more than the feature angle every few triangles.
Mesh rough_sphere(int level, double amplitude, uint32_t seed) {
  Mesh m = icosphere_mesh(1.0, level);
  std::mt19937 rng(seed);
  std::normal_distribution<double> noise(0.0, amplitude);
  for (Vec3& p : m.points) p = p * (1.0 + noise(rng));
  return m;
}

}  // namespace

// Ten rows of four sharp edges 0.2 long, 0.05 apart, straight or zigzagging by 90 degrees:
// eight cell lengths of sharp edges in one cell 1 wide (runs under 0.5 may be noise).
std::vector<mesh::FeatureEdge> rows(std::vector<Vec3>& points, bool zigzag) {
  std::vector<mesh::FeatureEdge> edges;
  for (int row = 0; row < 10; ++row) {
    const uint32_t first = uint32_t(points.size());
    for (int i = 0; i <= 4; ++i)
      points.push_back(zigzag ? Vec3{0.1 + 0.1414 * i, 0.02 + 0.05 * row + (i % 2 ? 0.1414 : 0.0), 0.5}
                              : Vec3{0.1 + 0.2 * i, 0.02 + 0.05 * row, 0.5});
    for (uint32_t i = 0; i < 4; ++i) edges.push_back({first + i, first + i + 1, mesh::FeatureKind::Sharp});
  }
  return edges;
}

TEST(NoiseFeatures, ShortRunsGoWhereTheyAreManyAndEndAtSharpTurns) {
  std::vector<Vec3> straight_points, zigzag_points;
  std::vector<mesh::FeatureEdge> straight = rows(straight_points, false), zigzag = rows(zigzag_points, true);
  straight.push_back({0, 4, mesh::FeatureKind::Boundary});  // not sharp: never dropped, never counted
  // Straight on, each row is one run 0.8 long: kept.
  EXPECT_EQ(mesh::drop_short_sharp_runs(straight_points, straight, 0.5, 30), 0u);
  EXPECT_EQ(straight.size(), 41u);
  // Zigzagging, each edge is a run of its own (the turns are corners): all 40 go.
  EXPECT_EQ(mesh::drop_short_sharp_runs(zigzag_points, zigzag, 0.5, 30), 40u);
  EXPECT_TRUE(zigzag.empty());
  // One zigzag row alone (1.1 cell lengths in its cell): a small part's edges, kept.
  std::vector<Vec3> one_points;
  std::vector<mesh::FeatureEdge> one = rows(one_points, true);
  one.resize(4);
  EXPECT_EQ(mesh::drop_short_sharp_runs(one_points, one, 0.5, 30), 0u);
}

TEST(NoiseFeatures, ACreaseRunsOnPastTheNoiseEdgesThatMeetIt) {
  // The straight rows again, each with a spur 0.1 long across it at its three inner vertices
  // (a rough scan's sharp edges meeting a crease; 3 cell lengths of them): the rows stay
  // whole, the spurs go.
  std::vector<Vec3> points;
  std::vector<mesh::FeatureEdge> edges = rows(points, false);
  const size_t row_edges = edges.size();
  for (uint32_t row = 0; row < 10; ++row)
    for (uint32_t i = 1; i <= 3; ++i) {
      const uint32_t at = 5 * row + i;
      points.push_back(points[at] + Vec3{0, 0, 0.1});
      edges.push_back({at, uint32_t(points.size() - 1), mesh::FeatureKind::Sharp});
    }
  EXPECT_EQ(mesh::drop_short_sharp_runs(points, edges, 0.5, 30), 30u);
  EXPECT_EQ(edges.size(), row_edges);
  for (const auto& e : edges) EXPECT_EQ(points[e.a][2], points[e.b][2]);  // the rows' own edges
}

TEST(NoiseFeatures, ASmallBoxKeepsItsEdges) {
  // Edges 1, 2 and 3 long against runs of 1.5: short, but 24 cell lengths over 8 cells.
  const prep::PreparedInput box = prep::prepare(box_mesh({0, 0, 0}, {1, 2, 3}), prep::PrepareParams{}, nullptr);
  ASSERT_EQ(sharp(box.feature_edges), 12u);  // the faces' diagonals are flat
  std::vector<mesh::FeatureEdge> edges = box.feature_edges;
  EXPECT_EQ(mesh::drop_short_sharp_runs(box.mesh.points, edges, 1.5, 30), 0u);
  EXPECT_EQ(edges.size(), box.feature_edges.size());
}

// A rough sphere of 82k triangles at 2 % (its edges a quarter of a base cell, as a scan's are
// at 1 %) has thousands of sharp edges, none of them a crease. Traced, they were thousands of
// feature curves (a 327k-triangle one at 1 %: 216k curves, 41 s against alpha wrap's 5 s,
// 330k triangles out). Most are dropped, and the wrap is valid and near.
TEST(NoiseFeatures, ARoughSphereIsNotTracedAsThousandsOfCreases) {
  const Mesh rough = rough_sphere(6, 0.006, 7);
  prep::PreparedInput in = prep::prepare(rough, prep::PrepareParams{}, nullptr);
  const double base = 0.02 * in.diagonal;
  const size_t curves_before = fit::build_feature_curves(in, 30).size();
  const size_t sharp_before = sharp(in.feature_edges);
  const size_t dropped =
      mesh::drop_short_sharp_runs(in.mesh.points, in.feature_edges, pipeline::kShortestSharpRun * base, 30);
  const size_t curves_after = fit::build_feature_curves(in, 30).size();
  std::printf("[rough sphere] sharp edges %zu, dropped %zu; curves %zu -> %zu\n", sharp_before, dropped, curves_before,
              curves_after);
  EXPECT_GT(dropped, sharp_before / 2);
  EXPECT_LT(curves_after, curves_before / 4);

  WrapParams p;
  p.base_size = Length{2, true};
  const WrapResult r = wrap(rough, p);
  auto v = valid_closed_surface(r.surface);
  EXPECT_TRUE(v.ok) << v.why;
  EXPECT_EQ(r.report.features.noise_sharp_edges, dropped);
  EXPECT_EQ(r.report.features.curves, curves_after);
  // Nearer on average than the roughness itself (its standard deviation, 0.006).
  EXPECT_LT(r.report.output_to_input.mean, 0.006);
  EXPECT_LT(r.report.output_to_input.max, r.report.base_size);
}
