// Stage 3: projection of the voxel surface onto the input, kept valid at every step.
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <random>

#include "check/intersections.h"
#include "common/closest_point.h"
#include "common/triangle_buckets.h"
#include "common/vec.h"
#include "extract/extract_surface.h"
#include "fit/fit_surface.h"
#include "mesh/surface_index.h"
#include "grid/flood_fill.h"
#include "grid/refine.h"
#include "prep/prepare.h"
#include "test_meshes.h"
#include "pipeline/stage_params.h"

using namespace vdbwrap;
using namespace vdbwrap::testing;

namespace {

struct Fitted {
  prep::PreparedInput input;
  std::unique_ptr<grid::AdaptiveGrid> grid;
  fit::FittedSurface surface;
};

Fitted fit_mesh(const Mesh& m, double base_percent, WrapParams params = {}) {
  Fitted f;
  f.input = prep::prepare(m, pipeline::prepare_params(params), nullptr);
  const double base = base_percent * 0.01 * f.input.diagonal;
  auto controls =
      grid::make_size_controls(pipeline::size_requests(params), f.input.mesh, f.input.origin, f.input.diagonal, base);
  auto refined = grid::build_refined_grid(f.input, pipeline::refine_criteria(params), base, controls, nullptr);
  f.grid = std::move(refined.grid);
  grid::Components comps;
  int32_t label = grid::choose_volume(*f.grid, params.volume, comps, nullptr);
  extract::ExtractStats stats;
  auto lattice = extract::extract_manifold_surface(*f.grid, label, params.volume, stats, nullptr);
  mesh::SurfaceIndex index(f.input.mesh.points, f.input.mesh.triangles);
  f.surface = fit::fit_to_input(lattice, *f.grid, index, {}, Vec3{0, 0, 0}, pipeline::fit_params(params), nullptr);
  return f;
}

}  // namespace

TEST(Projection, SphereNodesLandJustOutsideTheInput) {
  Fitted f = fit_mesh(sphere_mesh(1.0, 32, 64), 3);
  ASSERT_EQ(f.surface.held_back, 0u);
  mesh::SurfaceIndex index(f.input.mesh.points, f.input.mesh.triangles);
  const double offset = WrapParams{}.surface_offset * f.grid->fine_size();
  for (const Vec3& p : f.surface.points) {
    auto hit = index.closest(p);
    double d = std::sqrt(hit.squared_distance);
    // At most the offset away (less next to a convex crease, where a facet normal was used).
    EXPECT_LE(d, offset * (1 + 1e-9) + 1e-12 * f.input.diagonal);
    EXPECT_GT(d, 0.0);
    EXPECT_GT(dot(p - hit.point, hit.normal), 0.0) << "an outside wrap's nodes stay outside";
  }
  EXPECT_TRUE(check::mesh_self_intersecting_faces(f.surface.points, f.surface.triangles).empty());
}

TEST(Projection, InsideWrapNodesStayInside) {
  WrapParams p;
  p.volume = VolumeChoice::Inside;
  Fitted f = fit_mesh(sphere_mesh(1.0, 32, 64), 3, p);
  mesh::SurfaceIndex index(f.input.mesh.points, f.input.mesh.triangles);
  for (const Vec3& q : f.surface.points) {
    auto hit = index.closest(q);
    EXPECT_LT(dot(q - hit.point, hit.normal), 0.0);
  }
}

TEST(Projection, TwoSheetsAroundAZeroThicknessPlateNeverMeet) {
  // A single square sheet: the outside wrap goes around both sides of it; projection must
  // keep the two sheets apart (offset) and free of intersections.
  Mesh sheet;
  sheet.points = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}};
  sheet.triangles = {{0, 1, 2}, {0, 2, 3}};
  Fitted f = fit_mesh(sheet, 4);
  EXPECT_TRUE(check::mesh_self_intersecting_faces(f.surface.points, f.surface.triangles).empty());
  size_t above = 0, below = 0;
  for (const Vec3& q : f.surface.points) {
    if (q[0] > 0.05 && q[0] < 0.95 && q[1] > 0.05 && q[1] < 0.95) {
      EXPECT_GT(std::fabs(q[2]), 0.0);
      (q[2] > 0 ? above : below)++;
    }
  }
  EXPECT_GT(above, 0u);
  EXPECT_GT(below, 0u);
}

TEST(Projection, ValidityLoopHoldsNodesBackInsteadOfFolding) {
  // Interpenetrating boxes give concave junctions where plain projection folds; whatever
  // the loop holds back, the result must be free of intersections and degenerate faces.
  Mesh m = box_mesh({0, 0, 0}, {2, 2, 2});
  add_box(m, {1, 0.5, 1}, {3, 1.5, 3}, 1);
  Fitted f = fit_mesh(m, 2);
  // The loop's own verdict (one complete full check, then local checks) and CGAL's agree.
  EXPECT_TRUE(f.surface.valid);
  EXPECT_GT(f.surface.held_back, 0u);
  EXPECT_TRUE(check::mesh_self_intersecting_faces(f.surface.points, f.surface.triangles).empty());
  for (const Tri& t : f.surface.triangles) EXPECT_FALSE(check::triangle_is_degenerate(f.surface.points, t));
}

namespace {
// A CAD-like surface of slivers: a fan cap of 200 spokes and a cylinder side of full-length
// triangles, tilted so that no box is thin.
Mesh sliver_mesh() {
  Mesh m;
  const int n = 200;
  const double r = 1.0, h = 3.0;
  m.points.push_back({0, 0, 0});
  for (int i = 0; i < n; ++i) {
    const double a = 2 * M_PI * i / n;
    m.points.push_back({r * std::cos(a), r * std::sin(a), 0});
  }
  for (int i = 0; i < n; ++i) m.points.push_back({r * std::cos(2 * M_PI * i / n), r * std::sin(2 * M_PI * i / n), h});
  for (uint32_t i = 0; i < uint32_t(n); ++i) {
    const uint32_t a = 1 + i, b = 1 + (i + 1) % n;
    m.triangles.push_back({0, b, a});
    m.triangles.push_back({a, b, b + n});
    m.triangles.push_back({a, b + n, a + n});
  }
  // A finely tessellated plate beside it: the typical triangle is small, so the slivers are
  // split into many pieces.
  const uint32_t base = uint32_t(m.points.size()), g = 40;
  for (uint32_t i = 0; i <= g; ++i)
    for (uint32_t j = 0; j <= g; ++j) m.points.push_back({1.5 + 0.02 * i, -0.4 + 0.02 * j, 0.3 * std::sin(0.2 * i)});
  for (uint32_t i = 0; i < g; ++i)
    for (uint32_t j = 0; j < g; ++j) {
      const uint32_t a = base + i * (g + 1) + j;
      m.triangles.push_back({a, a + g + 1, a + 1});
      m.triangles.push_back({a + 1, a + g + 1, a + g + 2});
    }
  for (auto& p : m.points) {  // tilt about x and y
    const double y = p[1] * std::cos(0.5) - p[2] * std::sin(0.5), z = p[1] * std::sin(0.5) + p[2] * std::cos(0.5);
    const double x = p[0] * std::cos(0.3) + z * std::sin(0.3), z2 = -p[0] * std::sin(0.3) + z * std::cos(0.3);
    p = {x, y, z2};
  }
  return m;
}
// Uniform doubles in [lo, hi) from a fixed seed (the same sequence on every platform).
struct Uniform {
  explicit Uniform(uint64_t seed) : state(seed) {}
  double operator()(double lo, double hi) {
    state = state * 6364136223846793005ull + 1442695040888963407ull;
    return lo + (hi - lo) * double(state >> 11) / double(1ull << 53);
  }
  uint64_t state;
};
}  // namespace

// The index splits long thin triangles into pieces for its tree; every answer must still be the
// nearest point of the whole triangle set.
TEST(SurfaceIndex, NearestPointsAreExactOnSliversAndFans) {
  const Mesh m = sliver_mesh();
  mesh::SurfaceIndex index(m.points, m.triangles);
  Uniform uniform(12345);
  for (int k = 0; k < 3000; ++k) {
    const Vec3 q{uniform(-2, 3), uniform(-2, 3), uniform(-2, 4)};
    double best = INFINITY;
    for (const Tri& t : m.triangles)
      best = std::min(best, norm2(closest_on_triangle(q, m.points[t[0]], m.points[t[1]], m.points[t[2]]) - q));
    const auto hit = index.closest(q);
    ASSERT_NEAR(hit.squared_distance, best, 1e-12 * (1 + best)) << "query " << k;
    ASSERT_NEAR(norm2(hit.point - q), best, 1e-9 * (1 + best));
    const Tri& t = m.triangles[hit.triangle];
    EXPECT_NEAR(norm2(closest_on_triangle(q, m.points[t[0]], m.points[t[1]], m.points[t[2]]) - q), best,
                1e-12 * (1 + best));
    const double d = std::sqrt(best);
    EXPECT_TRUE(index.within(q, d * 1.001 + 1e-12));
    if (d > 1e-6) EXPECT_FALSE(index.within(q, d * 0.999));
    // Bounded: the same hit within a radius beyond the nearest distance, none short of it.
    mesh::SurfaceIndex::Hit near;
    ASSERT_TRUE(index.closest_within(q, d * 1.001 + 1e-12, near)) << "query " << k;
    EXPECT_EQ(near.triangle, hit.triangle);
    EXPECT_EQ(near.point, hit.point);
    EXPECT_EQ(near.squared_distance, hit.squared_distance);
    if (d > 1e-6) EXPECT_FALSE(index.closest_within(q, d * 0.999, near)) << "query " << k;
  }
}

// Cells crowded with slivers (the fan's centre, the cylinder's side) are cut into eighths in
// the index: queries packed around them, where the cut pieces are, must still get the nearest
// point of the whole set, and "within" must agree with it.
TEST(SurfaceIndex, NearestPointsAreExactInCrowdedCells) {
  const Mesh m = sliver_mesh();
  mesh::SurfaceIndex index(m.points, m.triangles);
  Uniform uniform(777);
  const int n = 200;
  for (int k = 0; k < 4000; ++k) {
    Vec3 q;
    if (k % 2 == 0) {  // around the fan's centre
      q = m.points[0] + Vec3{uniform(-0.05, 0.05), uniform(-0.05, 0.05), uniform(-0.05, 0.05)};
    } else {  // just off the cylinder's side, inside or outside
      const int i = int(uniform(0, n));
      const Vec3 on = lerp(m.points[1 + i], m.points[1 + n + i], uniform(0, 1));
      q = on + Vec3{uniform(-0.01, 0.01), uniform(-0.01, 0.01), uniform(-0.01, 0.01)};
    }
    double best = INFINITY;
    for (const Tri& t : m.triangles)
      best = std::min(best, norm2(closest_on_triangle(q, m.points[t[0]], m.points[t[1]], m.points[t[2]]) - q));
    const auto hit = index.closest(q);
    ASSERT_NEAR(hit.squared_distance, best, 1e-12 * (1 + best)) << "query " << k;
    const double d = std::sqrt(best);
    EXPECT_TRUE(index.within(q, d * 1.001 + 1e-12)) << "query " << k;
    if (d > 1e-6) EXPECT_FALSE(index.within(q, d * 0.999)) << "query " << k;
  }
}

// Crowded cells sort their triangles along a line and stop early (see Lane in
// surface_index.cpp); each triangle is also dismissed by a bound in its own frame. Both use
// rounded floats with margins: far from the origin, beside two crossing cylinders of 3000
// slivers and among degenerate triangles (a repeated vertex, three points on a line), the
// nearest triangle must still be the exact one, the lowest index among equally near ones.
TEST(SurfaceIndex, NearestPointsAreExactBesideThousandsOfSliversFarFromTheOrigin) {
  Mesh m;
  const Vec3 far{1000.0, -2000.0, 500.0};
  const int n = 3000;
  auto cylinder = [&](const Vec3& axis_tilt) {
    const uint32_t first = uint32_t(m.points.size());
    for (int end = 0; end < 2; ++end)
      for (int i = 0; i < n; ++i) {
        const double a = 2 * M_PI * i / n;
        Vec3 p{0.5 * std::cos(a), 0.5 * std::sin(a), 2.0 * end};
        const double y = p[1] * std::cos(axis_tilt[0]) - p[2] * std::sin(axis_tilt[0]);
        const double z = p[1] * std::sin(axis_tilt[0]) + p[2] * std::cos(axis_tilt[0]);
        const double x = p[0] * std::cos(axis_tilt[1]) + z * std::sin(axis_tilt[1]);
        m.points.push_back(far + Vec3{x, y, -p[0] * std::sin(axis_tilt[1]) + z * std::cos(axis_tilt[1])});
      }
    for (uint32_t i = 0; i < uint32_t(n); ++i) {
      const uint32_t a = first + i, b = first + (i + 1) % n;
      m.triangles.push_back({a, b, b + n});
      m.triangles.push_back({a, b + n, a + n});
    }
  };
  cylinder({0.4, 0.7});
  cylinder({-0.9, 0.2});
  // Small triangles all around, so that the typical triangle is small and the slivers are cut.
  Uniform uniform(99);
  for (int k = 0; k < 4000; ++k) {
    const Vec3 c = far + Vec3{uniform(-1.5, 1.5), uniform(-1.5, 1.5), uniform(-1, 2.5)};
    const uint32_t a = uint32_t(m.points.size());
    m.points.push_back(c);
    m.points.push_back(c + Vec3{uniform(-0.01, 0.01), uniform(-0.01, 0.01), uniform(-0.01, 0.01)});
    m.points.push_back(c + Vec3{uniform(-0.01, 0.01), uniform(-0.01, 0.01), uniform(-0.01, 0.01)});
    m.triangles.push_back({a, a + 1, a + 2});
    if (k % 50 == 0) m.triangles.push_back({a, a + 1, a + 1});  // a repeated vertex
    if (k % 50 == 1) {                                          // three points on a line
      m.points.push_back(lerp(m.points[a], m.points[a + 1], 0.25));
      m.triangles.push_back({a, uint32_t(m.points.size() - 1), a + 1});
    }
  }
  // A few slivers duplicated: exactly equal distances, so the lowest index must win.
  for (uint32_t k = 0; k < 200; k += 7) m.triangles.push_back(m.triangles[k]);
  mesh::SurfaceIndex index(m.points, m.triangles);
  for (int k = 0; k < 3000; ++k) {
    // Beside a sliver of either cylinder, at distances from none to a tenth of the radius.
    const uint32_t f = uint32_t(uniform(0, 4 * n));
    const Tri& t = m.triangles[f];
    const Vec3 on = lerp(lerp(m.points[t[0]], m.points[t[1]], uniform(0, 1)), m.points[t[2]], uniform(0, 1));
    const double s = k % 3 == 0 ? 1e-6 : (k % 3 == 1 ? 1e-3 : 5e-2);
    const Vec3 q = on + Vec3{uniform(-s, s), uniform(-s, s), uniform(-s, s)};
    double best = INFINITY;
    uint32_t lowest = UINT32_MAX;
    for (uint32_t g = 0; g < m.triangles.size(); ++g) {
      const Tri& u = m.triangles[g];
      const double d2 = norm2(closest_on_triangle(q, m.points[u[0]], m.points[u[1]], m.points[u[2]]) - q);
      if (d2 < best) best = d2, lowest = g;
    }
    const auto hit = index.closest(q);
    ASSERT_EQ(hit.squared_distance, best) << "query " << k;
    ASSERT_EQ(hit.triangle, lowest) << "query " << k;
    const double d = std::sqrt(best);
    EXPECT_TRUE(index.within(q, d * (1 + 1e-9) + 1e-12)) << "query " << k;
    if (d > 1e-9) EXPECT_FALSE(index.within(q, d * (1 - 1e-6))) << "query " << k;
  }
}

// touches() looks only at the slivers of a sorted piece whose keys lie within reach of the
// query along the lane (see MeetsTraits), with float margins. Far from the origin, a cylinder
// side of 1500 slivers among many tiny triangles (so the slivers are long, cut by cells and
// sorted): tiny and small triangles beside the slivers must get the answer of every triangle
// tested directly. (Exact contact is left out: touches() is a floating-point test, and there it
// may go either way.)
TEST(SurfaceIndex, TouchesAgreesWithEveryTriangleOnSortedSliversFarFromTheOrigin) {
  Mesh m;
  const Vec3 far{1000.0, -2000.0, 500.0};
  const int n = 1500;
  for (int end = 0; end < 2; ++end)
    for (int i = 0; i < n; ++i) {
      const double a = 2 * M_PI * i / n;
      const Vec3 p{0.5 * std::cos(a), 0.5 * std::sin(a), 2.0 * end};
      m.points.push_back(
          far + Vec3{p[0], p[1] * std::cos(0.6) - p[2] * std::sin(0.6), p[1] * std::sin(0.6) + p[2] * std::cos(0.6)});
    }
  for (uint32_t i = 0; i < uint32_t(n); ++i) {
    const uint32_t a = i, b = (i + 1) % n;
    m.triangles.push_back({a, b, b + n});
    m.triangles.push_back({a, b + n, a + n});
  }
  Uniform uniform(4242);
  for (int k = 0; k < 8000; ++k) {  // tiny triangles off to one side
    const Vec3 c = far + Vec3{uniform(2, 4), uniform(-1, 1), uniform(-1, 1)};
    const uint32_t a = uint32_t(m.points.size());
    m.points.push_back(c);
    m.points.push_back(c + Vec3{0.01, uniform(0, 0.01), 0});
    m.points.push_back(c + Vec3{0, uniform(0, 0.01), 0.01});
    m.triangles.push_back({a, a + 1, a + 2});
  }
  mesh::SurfaceIndex index(m.points, m.triangles);
  size_t touching = 0;
  std::vector<Vec3> pts = m.points;
  const uint32_t a = uint32_t(pts.size());
  pts.resize(pts.size() + 3);
  for (int k = 0; k < 2000; ++k) {
    const Tri& t = m.triangles[uint32_t(uniform(0, 2 * n))];
    const double s = k % 3 == 0 ? 1e-5 : (k % 3 == 1 ? 2e-4 : 2e-3);
    const Vec3 on = lerp(lerp(m.points[t[0]], m.points[t[1]], uniform(0, 1)), m.points[t[2]], uniform(0, 1));
    const Vec3 p0 = on + Vec3{uniform(-s, s), uniform(-s, s), uniform(-s, s)};
    pts[a] = p0, pts[a + 1] = p0 + Vec3{uniform(-s, s), uniform(-s, s), uniform(-s, s)},
    pts[a + 2] = p0 + Vec3{uniform(-s, s), uniform(-s, s), uniform(-s, s)};
    bool expected = false;
    for (const Tri& u : m.triangles)
      if (!expected && check::triangle_pair_intersects(pts, u, Tri{a, a + 1, a + 2})) expected = true;
    ASSERT_EQ(index.touches(pts[a], pts[a + 1], pts[a + 2]), expected) << "triangle " << k;
    touching += expected;
  }
  EXPECT_GT(touching, 400u);
  EXPECT_GT(2000 - touching, 400u);
}

// Each query starts from the triangle the thread found last, so answers must not depend on
// the order of queries: the nearest triangle, the lowest index among equally near ones. On a
// grid of exactly coplanar triangles, many queries are equally near several triangles.
TEST(SurfaceIndex, AnswersDoNotDependOnTheOrderOfQueries) {
  Mesh m = sliver_mesh();
  std::vector<Vec3> queries;
  for (int i = 0; i <= 40; ++i)
    for (int j = 0; j <= 40; ++j) {
      queries.push_back({1.5 + 0.01 * i, -0.4 + 0.02 * j, 0.5});  // over vertices and edges of the plate
      queries.push_back({0.05 * i - 1, 0.05 * j - 1, 4.0});       // far above the fan's side
    }
  mesh::SurfaceIndex index(m.points, m.triangles);
  std::vector<mesh::SurfaceIndex::Hit> forward, backward(queries.size());
  for (const Vec3& q : queries) forward.push_back(index.closest(q));
  for (size_t k = queries.size(); k-- > 0;) backward[k] = index.closest(queries[k]);
  size_t ties = 0;
  for (size_t k = 0; k < queries.size(); ++k) {
    ASSERT_EQ(forward[k].triangle, backward[k].triangle) << "query " << k;
    ASSERT_EQ(forward[k].point, backward[k].point) << "query " << k;
    ASSERT_EQ(forward[k].squared_distance, backward[k].squared_distance);
    // A hint (a triangle tried first) changes the work, not the answer: far, near, invalid.
    for (uint32_t hint :
         {uint32_t(k * 7919 % m.triangles.size()), forward[k].triangle, uint32_t(m.triangles.size() + 3)}) {
      const auto hinted = index.closest(queries[k], hint);
      ASSERT_EQ(hinted.triangle, forward[k].triangle) << "query " << k << ", hint " << hint;
      ASSERT_EQ(hinted.squared_distance, forward[k].squared_distance);
    }
    // The lowest index among the equally near triangles.
    const Vec3& q = queries[k];
    uint32_t lowest = UINT32_MAX;
    size_t equal = 0;
    for (uint32_t f = 0; f < m.triangles.size(); ++f) {
      const Tri& t = m.triangles[f];
      if (norm2(closest_on_triangle(q, m.points[t[0]], m.points[t[1]], m.points[t[2]]) - q) ==
          forward[k].squared_distance) {
        lowest = std::min(lowest, f);
        ++equal;
      }
    }
    EXPECT_EQ(forward[k].triangle, lowest) << "query " << k;
    ties += equal > 1;
  }
  EXPECT_GT(ties, 100u) << "the test needs queries equally near several triangles";
}

// within() with hints gives the tree's answer whatever the hints (near, far, none, invalid),
// and a triangle it reports is within the radius.
TEST(SurfaceIndex, WithinGivesTheSameAnswerWithAnyHints) {
  Mesh m = sliver_mesh();
  mesh::SurfaceIndex index(m.points, m.triangles);
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(-1.5, 3.5);
  std::uniform_int_distribution<uint32_t> tri(0, uint32_t(m.triangles.size()) - 1);
  size_t yes = 0, no = 0, hinted = 0;
  for (int i = 0; i < 3000; ++i) {
    const Vec3 q{u(rng), u(rng), 0.3 * u(rng)};
    const double r = 0.05 + 0.2 * (i % 5);
    const bool expected = index.within(q, r);
    // A hint that says yes when it may: the nearest triangle, every other query.
    const uint32_t good = index.closest(q).triangle;
    const std::array<uint32_t, 3> hints{i % 2 ? good : tri(rng), UINT32_MAX, uint32_t(m.triangles.size() + 7)};
    uint32_t found = UINT32_MAX;
    EXPECT_EQ(index.within(q, r, hints.data(), hints.size(), &found), expected) << "query " << i;
    EXPECT_EQ(index.within(q, r, nullptr, 0, nullptr), expected) << "query " << i;
    if (found != UINT32_MAX) {
      const Tri& t = m.triangles[found];
      EXPECT_LE(norm(closest_on_triangle(q, m.points[t[0]], m.points[t[1]], m.points[t[2]]) - q), r * (1 + 1e-12));
    } else if (expected) {
      ++hinted;
    }
    (expected ? yes : no)++;
  }
  EXPECT_GT(yes, 300u);
  EXPECT_GT(no, 300u);
  EXPECT_GT(hinted, 100u) << "the hints should answer some queries without the tree";
}

// touches() and in_view() walk the same cells of long triangles: against every triangle tested
// directly, small triangles thrown around the slivers must get the same answer, and segments
// through the cap must be blocked.
TEST(SurfaceIndex, TouchesAgreesWithEveryTriangleTestedDirectly) {
  const Mesh m = sliver_mesh();
  mesh::SurfaceIndex index(m.points, m.triangles);
  Uniform uniform(777);
  size_t touching = 0;
  for (int k = 0; k < 3000; ++k) {
    const Vec3 a{uniform(-1.5, 2.5), uniform(-1.5, 2.5), uniform(-1.5, 3.5)};
    const double s = uniform(0.05, 0.4);
    const Vec3 b = a + Vec3{uniform(-s, s), uniform(-s, s), uniform(-s, s)},
               c = a + Vec3{uniform(-s, s), uniform(-s, s), uniform(-s, s)};
    std::vector<Vec3> pts = m.points;
    const uint32_t n = uint32_t(pts.size());
    pts.insert(pts.end(), {a, b, c});
    bool expected = false;
    for (const Tri& t : m.triangles)
      if (!expected && check::triangle_pair_intersects(pts, t, Tri{n, n + 1, n + 2})) expected = true;
    ASSERT_EQ(index.touches(a, b, c), expected) << "triangle " << k;
    touching += expected;
  }
  EXPECT_GT(touching, 100u);
  EXPECT_GT(3000 - touching, 100u);
  // The fan cap (tilted) separates its two sides: from below to above through it is blocked,
  // beside it is clear.
  const Mesh plain = sliver_mesh();
  const Vec3 centre = plain.points[0], rim = plain.points[1];
  const Vec3 up = normalized(cross(plain.points[1] - centre, plain.points[2] - centre));
  for (double t = 0.05; t < 0.95; t += 0.1) {
    const Vec3 on = centre + (rim - centre) * t;
    EXPECT_FALSE(index.in_view(on - up * 0.5, on + up * 0.5, 0.01)) << t;
    EXPECT_TRUE(index.in_view(on - up * 0.5, on - up * 0.01, 0.001)) << t;
  }
}

// The triangle buckets (the validity loop's and coarsening's neighbour look-ups) find every
// triangle whose box overlaps a query box: near the origin, where the cells are numbered and
// sorted, and 1e18 away, where the cell numbers do not fit and the triangles go in one by one.
TEST(TriangleBuckets, FindEveryTriangleWhoseBoxOverlapsNearAndFarFromTheOrigin) {
  for (const double offset : {0.0, 1e18}) {
    std::mt19937 rng(9);
    std::uniform_real_distribution<double> coord(0.0, 100000.0), step(-3000.0, 3000.0);
    std::vector<Vec3> p;
    std::vector<Tri> t;
    for (uint32_t k = 0; k < 400; ++k) {
      const Vec3 a{offset + coord(rng), offset + coord(rng), offset + coord(rng)};
      p.push_back(a), p.push_back(a + Vec3{step(rng), step(rng), step(rng)}),
          p.push_back(a + Vec3{step(rng), step(rng), step(rng)});
      t.push_back({3 * k, 3 * k + 1, 3 * k + 2});
    }
    TriangleBuckets buckets(p, t, 1000.0);
    size_t found_total = 0;
    for (int q = 0; q < 200; ++q) {
      Box3 query;
      const Vec3 c{offset + coord(rng), offset + coord(rng), offset + coord(rng)};
      query.add(c), query.add(c + Vec3{15000, 15000, 15000});
      std::vector<uint32_t> found, expected;
      buckets.for_each_in_box(query, [&](uint32_t g) { found.push_back(g); });
      for (uint32_t f = 0; f < t.size(); ++f) {
        Box3 b;
        for (uint32_t v : t[f]) b.add(p[v]);
        if (b.overlaps(query)) expected.push_back(f);
      }
      std::sort(found.begin(), found.end());
      ASSERT_EQ(found, expected) << "offset " << offset << ", query " << q;
      found_total += found.size();
    }
    EXPECT_GT(found_total, 100u) << "offset " << offset;  // the queries are not all empty
  }
}

TEST(SurfaceIndex, EmptyInputAnswersWithoutCrashing) {
  mesh::SurfaceIndex index({}, {});
  EXPECT_FALSE(index.within({0, 0, 0}, 1.0));
  EXPECT_EQ(index.closest({0, 0, 0}).triangle, UINT32_MAX);
  EXPECT_FALSE(index.touches({0, 0, 0}, {1, 0, 0}, {0, 1, 0}));
}
