// Stage 4, proximity refinement (post/proximity_refinement.h, WrapParams::proximity_refinement):
// on real meshes whose farthest point at 1 % is a node the validity loop held back at a coarse
// cell, more than a base cell off the input, the pass brings the farthest point within a base
// cell, and the wrap stays valid and no farther from the input on average.
#include <gtest/gtest.h>

#include <cstdio>
#include <utility>

#include "test_meshes.h"
#include "vdbwrap/io.h"
#include "vdbwrap/wrap.h"

using namespace vdbwrap;
using namespace vdbwrap::testing;

namespace {

class ProximityRefinementWrap : public ::testing::TestWithParam<const char*> {};

TEST_P(ProximityRefinementWrap, FarthestPointWithinABaseCell) {
  const Mesh input = io::read_mesh(data_path(GetParam()));
  WrapParams off;
  off.base_size = Length{1, true};
  off.proximity_refinement = false;
  off.refine_where_far = false;  // the pass alone: the refit would bring these in by itself
  WrapParams on = off;
  on.proximity_refinement = true;
  const WrapResult a = wrap(input, off), b = wrap(input, on);
  const double base = 0.01 * a.report.diagonal;
  const ProximityRefinementReport& r = b.report.quality.proximity_refinement;
  std::printf(
      "[%s 1%%] max %.3f -> %.3f base cells; mean %.3g -> %.3g; far triangles %zu -> %zu; %zu pulls, %zu splits\n",
      GetParam(), a.report.output_to_input.max / base, b.report.output_to_input.max / base,
      a.report.output_to_input.mean, b.report.output_to_input.mean, r.far_triangles_before, r.far_triangles_after,
      r.pulls, r.splits);
  auto v = valid_closed_surface(b.surface);
  EXPECT_TRUE(v.ok) << v.why;
  EXPECT_EQ(b.report.output.intersecting_triangles, 0u);
  // Without the pass the farthest point is over a base cell off (what the test is about); with
  // it, within one.
  EXPECT_GT(a.report.output_to_input.max, base);
  EXPECT_LE(b.report.output_to_input.max, base);
  // No farther on average, nor from the input's sharp edges (2 % for the sampling's noise).
  const double eps = 1e-6 * a.report.diagonal;
  EXPECT_LE(b.report.output_to_input.mean, 1.02 * a.report.output_to_input.mean + eps);
  EXPECT_LE(b.report.output_to_input.p95, 1.02 * a.report.output_to_input.p95 + eps);
  EXPECT_LE(b.report.sharp_edges_to_output.mean, 1.02 * a.report.sharp_edges_to_output.mean + eps);
  // The report says what it did, and only when asked.
  EXPECT_TRUE(r.ran);
  EXPECT_FALSE(a.report.quality.proximity_refinement.ran);
  EXPECT_DOUBLE_EQ(r.far_distance, 0.75 * b.report.base_size);
  EXPECT_GT(r.pulls + r.splits, 0u);
  EXPECT_LT(r.far_triangles_after, r.far_triangles_before);
}

INSTANTIATE_TEST_SUITE_P(RealMeshes, ProximityRefinementWrap, ::testing::Values("quadknot.obj", "idler_riser.STL"));

}  // namespace

namespace {

// Prints from the wild set turned against the grid (random rotations, rounded to float as an
// STL file holds them). Their farthest point at 1 % was a node the validity loop held back over
// a base cell off the input:
// - on thingi_65004, a node of a traced feature edge, off its curve; such a node is pulled like
//   any other, and the input's sharp edges stay as near;
// - on thingi_99865, a node in a pleat (its fan folded over itself): every move of it turns the
//   folded triangles over, and it is merged into its neighbour nearest the input instead.
// `input` wrapped at 1 % without the pass and with it.
std::pair<WrapResult, WrapResult> without_and_with_the_pass(const Mesh& input) {
  WrapParams on;
  on.base_size = Length{1, true};
  WrapParams off = on;
  off.proximity_refinement = false;
  return {wrap(input, off), wrap(input, on)};
}

struct TurnedPrint {
  const char* file;
  double rotation[3][3];
  bool merges;  // the pass must merge a node away
};

class ProximityRefinementTurned : public ::testing::TestWithParam<TurnedPrint> {};

TEST_P(ProximityRefinementTurned, FarthestPointWithinABaseCell) {
  const TurnedPrint& c = GetParam();
  Mesh input = io::read_mesh(data_path(c.file));
  for (Vec3& p : input.points) {
    Vec3 q{0, 0, 0};
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) q[i] += c.rotation[i][j] * p[j];
    for (int i = 0; i < 3; ++i) p[i] = double(float(q[i]));
  }
  const auto [a, b] = without_and_with_the_pass(input);
  const double base = b.report.base_size;
  const ProximityRefinementReport& r = b.report.quality.proximity_refinement;
  std::printf("[turned %s 1%%] max %.3f -> %.3f base cells; sharp edges mean %.3g -> %.3g; %zu pulls, %zu merges\n",
              c.file, a.report.output_to_input.max / base, b.report.output_to_input.max / base,
              a.report.sharp_edges_to_output.mean, b.report.sharp_edges_to_output.mean, r.pulls, r.collapses);
  auto v = valid_closed_surface(b.surface);
  EXPECT_TRUE(v.ok) << v.why;
  EXPECT_GT(a.report.output_to_input.max, base);
  EXPECT_LE(b.report.output_to_input.max, base);
  if (c.merges) EXPECT_GT(r.collapses, 0u);
  const double eps = 1e-6 * b.report.diagonal;
  EXPECT_LE(b.report.output_to_input.mean, 1.02 * a.report.output_to_input.mean + eps);
  EXPECT_LE(b.report.sharp_edges_to_output.mean, 1.02 * a.report.sharp_edges_to_output.mean + eps);
  EXPECT_LE(b.report.sharp_edges_to_output.p95, 1.02 * a.report.sharp_edges_to_output.p95 + eps);
}

INSTANTIATE_TEST_SUITE_P(
    WildSet, ProximityRefinementTurned,
    ::testing::Values(
        TurnedPrint{"thingi_65004.stl",
                    {{0.542912, 0.047005, 0.838473}, {-0.748356, 0.48013, 0.457645}, {-0.381065, -0.875937, 0.295845}},
                    false},
        TurnedPrint{
            "thingi_99865.stl",
            {{0.076751, -0.811999, -0.578591}, {0.028086, -0.578312, 0.815332}, {-0.996655, -0.078828, -0.02158}},
            true}));

}  // namespace

namespace {

// An assembly of ten interpenetrating bodies (box.STL at 1 %): after the feature insertion, a
// face 1.2-2 base cells across bridges a groove beside a sharp edge, one corner on the edge,
// the other two held back 0.37 and 0.71 cells off (under the far distance, so not pulled);
// its middle is 1.14 cells off and no split of it is nearer. Its farthest corner goes onto the
// input instead.
TEST(ProximityRefinementConcaveCorner, AFaceAcrossAGrooveHasItsFarthestCornerPulled) {
  const auto [a, b] = without_and_with_the_pass(io::read_mesh(data_path("box.STL")));
  const double base = b.report.base_size;
  std::printf("[box.STL 1%%] max %.3f -> %.3f base cells; mean %.3g -> %.3g; %zu pulls\n",
              a.report.output_to_input.max / base, b.report.output_to_input.max / base, a.report.output_to_input.mean,
              b.report.output_to_input.mean, b.report.quality.proximity_refinement.pulls);
  auto v = valid_closed_surface(b.surface);
  EXPECT_TRUE(v.ok) << v.why;
  EXPECT_GT(a.report.output_to_input.max, base);
  EXPECT_LE(b.report.output_to_input.max, base);
  const double eps = 1e-6 * b.report.diagonal;
  EXPECT_LE(b.report.output_to_input.mean, 1.02 * a.report.output_to_input.mean + eps);
  EXPECT_LE(b.report.sharp_edges_to_output.mean, 1.02 * a.report.sharp_edges_to_output.mean + eps);
}

}  // namespace
