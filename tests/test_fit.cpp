// Stage 3: projection of the voxel surface onto the input, kept valid at every step.
#include <gtest/gtest.h>

#include <cmath>

#include "check/intersections.h"
#include "common/vec.h"
#include "extract/extract_surface.h"
#include "fit/fit_surface.h"
#include "fit/surface_index.h"
#include "grid/flood_fill.h"
#include "grid/refine.h"
#include "prep/prepare.h"
#include "test_meshes.h"

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
  f.input = prep::prepare(m, params, nullptr);
  const double base = base_percent * 0.01 * f.input.diagonal;
  auto controls = grid::make_size_controls(params, f.input.mesh, f.input.origin, f.input.diagonal, base);
  auto refined = grid::build_refined_grid(f.input, params, base, controls, nullptr);
  f.grid = std::move(refined.grid);
  grid::Components comps;
  int32_t label = grid::choose_volume(*f.grid, params.volume, comps, nullptr);
  extract::ExtractStats stats;
  auto lattice = extract::extract_manifold_surface(*f.grid, label, params.volume, stats, nullptr);
  fit::SurfaceIndex index(f.input.mesh.points, f.input.mesh.triangles);
  f.surface = fit::fit_to_input(lattice, *f.grid, index, {}, Vec3{0, 0, 0}, params, nullptr);
  return f;
}

}  // namespace

TEST(Projection, SphereNodesLandJustOutsideTheInput) {
  Fitted f = fit_mesh(sphere_mesh(1.0, 32, 64), 3);
  ASSERT_EQ(f.surface.held_back, 0u);
  fit::SurfaceIndex index(f.input.mesh.points, f.input.mesh.triangles);
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
  fit::SurfaceIndex index(f.input.mesh.points, f.input.mesh.triangles);
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
  EXPECT_TRUE(check::mesh_self_intersecting_faces(f.surface.points, f.surface.triangles).empty());
  for (const Tri& t : f.surface.triangles)
    EXPECT_FALSE(check::triangle_is_degenerate(f.surface.points, t));
}
