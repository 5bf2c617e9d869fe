// Sharp edges between strips narrower than the finest cell (mesh/narrow_strips.h): a thin tube
// with few sides is no set of feature curves; a part's own edges, a chamfer's and a thin
// wall's rims stay.
#include <gtest/gtest.h>

#include <cmath>

#include "common/vec.h"
#include "mesh/narrow_strips.h"
#include "post/quality.h"
#include "prep/prepare.h"
#include "test_meshes.h"
#include "vdbwrap/check.h"
#include "vdbwrap/wrap.h"

using namespace vdbwrap;
using namespace vdbwrap::testing;

namespace {

// A closed prism: the polygon (x, y, counter-clockwise) from z0 to z1, caps fanned from their
// centres.
void add_prism(Mesh& m, const std::vector<std::array<double, 2>>& polygon, double z0, double z1) {
  const uint32_t o = uint32_t(m.points.size()), n = uint32_t(polygon.size());
  double cx = 0, cy = 0;
  for (const auto& p : polygon) cx += p[0] / n, cy += p[1] / n;
  for (double z : {z0, z1})
    for (const auto& p : polygon) m.points.push_back({p[0], p[1], z});
  m.points.push_back({cx, cy, z0});
  m.points.push_back({cx, cy, z1});
  const uint32_t bottom = o + 2 * n, top = bottom + 1;
  for (uint32_t i = 0; i < n; ++i) {
    const uint32_t j = (i + 1) % n;
    m.triangles.push_back({o + i, o + j, o + n + j});
    m.triangles.push_back({o + i, o + n + j, o + n + i});
    m.triangles.push_back({bottom, o + j, o + i});
    m.triangles.push_back({top, o + n + i, o + n + j});
  }
}

std::vector<std::array<double, 2>> regular(double cx, double cy, double r, int sides) {
  std::vector<std::array<double, 2>> p;
  for (int k = 0; k < sides; ++k)
    p.push_back({cx + r * std::cos(2 * M_PI * k / sides), cy + r * std::sin(2 * M_PI * k / sides)});
  return p;
}

// A tube of `sides` flat sides, radius r, from a to b, open at its ends.
void add_tube(Mesh& m, const Vec3& a, const Vec3& b, double r, int sides) {
  const Vec3 t = normalized(b - a);
  const Vec3 u = normalized(cross(t, std::abs(t[2]) < 0.9 ? Vec3{0, 0, 1} : Vec3{1, 0, 0})), w = cross(t, u);
  const uint32_t o = uint32_t(m.points.size()), n = uint32_t(sides);
  for (const Vec3& c : {a, b})
    for (int k = 0; k < sides; ++k) {
      const double angle = 2 * M_PI * k / sides;
      m.points.push_back(c + (u * std::cos(angle) + w * std::sin(angle)) * r);
    }
  for (uint32_t i = 0; i < n; ++i) {
    const uint32_t j = (i + 1) % n;
    m.triangles.push_back({o + i, o + j, o + n + j});
    m.triangles.push_back({o + i, o + n + j, o + n + i});
  }
}

size_t sharp(const std::vector<mesh::FeatureEdge>& edges) {
  size_t n = 0;
  for (const auto& e : edges) n += e.kind == mesh::FeatureKind::Sharp;
  return n;
}

}  // namespace

// Four parts apart, at a finest cell of 0.25: a cube, a block with one edge chamfered 0.14
// wide, a plate 0.1 thick, a hexagonal rod 0.1 across. The rod's 18 edges go (its sides and
// ends are narrow), and the plate's 4 corner edges (between two narrow sides); the cube's 12,
// the block's 15 (the chamfer is narrow, the faces beside it are not) and the plate's 8 rim
// edges stay.
TEST(NarrowStrips, ATubesEdgesGoAPartsChamfersAndRimsStay) {
  Mesh m;
  add_prism(m, {{0, 0}, {10, 0}, {10, 10}, {0, 10}}, 0, 10);
  add_prism(m, {{20, 0}, {30, 0}, {30, 9.9}, {29.9, 10}, {20, 10}}, 0, 10);
  add_prism(m, {{40, 0}, {50, 0}, {50, 10}, {40, 10}}, 0, 0.1);
  add_prism(m, regular(60, 5, 0.05, 6), 0, 10);
  prep::PreparedInput in = prep::prepare(m, prep::PrepareParams{}, nullptr);
  ASSERT_EQ(sharp(in.feature_edges), 12u + 15u + 12u + 18u);
  const size_t dropped = mesh::drop_narrow_strip_edges(
      in.feature_edges, mesh::narrow_faces(in.mesh.points, in.mesh.triangles, in.feature_edges, 0.25));
  EXPECT_EQ(dropped, 18u + 4u);
  EXPECT_EQ(sharp(in.feature_edges), 12u + 15u + 8u);
  for (const auto& e : in.feature_edges) {
    const Vec3 a = in.mesh.points[e.a] + in.origin, b = in.mesh.points[e.b] + in.origin;
    EXPECT_LT(a[0], 55) << "an edge of the rod kept";
    if (a[0] >= 40) EXPECT_NEAR(a[2], b[2], 1e-9) << "a corner edge of the plate kept";
  }
  // A finest cell under the rod's sides (0.05 wide): nothing goes.
  prep::PreparedInput again = prep::prepare(m, prep::PrepareParams{}, nullptr);
  EXPECT_EQ(
      mesh::drop_narrow_strip_edges(
          again.feature_edges, mesh::narrow_faces(again.mesh.points, again.mesh.triangles, again.feature_edges, 0.04)),
      0u);
  // Closed pieces get the thin-part refinement's finer cells (here 0.25 / 8): nothing goes
  // either, all four parts being closed.
  EXPECT_EQ(mesh::drop_narrow_strip_edges(
                again.feature_edges, mesh::narrow_faces(again.mesh.points, again.mesh.triangles, again.feature_edges,
                                                        0.25, &again.closed_piece, 0.25 / 8)),
            0u);
}

// A ball with 80 hexagonal strands stuck through it, open tubes a third of a base cell across
// (a sculpt's hair): every side of every strand is narrower than the finest cell. Snapping the
// wrap onto the strands' edges made parallel curves a fraction of a cell apart: nodes inserted
// on each folded the blobs the strands are wrapped as, and left the wrap up to 1.4 base cells
// from the input.
TEST(NarrowStrips, HairOfHexagonalStrandsWrapsNearWithoutSlivers) {
  Mesh m = icosphere_mesh(1, 4);
  for (int i = 0; i < 80; ++i) {
    const double a = i * 2.39996, h = 0.2 + 0.4 * std::fmod(i * 0.618034, 1.0);
    const Vec3 s{0.9 * std::cos(a) * h, 0.9 * std::sin(a) * h, 0.9 * std::sqrt(1 - h * h)};
    const Vec3 d = normalized(s + Vec3{0.3 * std::cos(3 * a), 0.3 * std::sin(5 * a), 0});
    add_tube(m, s, s + d * 0.8, 0.008, 6);
  }
  WrapParams p;
  p.base_size = Length{1, true};
  const WrapResult r = wrap(m, p);
  auto v = valid_closed_surface(r.surface);
  EXPECT_TRUE(v.ok) << v.why;
  EXPECT_GT(r.report.features.narrow_strip_edges, 0u);
  EXPECT_LT(r.report.output_to_input.max, r.report.base_size);
  EXPECT_LT(r.report.output_to_input.mean, 0.0005 * r.report.diagonal);
}

// An unmerged lattice whose struts (boxes 0.2 base cells thick, each reaching past its nodes)
// share corners, welded edges and overlapping coplanar faces at every node, turned off the
// axes: no strut is a closed piece (its faces coincide with its neighbours' around the welded
// edges). The edges between the struts' sides, the welded edges and the lines where struts
// cross were thousands of curves half a strut long, which folded the wrap into 1.9 % of
// triangles under 10 degrees.
TEST(NarrowStrips, CoincidentLatticeStrutsCrossWithoutCurves) {
  const double side = 10, h = 0.25;
  const Vec3 axis = normalized(Vec3{0.3, -0.5, 0.81});
  auto turn = [&](const Vec3& p) {
    const double c = std::cos(0.6), s = std::sin(0.6);
    return p * c + cross(axis, p) * s + axis * (dot(axis, p) * (1 - c));
  };
  Mesh m;
  for (int along = 0; along < 3; ++along)
    for (int i = 0; i <= 4; ++i)
      for (int j = 0; j <= 4; ++j)
        for (int k = 0; k < 4; ++k) {
          Vec3 lo, hi;
          const int u = (along + 1) % 3, v = (along + 2) % 3;
          lo[u] = i * side - h, hi[u] = i * side + h;
          lo[v] = j * side - h, hi[v] = j * side + h;
          lo[along] = k * side - h, hi[along] = (k + 1) * side + h;
          add_box(m, lo, hi);
        }
  for (Vec3& p : m.points) p = turn(p);
  WrapParams p;
  p.base_size = Length{2.6, false};
  const WrapResult r = wrap(m, p);
  auto v = valid_closed_surface(r.surface);
  ASSERT_TRUE(v.ok) << v.why;
  EXPECT_GT(r.report.features.narrow_strip_intersection_segments, 0u);
  EXPECT_EQ(r.report.features.curves, 0u) << "the struts are wrapped as round blobs";
  size_t slivers = 0;
  const auto& q = r.surface.points;
  for (const Tri& t : r.surface.triangles) slivers += post::min_angle_deg(q[t[0]], q[t[1]], q[t[2]]) < 10;
  EXPECT_LE(slivers, r.surface.triangles.size() / 100) << "triangles under 10 degrees";
  EXPECT_LT(r.report.output_to_input.max, r.report.base_size);
  EXPECT_LT(r.report.output_to_input.mean, 0.05 * r.report.base_size);
}
