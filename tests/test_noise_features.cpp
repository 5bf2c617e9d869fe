// Sharp edges that are a rough surface's noise (mesh/short_feature_runs.h): runs shorter than the
// wrap can follow are dropped before the feature curves are built; creases stay.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "common/vec.h"
#include "mesh/short_feature_runs.h"
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

TEST(NoiseFeatures, ABoxKeepsItsEdgesUnlessTheyAreShorterThanTheBound) {
  const prep::PreparedInput box = prep::prepare(box_mesh({0, 0, 0}, {1, 2, 3}), prep::PrepareParams{}, nullptr);
  ASSERT_EQ(sharp(box.feature_edges), 12u);  // the faces' diagonals are flat
  std::vector<mesh::FeatureEdge> edges = box.feature_edges;
  EXPECT_EQ(mesh::drop_short_sharp_runs(box.mesh.points, edges, 0.9, 30), 0u);
  EXPECT_EQ(edges.size(), box.feature_edges.size());
  // Shorter than 1.5: the four edges 1 long go, those 2 and 3 long stay.
  EXPECT_EQ(mesh::drop_short_sharp_runs(box.mesh.points, edges, 1.5, 30), 4u);
  for (const auto& e : edges) EXPECT_GT(norm(box.mesh.points[e.a] - box.mesh.points[e.b]), 1.5);
}

TEST(NoiseFeatures, ARunEndsWhereItTurnsByMoreThanTheCornerAngle) {
  // Four edges 0.2 long: straight on, one run 0.8 long; zigzagging by 90 degrees, four runs.
  std::vector<Vec3> straight, zigzag;
  for (int i = 0; i <= 4; ++i) {
    straight.push_back({0.2 * i, 0, 0});
    zigzag.push_back({0.1414 * i, i % 2 ? 0.1414 : 0.0, 0});
  }
  std::vector<mesh::FeatureEdge> a, b;
  for (uint32_t i = 0; i < 4; ++i) {
    a.push_back({i, i + 1, mesh::FeatureKind::Sharp});
    b.push_back({i, i + 1, mesh::FeatureKind::Sharp});
  }
  a.push_back({0, 4, mesh::FeatureKind::Boundary});  // not sharp: never dropped, never counted
  EXPECT_EQ(mesh::drop_short_sharp_runs(straight, a, 0.5, 30), 0u);
  EXPECT_EQ(mesh::drop_short_sharp_runs(zigzag, b, 0.5, 30), 4u);
  EXPECT_TRUE(b.empty());
}

// A rough sphere of 82k triangles at 2 % (its edges a quarter of a base cell, as a scan's are
// at 1 %) has thousands of sharp edges, none of them a crease. Traced, they were thousands of
// feature curves (a 327k-triangle one at 1 %: 216k curves, 41 s against alpha wrap's 5 s,
// 330k triangles out). Most are dropped, and the wrap is valid and near.
TEST(NoiseFeatures, ARoughSphereIsNotTracedAsThousandsOfCreases) {
  const Mesh rough = rough_sphere(6, 0.006, 7);
  WrapParams p;
  p.base_size = Length{2, true};
  const WrapResult r = wrap(rough, p);
  auto v = valid_closed_surface(r.surface);
  EXPECT_TRUE(v.ok) << v.why;
  const FeatureStats& f = r.report.features;
  ASSERT_GT(f.sharp_edges, 1000u);
  EXPECT_GT(f.noise_sharp_edges, f.sharp_edges * 3 / 4);
  EXPECT_LT(f.curves, f.sharp_edges / 10);
  // Nearer on average than the roughness itself (its standard deviation, 0.006).
  EXPECT_LT(r.report.output_to_input.mean, 0.006);
  EXPECT_LT(r.report.output_to_input.max, r.report.base_size);
}
