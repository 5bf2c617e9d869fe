// mesh::far_triangles (core/mesh/far_from_input.h): the parts of a wrap far from the input,
// which the refit refines around and proximity refinement works on. A concave crease of two
// walls (z = 0 and y = 0, 4 x 4 each) and a wrap bridging it: its corners on the walls, the
// middles of its crossing edges one unit off (min(y, z) at (x, 1, 1)).
#include <gtest/gtest.h>

#include <algorithm>
#include <vector>

#include "common/vec.h"
#include "mesh/far_from_input.h"
#include "mesh/surface_index.h"

using namespace vdbwrap;

namespace {

struct Crease {
  std::vector<Vec3> points = {{0, 0, 0}, {4, 0, 0}, {4, 4, 0}, {0, 4, 0}, {4, 0, 4}, {0, 0, 4}};
  std::vector<Tri> triangles = {{0, 1, 2}, {0, 2, 3}, {0, 1, 4}, {0, 4, 5}};
  mesh::SurfaceIndex index{points, triangles};
};

// The distance from the crease of a point in its quadrant (y, z >= 0, x in [0, 4]).
double crease_distance(const Vec3& local) { return std::min(local[1], local[2]); }

const Vec3 kOrigin{10, 20, 30};  // the surface's frame: local + origin

std::vector<Vec3> in_surface_frame(std::vector<Vec3> local) {
  for (Vec3& p : local) p = p + kOrigin;
  return local;
}

TEST(FarTriangles, FindsTheFacesBridgingAConcaveCrease) {
  const Crease crease;
  // Nodes: a1, a2 on the floor, b1, b2 on the wall, then three on the floor away from the crease.
  const std::vector<Vec3> points =
      in_surface_frame({{1, 2, 0}, {2, 2, 0}, {1, 0, 2}, {2, 0, 2}, {1, 3, 0}, {2, 3, 0}, {1.5, 3.5, 0}});
  const std::vector<Tri> triangles = {{0, 1, 3}, {0, 3, 2}, {4, 5, 6}};
  std::vector<double> node_distance;

  // Far beyond 0.9: the two bridging faces (their crossing edges' middles are 1 off), the
  // farthest first and ties in triangle order; the face on the floor is not.
  auto far = mesh::far_triangles(points, triangles, {}, crease.index, kOrigin, 0.9, node_distance);
  ASSERT_EQ(far.size(), 2u);
  EXPECT_EQ(far[0].triangle, 0u);
  EXPECT_EQ(far[1].triangle, 1u);
  for (const mesh::FarTriangle& f : far) {
    EXPECT_NEAR(f.distance, 1.0, 1e-12);
    EXPECT_NEAR(crease_distance(f.at - kOrigin), f.distance, 1e-12) << "the point reported is that far";
  }
  // Nodes on the input get the cheap bound (a fiftieth of the distance asked), not a query.
  ASSERT_EQ(node_distance.size(), points.size());
  for (double d : node_distance) EXPECT_LE(d, 0.02 * 0.9 + 1e-12);

  // Nothing is over 1.1 off; the faces that are not alive are left out.
  EXPECT_TRUE(mesh::far_triangles(points, triangles, {}, crease.index, kOrigin, 1.1, node_distance).empty());
  far = mesh::far_triangles(points, triangles, {1, 0, 1}, crease.index, kOrigin, 0.9, node_distance);
  ASSERT_EQ(far.size(), 1u);
  EXPECT_EQ(far[0].triangle, 0u);
}

TEST(FarTriangles, AHeldBackCornerIsItsTrianglesFarthestPoint) {
  const Crease crease;
  // A node held back 1.5 off the crease, between a node on the floor and one on the wall.
  const std::vector<Vec3> points = in_surface_frame({{2, 1.5, 1.5}, {2, 3, 0}, {2, 0, 3}, {3, 3, 0}});
  const std::vector<Tri> triangles = {{0, 1, 2}, {1, 3, 2}};
  std::vector<double> node_distance;
  const auto far = mesh::far_triangles(points, triangles, {}, crease.index, kOrigin, 1.0, node_distance);
  ASSERT_GE(far.size(), 1u);
  EXPECT_EQ(far[0].triangle, 0u);
  EXPECT_NEAR(far[0].distance, 1.5, 1e-12);
  EXPECT_NEAR(node_distance[0], 1.5, 1e-12) << "a node farther than the bound is measured";
  for (const mesh::FarTriangle& f : far) EXPECT_GT(f.distance, 1.0);
}

// A face across a channel: its corners, edge midpoints and centroid lie on tiny input triangles,
// and the input is nowhere else, so far_triangles' samples see it near; a point between them
// (a barycentric grid of step 1/6) is over 0.9 off.
TEST(FarTriangles, AnyFartherLooksBetweenTheSamples) {
  const Vec3 a{0, 0, 0}, b{6, 0, 0}, c{0, 6, 0};
  std::vector<Vec3> input_points;
  std::vector<Tri> input_triangles;
  for (const Vec3& q : {a, b, c, (a + b) * 0.5, (b + c) * 0.5, (c + a) * 0.5, (a + b + c) * (1.0 / 3)}) {
    const uint32_t n = uint32_t(input_points.size());
    input_points.insert(input_points.end(), {q, q + Vec3{0.01, 0, 0}, q + Vec3{0, 0.01, 0}});
    input_triangles.push_back({n, n + 1, n + 2});
  }
  const mesh::SurfaceIndex index(input_points, input_triangles);
  const std::vector<Vec3> points = in_surface_frame({a, b, c});
  const std::vector<Tri> triangles = {{0, 1, 2}};
  std::vector<double> node_distance;
  EXPECT_TRUE(mesh::far_triangles(points, triangles, {}, index, kOrigin, 0.5, node_distance).empty());
  const std::vector<mesh::FarTriangle> far = {{0, 0.5, points[0]}};
  EXPECT_TRUE(mesh::any_farther(points, triangles, far, index, kOrigin, 6, 0.9));  // (1, 1, 0): 1.4 off
  EXPECT_FALSE(mesh::any_farther(points, triangles, far, index, kOrigin, 6, 1.5));
  EXPECT_FALSE(mesh::any_farther(points, triangles, far, index, kOrigin, 2, 0.9)) << "the samples themselves";
  EXPECT_FALSE(mesh::any_farther(points, triangles, {}, index, kOrigin, 6, 0.0));
}

}  // namespace
