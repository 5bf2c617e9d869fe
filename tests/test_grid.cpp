// Stage 2: triangle/box overlap, refinement, flood fill, and the extracted surface's topology.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>
#include <cmath>
#include <map>
#include <memory>
#include <random>

#include "extract/extract_surface.h"
#include "grid/flood_fill.h"
#include "grid/refine.h"
#include "prep/prepare.h"
#include "test_meshes.h"
#include "pipeline/stage_params.h"

using namespace vdbwrap;
using namespace vdbwrap::testing;
using openvdb::Coord;

namespace {

// The lattice surface as a triangle mesh (polygons fanned from their first node) for the
// combinatorial checks: closed, manifold, consistently oriented.
Mesh lattice_mesh(const extract::LatticeSurface& s) {
  Mesh m;
  for (const Coord& c : s.nodes) m.points.push_back({double(c.x()), double(c.y()), double(c.z())});
  for (const auto& p : s.polygons)
    for (size_t k = 1; k + 1 < p.size(); ++k) m.triangles.push_back({p[0], p[k], p[k + 1]});
  return m;
}

void expect_closed_manifold(const extract::LatticeSurface& s, VolumeChoice choice) {
  Mesh m = lattice_mesh(s);
  MeshDiagnostics d = diagnose(m, false);
  EXPECT_TRUE(d.closed) << "border " << d.border_edges << " nm-edges " << d.nonmanifold_edges;
  EXPECT_TRUE(d.manifold) << "nm-vertices " << d.nonmanifold_vertices;
  EXPECT_TRUE(d.oriented) << "misoriented " << d.misoriented_edges;
  EXPECT_GT(d.volume, 0) << "the wrap must face away from what it encloses";
  (void)choice;
}

grid::RefineResult refine(const Mesh& m, double base_percent, int levels, WrapParams params = {}) {
  params.levels = levels;
  auto prepared = prep::prepare(m, pipeline::prepare_params(params), nullptr);
  const double base = base_percent * 0.01 * prepared.diagonal;
  auto controls = grid::make_size_controls(pipeline::size_requests(params), prepared.mesh, prepared.origin,
                                           prepared.diagonal, base);
  return grid::build_refined_grid(prepared, pipeline::refine_criteria(params), base, controls, nullptr);
}

}  // namespace

TEST(TriangleBox, SeparatingAxesDecideOverlap) {
  const Vec3 c{0, 0, 0}, h{0.5, 0.5, 0.5};
  EXPECT_TRUE(grid::triangle_overlaps_box({-1, -1, 0}, {1, -1, 0}, {0, 1, 0}, c, h));
  EXPECT_FALSE(grid::triangle_overlaps_box({2, 2, 2}, {3, 2, 2}, {2, 3, 2}, c, h));
  // Diagonal triangle that passes near the corner but misses the box (only its bounding box overlaps).
  EXPECT_FALSE(grid::triangle_overlaps_box({0.9, 0.0, 0.0}, {0.0, 0.9, 0.0}, {0.0, 0.0, 0.9}, {-0.5, -0.5, -0.5},
                                           {0.45, 0.45, 0.45}));
  EXPECT_TRUE(grid::triangle_overlaps_box({0.6, 0.0, 0.0}, {0.0, 0.6, 0.0}, {0.0, 0.0, 0.6}, {0, 0, 0}, h));
  EXPECT_TRUE(grid::segment_overlaps_box({-1, 0, 0}, {1, 0, 0}, {-0.5, -0.5, -0.5}, {0.5, 0.5, 0.5}));
  EXPECT_FALSE(grid::segment_overlaps_box({-1, 1, 0}, {1, 1, 0}, {-0.5, -0.5, -0.5}, {0.5, 0.5, 0.5}));
}

// The block search must find exactly the cells a test of every cell in the box finds, for
// small triangles and for long slanted slivers whose box holds far more cells than they cross.
TEST(TriangleBox, BlockSearchFindsTheSameCellsAsTestingEach) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> coord(-3.0, 3.0), small(-0.4, 0.4);
  const Vec3 origin{-3.17, -2.93, -3.05};
  const double cell = 0.25, half_cell = cell * (0.5 + 1e-3);
  size_t cells_found = 0;
  for (int n = 0; n < 400; ++n) {
    Vec3 a{coord(rng), coord(rng), coord(rng)};
    // Alternately a long triangle across the box and a small one; some exactly on grid planes.
    Vec3 b = n % 2 ? Vec3{coord(rng), coord(rng), coord(rng)} : a + Vec3{small(rng), small(rng), small(rng)};
    Vec3 c = n % 2 ? b + Vec3{small(rng), small(rng), small(rng)} * 0.1 : a + Vec3{small(rng), small(rng), small(rng)};
    if (n % 7 == 0) a[2] = b[2] = c[2] = origin[2] + 9 * cell;
    int lo[3], hi[3];
    for (int k = 0; k < 3; ++k) {
      lo[k] = int(std::floor((std::min({a[k], b[k], c[k]}) - origin[k]) / cell - 1e-3));
      hi[k] = int(std::floor((std::max({a[k], b[k], c[k]}) - origin[k]) / cell + 1e-3));
    }
    std::vector<std::array<int, 3>> each, blocks;
    for (int z = lo[2]; z <= hi[2]; ++z)
      for (int y = lo[1]; y <= hi[1]; ++y)
        for (int x = lo[0]; x <= hi[0]; ++x) {
          const Vec3 center{origin[0] + (x + 0.5) * cell, origin[1] + (y + 0.5) * cell, origin[2] + (z + 0.5) * cell};
          if (triangle_overlaps_box(a, b, c, center, {half_cell, half_cell, half_cell})) each.push_back({x, y, z});
        }
    for_cells_overlapping(a, b, c, origin, cell, half_cell, lo, hi, [&](int x, int y, int z) {
      blocks.push_back({x, y, z});
    });
    std::sort(each.begin(), each.end());
    std::sort(blocks.begin(), blocks.end());
    ASSERT_EQ(each, blocks) << "triangle " << n;
    cells_found += each.size();
  }
  EXPECT_GT(cells_found, 2000u);  // the triangles do cross many cells
}

// The eight octants at once must be the octants a test of each one finds, for long slivers,
// small triangles and triangles lying on the cell's mid-planes, and a subset asked for must
// be that subset of them.
// The prepared tester (refinement's and the nearest-point index's cell tests) gives the
// separating-axis test's answers, for boxes and, through its shortcut, for cubes.
TEST(TriangleBox, PreparedTesterMatchesTheSeparatingAxisTest) {
  std::mt19937 rng(17);
  std::uniform_real_distribution<double> coord(-1.0, 1.0), size(0.01, 0.6);
  size_t met = 0;
  for (int n = 0; n < 3000; ++n) {
    const Vec3 a{coord(rng), coord(rng), coord(rng)}, b{coord(rng), coord(rng), coord(rng)},
        c{coord(rng), coord(rng), coord(rng)};
    const TriangleBoxTester tester(a, b, c);
    const Vec3 centre{coord(rng), coord(rng), coord(rng)};
    const double h = size(rng);
    const Vec3 half{h, size(rng), size(rng)};
    const bool cube = grid::triangle_overlaps_box(a, b, c, centre, {h, h, h});
    ASSERT_EQ(tester.overlaps_cube(centre, h), cube) << "triangle " << n;
    ASSERT_EQ(tester.overlaps(centre, {h, h, h}), cube) << "triangle " << n;
    ASSERT_EQ(tester.overlaps(centre, half), grid::triangle_overlaps_box(a, b, c, centre, half)) << "triangle " << n;
    met += cube;
  }
  EXPECT_GT(met, 300u);
  EXPECT_LT(met, 2700u);
}

TEST(TriangleBox, OctantsAtOnceMatchTestingEachOctant) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> coord(-1.2, 1.2), small(-0.3, 0.3);
  const Vec3 centre{0.13, -0.07, 0.21};
  const double quarter = 0.25, half = quarter * (1 + 2e-3);
  size_t met = 0, partly = 0;
  for (int n = 0; n < 2000; ++n) {
    Vec3 a = centre + Vec3{coord(rng), coord(rng), coord(rng)};
    Vec3 b = n % 2 ? centre + Vec3{coord(rng), coord(rng), coord(rng)} : a + Vec3{small(rng), small(rng), small(rng)};
    Vec3 c = n % 2 ? b + Vec3{small(rng), small(rng), small(rng)} * 0.1 : a + Vec3{small(rng), small(rng), small(rng)};
    if (n % 5 == 0) a[n % 3] = b[n % 3] = c[n % 3] = centre[n % 3];  // on a mid-plane
    uint8_t each = 0;
    for (int k = 0; k < 8; ++k) {
      const Vec3 box{centre[0] + (k & 1 ? quarter : -quarter), centre[1] + (k & 2 ? quarter : -quarter),
                     centre[2] + (k & 4 ? quarter : -quarter)};
      if (triangle_overlaps_box(a, b, c, box, {half, half, half})) each |= uint8_t(1 << k);
    }
    ASSERT_EQ(int(octants_overlapped(a, b, c, centre, quarter, half)), int(each)) << "triangle " << n;
    const uint8_t among = uint8_t(rng());
    ASSERT_EQ(int(octants_overlapped(a, b, c, centre, quarter, half, among)), int(each & among)) << "triangle " << n;
    met += each != 0;
    partly += each != 0 && each != 0xff;
  }
  EXPECT_GT(met, 500u);  // the cases are not all trivial
  EXPECT_GT(partly, 300u);
}

// A level-0 grid of more than 2^32 cells (two small boxes 2000 cells apart on each axis):
// each box must touch and refine the cells it does alone.
TEST(Refine, GridsNumberedPast32BitsFindTheSameCells) {
  const Mesh one = box_mesh({0, 0, 0}, {1, 1, 1});
  Mesh two = one;
  add_box(two, {2000, 2000, 2000}, {2001, 2001, 2001});
  // Base size 0.25 in both (percent of each diagonal): the far box sits on the same cell
  // boundaries as the near one.
  const auto alone = refine(one, 25.0 / std::sqrt(3.0), 1);
  const auto apart = refine(two, 25.0 / (std::sqrt(3.0) * 2001.0), 1);
  ASSERT_GT(double(apart.grid->dims0().x()) * apart.grid->dims0().y() * apart.grid->dims0().z(), 4.3e9);
  ASSERT_EQ(alone.touched_per_level.size(), apart.touched_per_level.size());
  ASSERT_GT(alone.touched_per_level[0], 0u);
  ASSERT_EQ(alone.refined_per_level.size(), apart.refined_per_level.size());
  ASSERT_GT(alone.refined_per_level[0], 0u);  // the boxes' edges refine
  for (size_t level = 0; level < alone.touched_per_level.size(); ++level) {
    EXPECT_EQ(apart.touched_per_level[level], 2 * alone.touched_per_level[level]) << "level " << level;
    EXPECT_EQ(apart.refined_per_level[level], 2 * alone.refined_per_level[level]) << "level " << level;
  }
}

// Level 0 finds its cells block by block: large slanted triangles crossing many blocks must
// touch exactly the cells that a test of each cell against each triangle finds.
TEST(Refine, LevelZeroCellsAreThoseEachCellTestFinds) {
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> coord(0.0, 1.0);
  Mesh soup;
  for (uint32_t t = 0; t < 40; ++t) {
    for (int k = 0; k < 3; ++k) soup.points.push_back({coord(rng), coord(rng), coord(rng)});
    soup.triangles.push_back({3 * t, 3 * t + 1, 3 * t + 2});
  }
  soup.triangle_part.assign(soup.triangles.size(), 0);
  WrapParams params;
  params.levels = 0;
  const auto prepared = prep::prepare(soup, pipeline::prepare_params(params), nullptr);
  const double base = 0.01 * prepared.diagonal;  // about 58 cells a side: 4 blocks
  const auto controls = grid::make_size_controls(pipeline::size_requests(params), prepared.mesh, prepared.origin,
                                                 prepared.diagonal, base);
  const auto r = grid::build_refined_grid(prepared, pipeline::refine_criteria(params), base, controls, nullptr);
  const auto& g = *r.grid;
  const auto& pts = prepared.mesh.points;
  const double half = base * (0.5 + 1e-3);  // refinement's margin
  size_t touched = 0, mismatched = 0;
  for (int x = -1; x <= g.dims0().x(); ++x)
    for (int y = -1; y <= g.dims0().y(); ++y)
      for (int z = -1; z <= g.dims0().z(); ++z) {
        const Vec3 centre = g.origin() + Vec3{(x + 0.5) * base, (y + 0.5) * base, (z + 0.5) * base};
        bool meets = false;
        for (const Tri& t : prepared.mesh.triangles)
          meets = meets || grid::triangle_overlaps_box(pts[t[0]], pts[t[1]], pts[t[2]], centre, {half, half, half});
        touched += meets;
        mismatched += meets != (g.get(0, Coord(x, y, z)) == grid::kTouched);
      }
  EXPECT_GT(touched, 5000u);
  EXPECT_EQ(r.touched_per_level[0], touched);
  EXPECT_EQ(mismatched, 0u);
}

TEST(Refine, FeaturesRefineAndFlatFacesDoNot) {
  // Normal spread is switched off (179 degrees) so features alone decide.
  Mesh box = box_mesh({0, 0, 0}, {1, 1, 1});
  WrapParams features;
  features.refine_normal_spread_deg = 179;
  auto with = refine(box, 5, 2, features);
  WrapParams no_features = features;
  no_features.refine_at_features = false;
  auto without = refine(box, 5, 2, no_features);
  ASSERT_EQ(with.touched_per_level.size(), 3u);
  EXPECT_GT(with.touched_per_level[2], 0u);
  // Without features the box's flat faces (two triangles each, one normal) never refine.
  ASSERT_GE(without.touched_per_level.size(), 1u);
  EXPECT_TRUE(without.touched_per_level.size() == 1 || without.touched_per_level[1] == 0);
  // Refined cells only near the edges: far fewer than refining every touched cell.
  EXPECT_LT(with.touched_per_level[2], 8 * 8 * with.touched_per_level[0] / 2);
}

TEST(Refine, FarCellsRefineOnlyWithTheSwitch) {
  // A tilted box: its flat faces cut level-0 cells obliquely, leaving points of their boundary
  // more than a base cell from the face in some of them. Only features and normal spread are off.
  Mesh box = box_mesh({0, 0, 0}, {1, 1, 1});
  const double a = 0.5, b = 0.3;
  for (Vec3& p : box.points) {
    Vec3 q{std::cos(a) * p[0] - std::sin(a) * p[1], std::sin(a) * p[0] + std::cos(a) * p[1], p[2]};
    p = Vec3{q[0], std::cos(b) * q[1] - std::sin(b) * q[2], std::sin(b) * q[1] + std::cos(b) * q[2]};
  }
  WrapParams plain;
  plain.refine_normal_spread_deg = 179;
  plain.refine_at_features = false;
  auto without = refine(box, 5, 1, plain);
  WrapParams far = plain;
  far.refine_far_cells = true;
  auto with = refine(box, 5, 1, far);
  ASSERT_GE(without.refined_per_level.size(), 1u);
  EXPECT_EQ(without.refined_per_level[0], 0u);
  ASSERT_GE(with.refined_per_level.size(), 1u);
  EXPECT_GT(with.refined_per_level[0], 0u);
  EXPECT_LT(with.refined_per_level[0], with.touched_per_level[0]);  // not every touched cell
}

TEST(Refine, CurvedSurfaceRefinesByNormalSpread) {
  Mesh sphere = sphere_mesh(1.0, 32, 64);
  WrapParams strict;
  strict.refine_normal_spread_deg = 2;
  auto fine = refine(sphere, 10, 1, strict);
  WrapParams loose;
  loose.refine_normal_spread_deg = 90;
  auto coarse = refine(sphere, 10, 1, loose);
  ASSERT_EQ(fine.touched_per_level.size(), 2u);
  EXPECT_GT(fine.touched_per_level[1], 0u);
  EXPECT_TRUE(coarse.touched_per_level.size() == 1 || coarse.touched_per_level[1] < fine.touched_per_level[1]);
}

TEST(FloodFill, SealedBoxHasAnInsideAndLeakingBoxDoesNot) {
  Mesh sealed = box_mesh({0, 0, 0}, {1, 1, 1});
  auto r = refine(sealed, 5, 0);
  grid::Components comps;
  int32_t inside = grid::choose_volume(*r.grid, VolumeChoice::Inside, comps, nullptr);
  EXPECT_NE(inside, 1);
  EXPECT_EQ(comps.count(), 2u);
  EXPECT_TRUE(comps.touches_outside[0]);
  EXPECT_FALSE(comps.touches_outside[1]);

  // Remove the two triangles of the top face: a hole far wider than a cell.
  Mesh leaking = sealed;
  leaking.triangles.erase(leaking.triangles.begin() + 2, leaking.triangles.begin() + 4);
  leaking.triangle_part.resize(leaking.triangles.size());
  auto l = refine(leaking, 5, 0);
  grid::Components lc;
  EXPECT_EQ(grid::choose_volume(*l.grid, VolumeChoice::Outside, lc, nullptr), 1);
  EXPECT_EQ(lc.count(), 1u);
  try {
    grid::choose_volume(*l.grid, VolumeChoice::Inside, lc, nullptr);
    FAIL() << "a leaking box encloses nothing";
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::WrapFailed);
  }
}

TEST(FloodFill, NestedShellsGiveThreeVolumesAndInsideIsTheLargest) {
  Mesh m = box_mesh({0, 0, 0}, {4, 4, 4});
  add_box(m, {1, 1, 1}, {3, 3, 3});
  auto r = refine(m, 4, 0);
  grid::Components comps;
  int32_t inside = grid::choose_volume(*r.grid, VolumeChoice::Inside, comps, nullptr);
  ASSERT_EQ(comps.count(), 3u);
  // The inner cube (8 units^3) is smaller than the shell between the boxes (56 units^3).
  double chosen = comps.volume[inside - comps.first_label];
  for (size_t i = 0; i < comps.count(); ++i)
    if (!comps.touches_outside[i]) EXPECT_GE(chosen, comps.volume[i]);
}

namespace {

// A grid larger than a few level-0 blocks (and not a multiple of them) with hollow boxes of
// touched cells, some with a hole, random touched and refined cells between: components of
// every kind, large uniform stretches of free space, and blocks clipped by the box.
std::unique_ptr<grid::AdaptiveGrid> blocky_grid(uint32_t seed) {
  const Coord dims(29, 21, 26);
  auto g = std::make_unique<grid::AdaptiveGrid>(Vec3{0, 0, 0}, 1.0, 1, dims);
  if (seed == 0) {
    // One pocket: the uniform block 8..15 and two layers of a mixed block above it, reached
    // from the block only across its top face.
    for (int z = 7; z <= 18; ++z)
      for (int y = 7; y <= 16; ++y)
        for (int x = 7; x <= 16; ++x)
          if (x == 7 || x == 16 || y == 7 || y == 16 || z == 7 || z == 18) g->set(0, Coord(x, y, z), grid::kTouched);
    return g;
  }
  std::mt19937 rng(seed);
  std::uniform_int_distribution<int> pick(0, 1 << 20);
  for (int shell = 0; shell < 3; ++shell) {
    Coord lo, hi;
    for (int k = 0; k < 3; ++k) {
      lo[k] = 1 + pick(rng) % (dims[k] / 2);
      hi[k] = std::min(dims[k] - 2, lo[k] + 4 + pick(rng) % (dims[k] / 2));
    }
    const bool holed = shell == 2;
    for (int z = lo.z(); z <= hi.z(); ++z)
      for (int y = lo.y(); y <= hi.y(); ++y)
        for (int x = lo.x(); x <= hi.x(); ++x) {
          const bool wall = x == lo.x() || x == hi.x() || y == lo.y() || y == hi.y() || z == lo.z() || z == hi.z();
          const bool hole = holed && z == hi.z() && std::abs(x - (lo.x() + hi.x()) / 2) <= 1 &&
                            std::abs(y - (lo.y() + hi.y()) / 2) <= 1;
          if (wall && !hole) g->set(0, Coord(x, y, z), grid::kTouched);
        }
  }
  for (int n = 0; n < 60; ++n) {
    const Coord c(1 + pick(rng) % (dims.x() - 2), 1 + pick(rng) % (dims.y() - 2), 1 + pick(rng) % (dims.z() - 2));
    if (g->get(0, c) != grid::kFree) continue;  // a refined cell keeps its children
    if (n % 3) {
      g->set(0, c, grid::kTouched);
      continue;
    }
    g->set(0, c, grid::kRefined);
    for (int k = 0; k < 8; ++k)
      g->set(1, Coord(2 * c.x() + (k & 1), 2 * c.y() + ((k >> 1) & 1), 2 * c.z() + ((k >> 2) & 1)),
             pick(rng) % 3 == 0 ? grid::kTouched : grid::kFree);
  }
  return g;
}

struct LeafKey {
  int level;
  Coord c;
  bool operator<(const LeafKey& o) const { return level != o.level ? level < o.level : c < o.c; }
};

}  // namespace

// The flood fill labels uniform level-0 blocks whole (VDB tiles). Its labels, volumes and
// flags must be those of a plain walk from leaf to leaf, numbered the same way: the outside
// first, then in the order of for_each_leaf.
TEST(FloodFill, LabellingByBlocksMatchesAWalkFromLeafToLeaf) {
  for (uint32_t seed = 0; seed <= 6; ++seed) {
    SCOPED_TRACE("seed " + std::to_string(seed));
    auto g = blocky_grid(seed);
    std::vector<LeafKey> leaves;
    g->for_each_leaf([&](int level, const Coord& c, int32_t v) {
      if (v == grid::kFree) leaves.push_back({level, c});
    });
    std::map<LeafKey, int32_t> expected;
    std::vector<double> volume;
    std::vector<uint8_t> outside, level0;
    auto walk = [&](const LeafKey& start) {
      const int32_t label = int32_t(volume.size()) + 1;
      volume.push_back(0), outside.push_back(0), level0.push_back(0);
      std::vector<LeafKey> queue{start};
      expected[start] = label;
      for (size_t q = 0; q < queue.size(); ++q) {
        const LeafKey cur = queue[q];
        const double side = g->fine_units(cur.level);
        volume.back() += side * side * side;
        level0.back() |= cur.level == 0;
        for (int axis = 0; axis < 3; ++axis)
          for (int dir = -1; dir <= 1; dir += 2)
            g->for_each_face_neighbour(cur.level, cur.c, axis, dir, [&](const grid::LeafRef& n) {
              if (n.outside_box) outside.back() = 1;
              if (n.outside_box || n.value != grid::kFree) return;
              if (expected.emplace(LeafKey{n.level, n.ijk}, label).second) queue.push_back({n.level, n.ijk});
            });
      }
    };
    walk({0, Coord(0, 0, 0)});
    for (const LeafKey& k : leaves)
      if (!expected.count(k)) walk(k);
    ASSERT_GE(volume.size(), 2u) << "the configuration should enclose something";

    const size_t blocks_before = g->level_grid(0)->tree().leafCount();
    const grid::Components comps = grid::label_components(
        *g, [](int32_t v) { return v == grid::kFree; }, 1);
    ASSERT_EQ(comps.count(), volume.size());
    for (size_t i = 0; i < volume.size(); ++i) {
      EXPECT_EQ(comps.volume[i], volume[i]) << "component " << i;
      EXPECT_EQ(comps.touches_outside[i], outside[i]) << "component " << i;
      EXPECT_EQ(comps.holds_level0[i], level0[i]) << "component " << i;
    }
    size_t wrong = 0;
    for (const auto& [k, label] : expected) wrong += g->leaf_at(k.level, k.c).value != label;
    EXPECT_EQ(wrong, 0u);
    // Whole blocks went in as tiles: the labelling added no leaf nodes for them.
    EXPECT_LE(g->level_grid(0)->tree().leafCount(), blocks_before);
  }
}

// The extraction lists only the cells of uniform blocks that can have a face: it must find
// every face a cell-by-cell search finds (one quad per leaf face, or per finer neighbour).
TEST(Extract, FacesOfBlockLabelledVolumesAreAllFound) {
  for (uint32_t seed = 0; seed <= 6; ++seed) {
    SCOPED_TRACE("seed " + std::to_string(seed));
    grid::Components comps;
    for (VolumeChoice choice : {VolumeChoice::Outside, VolumeChoice::Inside}) {
      auto h = blocky_grid(seed);
      const int32_t label = grid::choose_volume(*h, choice, comps, nullptr);
      size_t faces = 0;
      h->for_each_leaf([&](int level, const Coord& c, int32_t v) {
        if (v != label) return;
        for (int axis = 0; axis < 3; ++axis)
          for (int dir = -1; dir <= 1; dir += 2)
            h->for_each_face_neighbour(level, c, axis, dir, [&](const grid::LeafRef& n) {
              const bool in = n.outside_box ? choice == VolumeChoice::Outside : n.value == label;
              faces += in ? 0 : 1;
            });
      });
      const auto surf = extract::extract_faces(*h, label, choice);
      EXPECT_GT(faces, 0u);
      EXPECT_EQ(surf.polygons.size(), faces) << (choice == VolumeChoice::Inside ? "inside" : "outside");
    }
  }
}

TEST(Extract, HandMadeEdgeAndCornerContactsBecomeManifold) {
  // Two touched cells meeting only along an edge, two meeting only at a corner, and a
  // refined cell next to coarse ones: the wrap around them must be a closed 2-manifold.
  for (VolumeChoice choice : {VolumeChoice::Outside}) {
    grid::AdaptiveGrid g({0, 0, 0}, 1.0, 1, Coord(10, 10, 10));
    g.set(0, Coord(3, 3, 3), grid::kTouched);
    g.set(0, Coord(4, 4, 3), grid::kTouched);  // edge contact
    g.set(0, Coord(5, 5, 4), grid::kTouched);  // corner contact
    g.set(0, Coord(6, 3, 3), grid::kRefined);  // level transition
    for (int k = 0; k < 8; ++k)
      g.set(1, Coord(12 + (k & 1), 6 + ((k >> 1) & 1), 6 + ((k >> 2) & 1)),
            k == 0 || k == 7 ? grid::kTouched : grid::kFree);
    grid::Components comps;
    int32_t label = grid::choose_volume(g, choice, comps, nullptr);
    extract::ExtractStats stats;
    auto surf = extract::extract_manifold_surface(g, label, choice, stats, nullptr);
    EXPECT_GT(stats.excluded_cells, 0u);
    expect_closed_manifold(surf, choice);
  }
}

// Random cells on 3 levels: touched and free level-0 cells, refined ones with touched, free
// and refined children. Each choice of volume gets its own deep copy.
std::unique_ptr<grid::AdaptiveGrid> random_cell_grid(std::mt19937& rng) {
  auto g = std::make_unique<grid::AdaptiveGrid>(Vec3{0, 0, 0}, 1.0, 2, Coord(9, 9, 9));
  std::uniform_real_distribution<double> u(0, 1);
  for (int z = 2; z < 7; ++z)
    for (int y = 2; y < 7; ++y)
      for (int x = 2; x < 7; ++x) {
        double r = u(rng);
        if (r < 0.25) {
          g->set(0, Coord(x, y, z), grid::kTouched);
        } else if (r < 0.4) {
          g->set(0, Coord(x, y, z), grid::kRefined);
          for (int k = 0; k < 8; ++k) {
            Coord c(2 * x + (k & 1), 2 * y + ((k >> 1) & 1), 2 * z + ((k >> 2) & 1));
            double s = u(rng);
            if (s < 0.15) {
              g->set(1, c, grid::kRefined);
              for (int j = 0; j < 8; ++j)
                g->set(2, Coord(2 * c.x() + (j & 1), 2 * c.y() + ((j >> 1) & 1), 2 * c.z() + ((j >> 2) & 1)),
                       u(rng) < 0.4 ? grid::kTouched : grid::kFree);
            } else {
              g->set(1, c, s < 0.5 ? grid::kTouched : grid::kFree);
            }
          }
        }
      }
  return g;
}

std::unique_ptr<grid::AdaptiveGrid> deep_copy(const grid::AdaptiveGrid& g) {
  // Each level grid is shared by a plain copy; copy the values so that choices do not interfere.
  auto h = std::make_unique<grid::AdaptiveGrid>(Vec3{0, 0, 0}, 1.0, g.max_level(), g.dims0());
  for (int l = 0; l <= g.max_level(); ++l)
    for (auto it = g.level_grid(l)->cbeginValueOn(); it; ++it) h->set(l, it.getCoord(), *it);
  return h;
}

TEST(Extract, RandomCellConfigurationsAlwaysGiveClosedManifoldSurfaces) {
  std::mt19937 rng(7);
  for (int trial = 0; trial < 40; ++trial) {
    const auto g = random_cell_grid(rng);
    for (VolumeChoice choice : {VolumeChoice::Outside, VolumeChoice::Inside}) {
      auto h = deep_copy(*g);
      grid::Components comps;
      int32_t label;
      try {
        label = grid::choose_volume(*h, choice, comps, nullptr);
      } catch (const Error&) {
        continue;  // nothing enclosed in this random configuration
      }
      extract::ExtractStats stats;
      auto surf = extract::extract_manifold_surface(*h, label, choice, stats, nullptr);
      SCOPED_TRACE("trial " + std::to_string(trial) + (choice == VolumeChoice::Inside ? " inside" : " outside"));
      expect_closed_manifold(surf, choice);
    }
  }
}

// Rounds after the first look only near the cells the last round changed; they must change
// the same cells as rounds over the whole surface, and so give the same surface.
TEST(Extract, RoundsNearTheChangesGiveTheSameSurfaceAsWholeRounds) {
  std::mt19937 rng(11);
  size_t later_rounds = 0;
  for (int trial = 0; trial < 60; ++trial) {
    const auto g = random_cell_grid(rng);
    for (VolumeChoice choice : {VolumeChoice::Outside, VolumeChoice::Inside}) {
      SCOPED_TRACE("trial " + std::to_string(trial) + (choice == VolumeChoice::Inside ? " inside" : " outside"));
      auto near = deep_copy(*g), whole = deep_copy(*g);
      grid::Components comps;
      int32_t label_near, label_whole;
      try {
        label_near = grid::choose_volume(*near, choice, comps, nullptr);
        label_whole = grid::choose_volume(*whole, choice, comps, nullptr);
      } catch (const Error&) {
        continue;
      }
      for (int min_exclude_level : {-1, 1}) {
        auto a = deep_copy(*near), b = deep_copy(*whole);
        int32_t la = label_near, lb = label_whole;
        extract::ExtractStats sa, sb;
        const auto surf_near =
            extract::extract_manifold_surface(*a, la, choice, sa, nullptr, {}, min_exclude_level, false);
        const auto surf_whole =
            extract::extract_manifold_surface(*b, lb, choice, sb, nullptr, {}, min_exclude_level, true);
        EXPECT_EQ(sa.rounds, sb.rounds);
        EXPECT_EQ(sa.excluded_cells, sb.excluded_cells);
        EXPECT_EQ(sa.dropped_pieces, sb.dropped_pieces);
        EXPECT_EQ(surf_near.nodes, surf_whole.nodes);
        EXPECT_EQ(surf_near.node_size, surf_whole.node_size);
        EXPECT_EQ(surf_near.polygons, surf_whole.polygons);
        later_rounds += sa.rounds > 2 ? 1 : 0;
      }
    }
  }
  EXPECT_GT(later_rounds, 10u);  // the configurations do need rounds near the changes
}

// The extraction's rounds take non-manifold cells out of the volume; the pieces this cuts off
// are found by searches from the cells next to the ones taken out, without labelling the
// whole volume again. A closed shell cuts off its inside; an open one cuts off nothing; a wall
// through the middle leaves two large halves, which only a full labelling may decide.
TEST(Extract, CutOffPocketsAreFoundNearTheCellsTakenOut) {
  const int32_t label = 5;
  auto volume_grid = [&] {
    auto g = std::make_unique<grid::AdaptiveGrid>(Vec3{0, 0, 0}, 1.0, 1, Coord(12, 12, 12));
    for (int z = 0; z < 12; ++z)
      for (int y = 0; y < 12; ++y)
        for (int x = 0; x < 12; ++x) g->set(0, Coord(x, y, z), label);
    return g;
  };
  auto count = [&](const grid::AdaptiveGrid& g, int32_t value) {
    size_t n = 0;
    g.for_each_leaf([&](int, const Coord&, int32_t v) { n += v == value; });
    return n;
  };
  auto take_out = [](grid::AdaptiveGrid& g, const std::vector<std::pair<int, Coord>>& cells) {
    for (const auto& [level, c] : cells) g.set(level, c, grid::kExcluded);
  };
  // The shell of the 4x4x4 block at 4..7 around the 2x2x2 block at 5..6.
  std::vector<std::pair<int, Coord>> shell;
  for (int z = 4; z < 8; ++z)
    for (int y = 4; y < 8; ++y)
      for (int x = 4; x < 8; ++x)
        if (x == 4 || x == 7 || y == 4 || y == 7 || z == 4 || z == 7) shell.emplace_back(0, Coord(x, y, z));
  {
    auto g = volume_grid();
    take_out(*g, shell);
    size_t dropped = 99;
    ASSERT_TRUE(extract::drop_cut_off_pockets(*g, label, shell, 0.25, SIZE_MAX, dropped));
    EXPECT_EQ(dropped, 1u);
    EXPECT_EQ(g->get(0, Coord(5, 5, 5)), grid::kExcluded);
    EXPECT_EQ(g->get(0, Coord(6, 6, 6)), grid::kExcluded);
    EXPECT_EQ(count(*g, label), 1728u - 64u);
  }
  {
    auto open = shell;
    open.erase(std::find(open.begin(), open.end(), std::pair<int, Coord>(0, Coord(5, 5, 4))));
    auto g = volume_grid();
    take_out(*g, open);
    size_t dropped = 99;
    ASSERT_TRUE(extract::drop_cut_off_pockets(*g, label, open, 0.25, SIZE_MAX, dropped));
    EXPECT_EQ(dropped, 0u);
    EXPECT_EQ(g->get(0, Coord(5, 5, 5)), label);
    EXPECT_EQ(count(*g, label), 1728u - 55u);
  }
  {
    std::vector<std::pair<int, Coord>> wall;
    for (int z = 0; z < 12; ++z)
      for (int y = 0; y < 12; ++y) wall.emplace_back(0, Coord(6, y, z));
    auto g = volume_grid();
    take_out(*g, wall);
    size_t dropped = 99;
    EXPECT_FALSE(extract::drop_cut_off_pockets(*g, label, wall, 0.25, SIZE_MAX, dropped));
    EXPECT_EQ(count(*g, label), 1728u - 144u) << "nothing may change when the searches cannot tell";
  }
  {
    // The shell again, with room for fewer cells than the searches need: a labelling decides.
    auto g = volume_grid();
    take_out(*g, shell);
    size_t dropped = 99;
    EXPECT_FALSE(extract::drop_cut_off_pockets(*g, label, shell, 0.25, 8, dropped));
    EXPECT_EQ(g->get(0, Coord(5, 5, 5)), label) << "nothing may change past the total budget";
    EXPECT_EQ(count(*g, label), 1728u - 56u);
  }
}
