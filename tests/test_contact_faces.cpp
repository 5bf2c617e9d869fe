// Faces where solids touch (voxel art): the feature edges of the union, not of every voxel.
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <map>
#include <random>
#include <set>

#include "common/vec.h"
#include "prep/prepare.h"
#include "test_meshes.h"
#include "vdbwrap/check.h"
#include "vdbwrap/wrap.h"

using namespace vdbwrap;

namespace {

using Cell = std::array<int, 3>;

// A unit cube per voxel, outward, each face split along a diagonal chosen by `rng`: where two
// voxels touch, the two copies of the face coincide (deduplicated as turned twins) or cross
// (coincident pairs of triangles at the face's sides).
Mesh voxel_mesh(const std::set<Cell>& voxels, std::mt19937& rng, int32_t part_from_x = INT32_MAX) {
  Mesh m;
  m.part_names = {"part0", "part1"};
  for (const Cell& c : voxels)
    for (int axis = 0; axis < 3; ++axis)
      for (int side = 0; side < 2; ++side) {
        // The face's corners counterclockwise seen from outside.
        const int u = (axis + 1) % 3, v = (axis + 2) % 3;
        std::array<Vec3, 4> q;
        const int du[4] = {0, 1, 1, 0}, dv[4] = {0, 0, 1, 1};
        for (int k = 0; k < 4; ++k) {
          Vec3 p{double(c[0]), double(c[1]), double(c[2])};
          p[axis] += side;
          p[u] += du[side ? k : 3 - k];
          p[v] += dv[side ? k : 3 - k];
          q[k] = p;
        }
        const uint32_t base = uint32_t(m.points.size());
        m.points.insert(m.points.end(), q.begin(), q.end());
        const uint32_t d = rng() % 2;
        m.triangles.push_back({base + d, base + d + 1, base + (d + 2) % 4});
        m.triangles.push_back({base + d, base + (d + 2) % 4, base + (d + 3) % 4});
        for (int k = 0; k < 2; ++k) m.triangle_part.push_back(c[0] >= part_from_x ? 1 : 0);
      }
  return m;
}

enum class Expect { None, Sharp, NonManifold };

// What the union of the voxels shows at the unit edge along `axis` at `at`: the four cells around
// it decide. One or three (a convex or a concave step): a crease. Two across a diagonal: two
// creases on one line. Two side by side: flat; none or four: not on the surface.
Expect union_edge(const std::set<Cell>& voxels, int axis, const Cell& at) {
  const int u = (axis + 1) % 3, v = (axis + 2) % 3;
  bool in[2][2];
  int count = 0;
  for (int i = 0; i < 2; ++i)
    for (int j = 0; j < 2; ++j) {
      Cell c = at;
      c[u] -= 1 - i;
      c[v] -= 1 - j;
      in[i][j] = voxels.count(c) > 0;
      count += in[i][j];
    }
  if (count == 1 || count == 3) return Expect::Sharp;
  if (count == 2 && in[0][0] == in[1][1]) return Expect::NonManifold;
  return Expect::None;
}

// The feature edges of the prepared voxels by (axis, lower end), against the union's.
void expect_union_features(const std::set<Cell>& voxels, const prep::PreparedInput& p) {
  std::map<std::pair<int, Cell>, prep::FeatureKind> found;
  for (const auto& f : p.feature_edges) {
    const Vec3 a = p.mesh.points[f.a] + p.origin, b = p.mesh.points[f.b] + p.origin;
    int axis = -1, moved = 0;
    for (int k = 0; k < 3; ++k)
      if (std::abs(a[k] - b[k]) > 0.5) axis = k, ++moved;
    ASSERT_EQ(moved, 1) << "a feature edge across a face (a diagonal) at " << a[0] << " " << a[1] << " " << a[2];
    Cell lo;
    for (int k = 0; k < 3; ++k) lo[k] = int(std::lround(std::min(a[k], b[k])));
    found[{axis, lo}] = f.kind;
  }
  Cell lo{INT32_MAX, INT32_MAX, INT32_MAX}, hi{INT32_MIN, INT32_MIN, INT32_MIN};
  for (const Cell& c : voxels)
    for (int k = 0; k < 3; ++k) lo[k] = std::min(lo[k], c[k]), hi[k] = std::max(hi[k], c[k] + 1);
  size_t sharp = 0, flat = 0;
  for (int axis = 0; axis < 3; ++axis)
    for (int x = lo[0]; x <= hi[0]; ++x)
      for (int y = lo[1]; y <= hi[1]; ++y)
        for (int z = lo[2]; z <= hi[2]; ++z) {
          const Cell at{x, y, z};
          const Expect want = union_edge(voxels, axis, at);
          const auto it = found.find({axis, at});
          const std::string where = "edge along axis " + std::to_string(axis) + " from " + std::to_string(x) + " " +
                                    std::to_string(y) + " " + std::to_string(z);
          if (want == Expect::None) {
            EXPECT_TRUE(it == found.end()) << where << " is flat or inside the union, yet a feature";
          } else {
            ASSERT_TRUE(it != found.end()) << where << " is a crease of the union, yet no feature";
            EXPECT_EQ(it->second, want == Expect::Sharp ? prep::FeatureKind::Sharp : prep::FeatureKind::NonManifold)
                << where;
            sharp += want == Expect::Sharp;
          }
          flat += want == Expect::None;
        }
  EXPECT_GT(sharp, 20u);  // the blob has steps, convex and concave
  EXPECT_GT(flat, 20u);
  // The faces where voxels touch are left out: every face kept lies between a voxel and air.
  EXPECT_GT(p.dropped_inside, 0u);
  for (const Tri& t : p.mesh.triangles) {
    Vec3 c{0, 0, 0};
    for (uint32_t v : t) c = c + (p.mesh.points[v] + p.origin) * (1.0 / 3);
    int axis = 0;
    for (int k = 0; k < 3; ++k)
      if (std::abs(c[k] - std::round(c[k])) < 1e-9) axis = k;
    Cell below, above;
    for (int k = 0; k < 3; ++k) below[k] = above[k] = int(std::floor(c[k]));
    below[axis] = int(std::lround(c[axis])) - 1;
    above[axis] = below[axis] + 1;
    EXPECT_NE(voxels.count(below), voxels.count(above))
        << "a face inside the union or in the air at " << c[0] << " " << c[1] << " " << c[2];
  }
}

std::set<Cell> voxel_blob(std::mt19937& rng) {
  std::set<Cell> voxels;
  for (int x = 0; x < 6; ++x)
    for (int y = 0; y < 5; ++y)
      for (int z = 0; z < 4; ++z)
        if ((x - 2.5) * (x - 2.5) + (y - 2) * (y - 2) + 2 * (z - 1.5) * (z - 1.5) < 7 + 4.0 * (rng() % 100) / 100)
          voxels.insert({x, y, z});
  return voxels;
}

prep::PrepareParams outside(bool parts_kept_apart = false) {
  prep::PrepareParams p;
  p.contact_faces_inside = true;
  p.parts_kept_apart = parts_kept_apart;
  return p;
}

}  // namespace

// Voxel art for printing gives every voxel its own cube: every edge where two voxels touch is
// non-manifold, and was a feature curve, a base cell long, though the wrap is flat there.
TEST(ContactFaces, VoxelArtHasTheFeatureEdgesOfItsUnion) {
  for (uint32_t seed = 1; seed <= 6; ++seed) {
    std::mt19937 rng(seed);
    const std::set<Cell> voxels = voxel_blob(rng);
    const auto p = prep::prepare(voxel_mesh(voxels, rng), outside(), nullptr);
    SCOPED_TRACE("seed " + std::to_string(seed) + ", " + std::to_string(voxels.size()) + " voxels");
    expect_union_features(voxels, p);
  }
}

// The inside volume and a seed point's can lie between the solids: their contacts stay features.
TEST(ContactFaces, OnlyAroundTheOutside) {
  std::mt19937 rng(7);
  const std::set<Cell> voxels{{0, 0, 0}, {1, 0, 0}};
  const auto p = prep::prepare(voxel_mesh(voxels, rng), prep::PrepareParams{}, nullptr);
  size_t nonmanifold = 0;
  for (const auto& f : p.feature_edges) nonmanifold += f.kind == prep::FeatureKind::NonManifold;
  EXPECT_EQ(nonmanifold, 4u);  // the four sides of the face where the two voxels touch
  const auto q = prep::prepare(voxel_mesh(voxels, rng), outside(), nullptr);
  EXPECT_EQ(q.feature_edges.size(), 16u);  // the 2 x 1 x 1 box's edges, in unit steps
}

// Parts kept apart by contact prevention are wrapped each on its own: where they touch, the
// wrap has creases.
TEST(ContactFaces, PartsKeptApartKeepTheirContactsFeatures) {
  std::mt19937 rng(8);
  const std::set<Cell> voxels{{0, 0, 0}, {1, 0, 0}};
  const auto apart = prep::prepare(voxel_mesh(voxels, rng, 1), outside(true), nullptr);
  size_t nonmanifold = 0;
  for (const auto& f : apart.feature_edges) nonmanifold += f.kind == prep::FeatureKind::NonManifold;
  EXPECT_EQ(nonmanifold, 4u);
  const auto together = prep::prepare(voxel_mesh(voxels, rng, 1), outside(false), nullptr);
  EXPECT_EQ(together.feature_edges.size(), 16u);
}

// A face given twice, turned, is also a double-sided sheet: standing out of a solid, it is no
// contact, and where it meets the solid the wrap has two concave creases.
TEST(ContactFaces, ADoubleSidedSheetOnASolidStaysAFeature) {
  std::mt19937 rng(9);
  const std::set<Cell> voxels{{0, 0, 0}, {1, 0, 0}};
  Mesh m = voxel_mesh(voxels, rng);
  const uint32_t base = uint32_t(m.points.size());
  m.points.insert(m.points.end(), {{1, 0, 1}, {1, 1, 1}, {1, 1, 2}, {1, 0, 2}});
  for (const Tri& t : std::vector<Tri>{{0, 1, 2}, {0, 2, 3}, {0, 2, 1}, {0, 3, 2}}) {
    m.triangles.push_back({base + t[0], base + t[1], base + t[2]});
    m.triangle_part.push_back(0);
  }
  const auto p = prep::prepare(m, outside(), nullptr);
  bool sheet_foot = false;
  for (const auto& f : p.feature_edges) {
    const Vec3 a = p.mesh.points[f.a] + p.origin, b = p.mesh.points[f.b] + p.origin;
    if (a[0] == 1 && b[0] == 1 && a[2] == 1 && b[2] == 1) sheet_foot = f.kind == prep::FeatureKind::NonManifold;
  }
  EXPECT_TRUE(sheet_foot);
}

// A small box on a large one, the large one's top split its own way: the two faces meet at an
// edge, coincident and turned apart, but the large one's triangle reaches past the small box.
// Dropped, it left a hole (not_convex.obj, a table of boxes, came out 10x farther).
TEST(ContactFaces, AFaceReachingPastItsPartnerStays) {
  Mesh m;
  vdbwrap::testing::add_box(m, {0, 0, 0}, {2, 1, 1});
  vdbwrap::testing::add_box(m, {0, 0, 1}, {1, 1, 2});
  const auto p = prep::prepare(m, outside(), nullptr);
  EXPECT_EQ(p.dropped_inside, 0u);
  EXPECT_EQ(p.mesh.triangles.size(), 24u);
  for (const auto& f : p.feature_edges) EXPECT_NE(f.kind, prep::FeatureKind::Boundary);
}

// Turned inside out, the faces around the contacts put the material on the wrong side: no
// contact edge is judged, and none of the faces inside, between four voxels, may go alone
// (dropping them left their neighbours' rims in the material: 1,405 boundary edges on voxel
// art of 10k voxels).
TEST(ContactFaces, AnInsideOutVoxelModelKeepsItsFacesWhole) {
  for (uint32_t seed = 1; seed <= 6; ++seed) {
    std::mt19937 rng(seed);
    const std::set<Cell> voxels = voxel_blob(rng);
    Mesh m = voxel_mesh(voxels, rng);
    for (Tri& t : m.triangles) std::swap(t[1], t[2]);
    const auto p = prep::prepare(m, outside(), nullptr);
    for (const auto& f : p.feature_edges) EXPECT_NE(f.kind, prep::FeatureKind::Boundary) << "seed " << seed;
  }
}

// The report measures the wrap against the input as prepared (the projection's index), with
// the contact faces left out: the distance to the union's surface. It is the distance to the
// input as given (`vdbwrap check --against`) but where the wrap dips into the material (a
// chord across a concave step) and a face inside is nearer than the surface: never nearer.
TEST(ContactFaces, TheReportMeasuresTheWrapAgainstTheUnionsSurface) {
  std::mt19937 rng(3);
  const Mesh m = voxel_mesh(voxel_blob(rng), rng);
  WrapParams p;
  p.base_size = Length{4, true};
  const WrapResult r = wrap(m, p);
  ASSERT_GT(r.report.features.inside_faces, 0u);
  const DistanceStats given = sampled_distance(r.surface, m);
  const DistanceStats& reported = r.report.output_to_input;
  EXPECT_EQ(reported.samples, given.samples);
  EXPECT_DOUBLE_EQ(reported.diagonal, given.diagonal);
  const double eps = 1e-9 * given.diagonal;
  EXPECT_GE(reported.mean, given.mean - eps);
  EXPECT_LE(reported.mean, 1.05 * given.mean + eps);
  EXPECT_GE(reported.p95, given.p95 - eps);
  EXPECT_GE(reported.max, given.max - eps);
  EXPECT_LE(reported.max, 1.05 * given.max + eps);
}
