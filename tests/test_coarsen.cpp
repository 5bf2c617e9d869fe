// Coarsening (stage 4): fewer triangles on flat parts, the surface still valid, still close
// to the input, the feature edges still on it.
#include <gtest/gtest.h>

#include "common/vec.h"
#include "test_meshes.h"
#include "vdbwrap/wrap.h"

using namespace vdbwrap;
using namespace vdbwrap::testing;

namespace {

// A cube turned by arbitrary angles, so nothing lines up with the grid.
Mesh rotated_cube() {
  Mesh m = box_mesh({-0.5, -0.5, -0.5}, {0.5, 0.5, 0.5});
  const double a = 0.37, b = 0.61;
  for (Vec3& p : m.points) {
    Vec3 q{p[0] * std::cos(a) - p[1] * std::sin(a), p[0] * std::sin(a) + p[1] * std::cos(a), p[2]};
    p = {q[0], q[1] * std::cos(b) - q[2] * std::sin(b), q[1] * std::sin(b) + q[2] * std::cos(b)};
  }
  return m;
}

}  // namespace

TEST(Coarsen, FewerTrianglesSameValidityDistanceAndEdges) {
  for (const Mesh& m : {rotated_cube(), sphere_mesh(1.0, 48, 96)}) {
    // Coarsening alone: the remeshing and sliver removal of stage 4 (which change triangles
    // too) are off.
    WrapParams fine;
    fine.coarsen_tolerance = 0;
    fine.remesh = false;
    fine.remove_slivers = false;
    WrapParams coarse;  // the default tolerance
    coarse.remesh = false;
    coarse.remove_slivers = false;
    ASSERT_GT(coarse.coarsen_tolerance, 0);
    WrapResult a = wrap(m, fine), b = wrap(m, coarse);
    auto va = valid_closed_surface(a.surface), vb = valid_closed_surface(b.surface);
    EXPECT_TRUE(va.ok) << va.why;
    EXPECT_TRUE(vb.ok) << vb.why;
    EXPECT_LT(double(b.surface.triangles.size()), 0.6 * double(a.surface.triangles.size()))
        << a.surface.triangles.size() << " -> " << b.surface.triangles.size();
    EXPECT_EQ(b.report.triangles_before_coarsening, a.surface.triangles.size());
    // Every new triangle's samples stay within the tolerance: the distance to the input grows
    // by at most that much.
    const double tolerance = coarse.coarsen_tolerance * b.report.base_size;
    EXPECT_LE(b.report.output_to_input.max, a.report.output_to_input.max + tolerance);
    EXPECT_LE(b.report.input_to_output.p95, a.report.input_to_output.p95 + tolerance);
    // Snapped feature nodes are never removed: the cube's edges stay where they were.
    EXPECT_LE(b.report.sharp_edges_to_output.mean, a.report.sharp_edges_to_output.mean + 1e-4 * b.report.diagonal);
  }
}

TEST(Coarsen, OneThreadAndTwoGiveTheSameSurface) {
  // Blocks of the surface coarsen at once, each on its own, and the batches after them depend
  // on the queue alone.
  WrapParams one, two;
  one.threads = 1;
  two.threads = 2;
  one.compute_distances = two.compute_distances = false;
  WrapResult a = wrap(rotated_cube(), one), b = wrap(rotated_cube(), two);
  ASSERT_GT(a.report.triangles_before_coarsening, 2 * a.surface.triangles.size());
  EXPECT_EQ(a.surface.triangles, b.surface.triangles);
  EXPECT_EQ(a.surface.points, b.surface.points);
}

TEST(Coarsen, OneThreadAndTwoGiveTheSameSurfaceOverManyBlocks) {
  // A finer wrap: hundreds of blocks, dozens of each colour coarsening at once, so that a
  // collapse reading or writing anything beyond its block's reach shows as a difference.
  WrapParams one, two;
  one.base_size = two.base_size = Length{0.6, true};
  one.threads = 1;
  two.threads = 2;
  one.compute_distances = two.compute_distances = false;
  one.remesh = two.remesh = false;
  const Mesh m = sphere_mesh(1.0, 48, 96);
  WrapResult a = wrap(m, one), b = wrap(m, two);
  ASSERT_GT(a.report.triangles_before_coarsening, 2 * a.surface.triangles.size());
  EXPECT_EQ(a.surface.triangles, b.surface.triangles);
  EXPECT_EQ(a.surface.points, b.surface.points);
  auto v = valid_closed_surface(b.surface);
  EXPECT_TRUE(v.ok) << v.why;
}
