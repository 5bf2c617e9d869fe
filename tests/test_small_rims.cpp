// Rims of open pieces too small for the wrap to show (mesh/small_rims.h): a raw scan's floating
// fragments are no feature curves; the scan's own opening stays one.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "common/vec.h"
#include "mesh/small_rims.h"
#include "pipeline/stage_params.h"
#include "prep/prepare.h"
#include "test_meshes.h"
#include "vdbwrap/check.h"
#include "vdbwrap/wrap.h"

using namespace vdbwrap;
using namespace vdbwrap::testing;

namespace {

// An open dome (a turntable scan without its base) of radius 1, and `fragments` small fans
// floating near it, each `size` across: what a raw scan keeps of its noise.
Mesh scan_with_fragments(int fragments, double size, uint32_t seed) {
  Mesh m;
  const int rings = 24, segments = 48;
  for (int i = 0; i <= rings; ++i)
    for (int j = 0; j < segments; ++j) {
      const double th = 0.5 * M_PI * i / rings, ph = 2 * M_PI * j / segments;
      m.points.push_back({std::sin(th) * std::cos(ph), std::sin(th) * std::sin(ph), std::cos(th)});
    }
  for (int i = 0; i < rings; ++i)
    for (int j = 0; j < segments; ++j) {
      const uint32_t a = i * segments + j, b = i * segments + (j + 1) % segments;
      const uint32_t c = a + segments, d = b + segments;
      if (i > 0) m.triangles.push_back({a, c, b});  // the pole's ring collapses to a point
      m.triangles.push_back({b, c, d});
    }
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-1, 1);
  for (int f = 0; f < fragments; ++f) {
    Vec3 c{u(rng), u(rng), 0.5 + 0.5 * u(rng)};
    c = normalized(c) * (1.1 + 0.1 * u(rng));
    const uint32_t centre = uint32_t(m.points.size());
    m.points.push_back(c);
    const int k = 5;
    for (int s = 0; s < k; ++s) {
      const double a = 2 * M_PI * s / k;
      m.points.push_back(c + Vec3{0.5 * size * std::cos(a), 0.5 * size * std::sin(a), 0.2 * size * u(rng)});
    }
    for (int s = 0; s + 1 < k; ++s) m.triangles.push_back({centre, centre + 1 + s, centre + 2 + s});
  }
  m.triangle_part.assign(m.triangles.size(), 0);
  m.part_names = {"scan"};
  return m;
}

size_t boundary(const std::vector<mesh::FeatureEdge>& edges) {
  size_t n = 0;
  for (const auto& e : edges) n += e.kind == mesh::FeatureKind::Boundary;
  return n;
}

}  // namespace

TEST(SmallRims, FragmentsRimsGoTheScansOpeningStays) {
  const int fragments = 40;
  const Mesh scan = scan_with_fragments(fragments, 0.03, 3);
  prep::PreparedInput in = prep::prepare(scan, prep::PrepareParams{}, nullptr);
  const double base = 0.01 * in.diagonal;
  const size_t before = boundary(in.feature_edges);
  const size_t dropped = mesh::drop_small_rims(in.mesh.points, in.feature_edges, pipeline::kSmallestRim * base);
  // Every fragment's rim (6 edges: a fan of 4 triangles' 4 outer sides and 2 spokes) goes, the
  // dome's opening (48) stays.
  EXPECT_EQ(dropped, size_t(fragments) * 6);
  EXPECT_EQ(boundary(in.feature_edges), before - dropped);
  EXPECT_EQ(boundary(in.feature_edges), 48u);
  for (const auto& e : in.feature_edges)
    if (e.kind == mesh::FeatureKind::Boundary)
      EXPECT_NEAR(in.mesh.points[e.a][2] + in.origin[2], 0, 1e-9) << "a boundary edge left off the dome's rim";
  // Nothing of a larger fragment: its rim is over three base cells across.
  prep::PreparedInput large = prep::prepare(scan_with_fragments(fragments, 0.2, 3), prep::PrepareParams{}, nullptr);
  EXPECT_EQ(mesh::drop_small_rims(large.mesh.points, large.feature_edges, pipeline::kSmallestRim * base), 0u);
}

TEST(SmallRims, AScanWithFragmentsWrapsValidAndNear) {
  const Mesh scan = scan_with_fragments(200, 0.03, 4);
  WrapParams p;
  p.base_size = Length{1, true};
  const WrapResult r = wrap(scan, p);
  auto v = valid_closed_surface(r.surface);
  EXPECT_TRUE(v.ok) << v.why;
  // Every fragment's rim goes: as a small rim, or, beside another fragment's within a finest
  // cell, as a side of a gap (where the two fragments turn from each other, one side stays as a
  // crease's edge: a few).
  const size_t gone = r.report.features.small_rim_edges + r.report.features.crack_edges;
  EXPECT_LE(gone, 200u * 6);
  EXPECT_GE(gone, 200u * 6 - 12);
  EXPECT_LT(r.report.output_to_input.max, 1.5 * r.report.base_size);
}
