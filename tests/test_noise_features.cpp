// Sharp edges that are a rough surface's noise (mesh/short_feature_runs.h): runs shorter than the
// wrap can follow are dropped before the feature curves are built; creases stay.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <random>

#include "check/distance_stats.h"
#include "common/vec.h"
#include "fit/features.h"
#include "mesh/fold_crossings.h"
#include "mesh/rough_edges.h"
#include "mesh/short_feature_runs.h"
#include "pipeline/stage_params.h"
#include "pipeline/stages.h"
#include "pipeline/wrap_run.h"
#include "prep/prepare.h"
#include "test_meshes.h"
#include "vdbwrap/check.h"
#include "vdbwrap/io.h"
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

// The wrap at `percent` of the diagonal, checked valid.
WrapResult valid_wrap(const Mesh& m, double percent) {
  WrapParams p;
  p.base_size = Length{percent, true};
  WrapResult r = wrap(m, p);
  auto v = valid_closed_surface(r.surface);
  EXPECT_TRUE(v.ok) << v.why;
  return r;
}
WrapResult valid_wrap_at_2_percent(const Mesh& m) { return valid_wrap(m, 2); }

}  // namespace

// Ten rows of four sharp edges 0.2 long, 0.05 apart, straight or zigzagging by 90 degrees:
// eight cell lengths of sharp edges in one cell 1 wide (runs under 0.5 may be noise).
std::vector<mesh::FeatureEdge> rows(std::vector<Vec3>& points, bool zigzag) {
  std::vector<mesh::FeatureEdge> edges;
  for (int row = 0; row < 10; ++row) {
    const uint32_t first = uint32_t(points.size());
    for (int i = 0; i <= 4; ++i)
      points.push_back(zigzag ? Vec3{0.1 + 0.1414 * i, 0.02 + 0.05 * row + (i % 2 ? 0.1414 : 0.0), 0.5}
                              : Vec3{0.1 + 0.2 * i, 0.02 + 0.05 * row, 0.5});
    for (uint32_t i = 0; i < 4; ++i) edges.push_back({first + i, first + i + 1, mesh::FeatureKind::Sharp});
  }
  return edges;
}

TEST(NoiseFeatures, ShortRunsGoWhereTheyAreManyAndEndAtSharpTurns) {
  std::vector<Vec3> straight_points, zigzag_points;
  std::vector<mesh::FeatureEdge> straight = rows(straight_points, false), zigzag = rows(zigzag_points, true);
  straight.push_back({0, 4, mesh::FeatureKind::Boundary});  // not sharp: never dropped, never counted
  // Straight on, each row is one run 0.8 long: kept.
  EXPECT_EQ(mesh::drop_short_sharp_runs(straight_points, straight, 0.5, 30), 0u);
  EXPECT_EQ(straight.size(), 41u);
  // Zigzagging, each edge is a run of its own (the turns are corners): all 40 go.
  EXPECT_EQ(mesh::drop_short_sharp_runs(zigzag_points, zigzag, 0.5, 30), 40u);
  EXPECT_TRUE(zigzag.empty());
  // One zigzag row alone (1.1 cell lengths in its cell): a small part's edges, kept.
  std::vector<Vec3> one_points;
  std::vector<mesh::FeatureEdge> one = rows(one_points, true);
  one.resize(4);
  EXPECT_EQ(mesh::drop_short_sharp_runs(one_points, one, 0.5, 30), 0u);
}

TEST(NoiseFeatures, ACreaseRunsOnPastTheNoiseEdgesThatMeetIt) {
  // The straight rows again, each with a spur 0.1 long across it at its three inner vertices
  // (a rough scan's sharp edges meeting a crease; 3 cell lengths of them): the rows stay
  // whole, the spurs go.
  std::vector<Vec3> points;
  std::vector<mesh::FeatureEdge> edges = rows(points, false);
  const size_t row_edges = edges.size();
  for (uint32_t row = 0; row < 10; ++row)
    for (uint32_t i = 1; i <= 3; ++i) {
      const uint32_t at = 5 * row + i;
      points.push_back(points[at] + Vec3{0, 0, 0.1});
      edges.push_back({at, uint32_t(points.size() - 1), mesh::FeatureKind::Sharp});
    }
  EXPECT_EQ(mesh::drop_short_sharp_runs(points, edges, 0.5, 30), 30u);
  EXPECT_EQ(edges.size(), row_edges);
  for (const auto& e : edges) EXPECT_EQ(points[e.a][2], points[e.b][2]);  // the rows' own edges
}

TEST(NoiseFeatures, ASmallBoxKeepsItsEdges) {
  // Edges 1, 2 and 3 long against runs of 1.5: short, but 24 cell lengths over 8 cells.
  const prep::PreparedInput box = prep::prepare(box_mesh({0, 0, 0}, {1, 2, 3}), prep::PrepareParams{}, nullptr);
  ASSERT_EQ(sharp(box.feature_edges), 12u);  // the faces' diagonals are flat
  std::vector<mesh::FeatureEdge> edges = box.feature_edges;
  EXPECT_EQ(mesh::drop_short_sharp_runs(box.mesh.points, edges, 1.5, 30), 0u);
  EXPECT_EQ(edges.size(), box.feature_edges.size());
}

// A rough sphere of 82k triangles at 2 % (its edges a quarter of a base cell, as a scan's are
// at 1 %) has thousands of sharp edges, none of them a crease. Traced, they were thousands of
// feature curves (a 327k-triangle one at 1 %: 216k curves, 41 s against alpha wrap's 5 s,
// 330k triangles out). Most are dropped, and the wrap is valid and near.
TEST(NoiseFeatures, ARoughSphereIsNotTracedAsThousandsOfCreases) {
  const Mesh rough = rough_sphere(6, 0.006, 7);
  prep::PreparedInput in = prep::prepare(rough, prep::PrepareParams{}, nullptr);
  const double base = 0.02 * in.diagonal;
  const size_t curves_before = fit::build_feature_curves(in, 30).size();
  const size_t sharp_before = sharp(in.feature_edges);
  const size_t dropped =
      mesh::drop_short_sharp_runs(in.mesh.points, in.feature_edges, pipeline::kShortestSharpRun * base, 30);
  const size_t curves_after = fit::build_feature_curves(in, 30).size();
  std::printf("[rough sphere] sharp edges %zu, dropped %zu; curves %zu -> %zu\n", sharp_before, dropped, curves_before,
              curves_after);
  EXPECT_GT(dropped, sharp_before / 2);
  EXPECT_LT(curves_after, curves_before / 4);

  const WrapResult r = valid_wrap(rough, 2);
  // At 2 % the runs leave few edges; the cell-scale test (below) may take some of those.
  EXPECT_GE(r.report.features.noise_sharp_edges, dropped);
  EXPECT_LE(r.report.features.curves, curves_after);
  // Nearer on average than the roughness itself (its standard deviation, 0.006).
  EXPECT_LT(r.report.output_to_input.mean, 0.006);
  EXPECT_LT(r.report.output_to_input.max, r.report.base_size);
}

// Self-intersection lines as segments by their ends (mesh::short_line_runs): the rows again.
TEST(NoiseFeatures, ShortIntersectionRunsGoWhereTheyAreManyAndLongOnesStay) {
  auto ends_of = [](bool zigzag) {
    std::vector<Vec3> points, ends;
    for (const auto& e : rows(points, zigzag)) ends.push_back(points[e.a]), ends.push_back(points[e.b]);
    return ends;
  };
  auto noise = [](const std::vector<uint8_t>& flags) { return size_t(std::count(flags.begin(), flags.end(), 1)); };
  // Straight rows: one line 0.8 long each, kept; zigzagging: 40 short runs in a cell, all go.
  EXPECT_EQ(noise(mesh::short_line_runs(ends_of(false), 0.5, 30, 1e-9)), 0u);
  EXPECT_EQ(noise(mesh::short_line_runs(ends_of(true), 0.5, 30, 1e-9)), 40u);
  // The ends of one line's pieces met up to rounding: still one run.
  std::vector<Vec3> rounded = ends_of(false);
  for (size_t i = 1; i < rounded.size(); i += 2) rounded[i] = rounded[i] + Vec3{1e-12, 0, 0};
  EXPECT_EQ(noise(mesh::short_line_runs(rounded, 0.5, 30, 1e-10)), 0u);
  // One zigzag row alone: a small part crossing another, kept.
  std::vector<Vec3> one = ends_of(true);
  one.resize(8);
  EXPECT_EQ(noise(mesh::short_line_runs(one, 0.5, 30, 1e-9)), 0u);
}

// An unmerged scan: two rough shells of one sphere, each a little off the other (registration
// error), cross along a labyrinth of short lines where their noise puts one above the other;
// the crossings steep enough to count meander in runs a few triangles long. Traced, they were
// thousands of feature curves (a 2.3M-triangle scan of three views at 1 %: 276k curves, 107 s
// against alpha wrap's 58 s). They go; the wrap is valid and near.
TEST(NoiseFeatures, RoughShellsCrossingAreNotTracedAlongTheirIntersections) {
  Mesh views = rough_sphere(6, 0.006, 11);
  const Mesh other = rough_sphere(6, 0.006, 12);
  const uint32_t offset = uint32_t(views.points.size());
  for (const Vec3& p : other.points) views.points.push_back(p + Vec3{0.002, -0.001, 0.001});
  for (const Tri& t : other.triangles) views.triangles.push_back({t[0] + offset, t[1] + offset, t[2] + offset});
  const prep::PreparedInput in = prep::prepare(views, prep::PrepareParams{}, nullptr);
  ASSERT_GT(in.intersections.size(), 1000u);
  const WrapResult r = valid_wrap_at_2_percent(views);
  const auto& f = r.report.features;
  std::printf("[rough shells] intersection segments %zu, dropped %zu; curves %zu\n", f.intersection_segments,
              f.noise_intersection_segments, f.curves);
  EXPECT_EQ(f.intersection_segments, in.intersections.size());
  EXPECT_GT(f.noise_intersection_segments, f.intersection_segments * 3 / 4);
  EXPECT_LT(r.report.output_to_input.mean, 0.006);
  EXPECT_LT(r.report.output_to_input.max, r.report.base_size);
}

// Parts that cross meet along long lines, and a thin pin through a plate along a short one
// alone: none of them is noise, and the wrap keeps the creases there.
TEST(NoiseFeatures, PartsThatCrossKeepTheirIntersectionLines) {
  Mesh m = box_mesh({0, 0, 0}, {4, 4, 0.5});
  add_box(m, {1, 1, -1}, {3, 3, 1.5});           // a block through the plate: lines 8 long
  add_cylinder(m, {3.5, 3.5, -1}, 0.05, 3, 12);  // a pin through it: a loop 0.3 long
  const prep::PreparedInput in = prep::prepare(m, prep::PrepareParams{}, nullptr);
  ASSERT_GT(in.intersections.size(), 12u);
  const WrapResult r = valid_wrap_at_2_percent(m);
  EXPECT_EQ(r.report.features.noise_intersection_segments, 0u);
  // The block's crease with the plate is in the wrap (the pin is thinner than a cell).
  std::vector<Vec3> on_block;
  for (const auto& s : in.intersections)
    if (s.a[0] + in.origin[0] < 3.2) on_block.push_back(s.a + in.origin), on_block.push_back(s.b + in.origin);
  ASSERT_GT(on_block.size(), 8u);
  const DistanceStats d = check::distances_to(on_block, r.surface, r.report.diagonal);
  EXPECT_LT(d.max, 0.05 * r.report.base_size);
}

// The same sphere at 1 %: its triangles are half a base cell, and its noise edges line up into
// runs longer than a cell along the straight lines of its regular tessellation, which the
// short-run test keeps (16.8k curves). Seen over a base cell on either hand the surface is
// smooth there: those edges go too, and the wrap is near and valid.
TEST(NoiseFeatures, ARoughSurfaceIsSmoothAtTheCellScale) {
  const Mesh rough = rough_sphere(6, 0.006, 7);
  prep::PreparedInput in = prep::prepare(rough, prep::PrepareParams{}, nullptr);
  const double base = 0.01 * in.diagonal;
  const mesh::Roughness marks = mesh::roughness(in.mesh.points.size(), in.mesh.triangles, in.feature_edges);
  const size_t runs =
      mesh::drop_short_sharp_runs(in.mesh.points, in.feature_edges, pipeline::kShortestSharpRun * base, 30);
  const size_t left = sharp(in.feature_edges);
  const size_t curves_before = fit::build_feature_curves(in, 30).size();
  const size_t smooth =
      mesh::drop_edges_smooth_at_scale(in.mesh.points, in.mesh.triangles, in.feature_edges, marks, base, 30);
  const size_t curves_after = fit::build_feature_curves(in, 30).size();
  std::printf(
      "[rough sphere at 1 %%] sharp edges left by the runs %zu, smooth at the cell scale %zu; curves %zu -> %zu\n",
      left, smooth, curves_before, curves_after);
  EXPECT_GT(smooth, left * 3 / 4);
  EXPECT_LT(curves_after, curves_before / 4);

  const WrapResult r = valid_wrap(rough, 1);
  EXPECT_EQ(r.report.features.noise_sharp_edges, runs + smooth);
  EXPECT_EQ(r.report.features.curves, curves_after);
  EXPECT_LT(r.report.output_to_input.mean, 0.006);
  EXPECT_LT(r.report.output_to_input.max, r.report.base_size);
}

// Real parts' creases are no noise at the cell scale, finely tessellated or not: CAD models of
// the corpus at 1 %, their edges dropped as the wrap drops them (short runs first), keep every
// sharp edge the runs leave. Without the roughness and face-count tests thingi_99865 lost
// 1,265 (the creases of small pyramids whose flat faces are finely tessellated: six or seven
// faces within a cell, their normals a little under 30 degrees apart when averaged).
// octagonal_pocket and box.STL are not here: one edge between coplanar faces of the one, the
// other's seams (walls 0.002 apart against a base cell of 0.11) go, as noise does.
TEST(NoiseFeatures, CreasesOfRealPartsAreSharpAtTheCellScale) {
  for (const char* name : {"fandisk.obj", "featuretype.STL", "angle_block.STL", "idler_riser.STL", "plate_holes.STL",
                           "1002_tray_bottom.STL", "busted.STL", "fuze.obj", "thingi_99865.stl"}) {
    prep::PreparedInput in = prep::prepare(io::read_mesh(data_path(name)), prep::PrepareParams{}, nullptr);
    const double base = 0.01 * in.diagonal;
    const mesh::Roughness marks = mesh::roughness(in.mesh.points.size(), in.mesh.triangles, in.feature_edges);
    mesh::drop_short_sharp_runs(in.mesh.points, in.feature_edges, pipeline::kShortestSharpRun * base, 30);
    const size_t left = sharp(in.feature_edges);
    ASSERT_GT(left, 0u) << name;
    EXPECT_EQ(mesh::drop_edges_smooth_at_scale(in.mesh.points, in.mesh.triangles, in.feature_edges, marks, base, 30),
              0u)
        << name << " (" << left << " sharp edges)";
  }
}

// A rough closed scan whose noise is as coarse as its faces (82k triangles, each coordinate
// off by up to 4 %: faces half a base cell at 1 %, folded over every way and crossing the
// faces around them). Its folds ran every way, many longer than a cell, and its crossings
// were thousands of short lines too sparse to count as dense: 66k feature curves, 103k nodes
// inserted, 155 s against alpha wrap's 3.3 s (bench/results/2026-11-27-coarse-noise.md). Such
// a surface is cut up by noise: its sharp edges go, long or short, and so do the crossings of
// faces within two rings of each other.
TEST(NoiseFeatures, NoiseAsCoarseAsTheFacesIsNoCrease) {
  const Mesh rough = jittered_icosphere(6, 0.04);
  prep::PreparedInput in = prep::prepare(rough, prep::PrepareParams{}, nullptr);
  const double base = 0.01 * in.diagonal;
  const mesh::Roughness marks = mesh::roughness(in.mesh.points.size(), in.mesh.triangles, in.feature_edges);
  mesh::drop_short_sharp_runs(in.mesh.points, in.feature_edges, pipeline::kShortestSharpRun * base, 30);
  auto longer_than_a_cell = [&] {
    size_t n = 0;
    for (const auto& e : in.feature_edges)
      n += e.kind == mesh::FeatureKind::Sharp && norm(in.mesh.points[e.b] - in.mesh.points[e.a]) > base;
    return n;
  };
  const size_t left = sharp(in.feature_edges), long_left = longer_than_a_cell();
  const size_t dropped =
      mesh::drop_edges_smooth_at_scale(in.mesh.points, in.mesh.triangles, in.feature_edges, marks, base, 30);
  std::printf("[coarse noise] sharp edges left by the runs %zu (%zu longer than a cell), dropped %zu, long left %zu\n",
              left, long_left, dropped, longer_than_a_cell());
  EXPECT_GT(dropped, left * 85 / 100);
  EXPECT_LT(longer_than_a_cell(), long_left / 10);

  // Its crossings are folds: the faces that cross lie within two rings of each other.
  std::vector<std::pair<uint32_t, uint32_t>> pairs;
  for (const auto& s : in.intersections) pairs.emplace_back(s.tri_a, s.tri_b);
  ASSERT_GT(pairs.size(), 1000u);
  const std::vector<uint8_t> fold = mesh::fold_crossings(in.mesh.points.size(), in.mesh.triangles, pairs);
  EXPECT_GT(size_t(std::count(fold.begin(), fold.end(), 1)), pairs.size() * 95 / 100);

  const WrapResult r = valid_wrap(rough, 1);
  std::printf(
      "[coarse noise at 1 %%] sharp edges %zu, curves %zu, crossings %zu of which noise %zu; mean %.5f max %.5f\n",
      r.report.features.sharp_edges, r.report.features.curves, r.report.features.intersection_segments,
      r.report.features.noise_intersection_segments, r.report.output_to_input.mean, r.report.output_to_input.max);
  EXPECT_LT(r.report.features.curves, r.report.features.sharp_edges / 10);
  EXPECT_GT(r.report.features.noise_intersection_segments, r.report.features.intersection_segments * 95 / 100);
  EXPECT_LT(r.report.output_to_input.max, r.report.base_size);
}

// Two such spheres overlapping (an unmerged union of two rough scans): the faces of the one
// crossing the other's are far apart on the surface, and their crossing is no fold.
TEST(NoiseFeatures, RoughPartsThatCrossAreNoFold) {
  Mesh m = jittered_icosphere(5, 0.04, 1);
  const uint32_t first = uint32_t(m.triangles.size());
  const Mesh other = jittered_icosphere(5, 0.04, 2, {1.2, 0, 0});
  const uint32_t offset = uint32_t(m.points.size());
  m.points.insert(m.points.end(), other.points.begin(), other.points.end());
  for (const Tri& t : other.triangles) m.triangles.push_back({t[0] + offset, t[1] + offset, t[2] + offset});
  const prep::PreparedInput in = prep::prepare(m, prep::PrepareParams{}, nullptr);
  // Which sphere each prepared triangle came from.
  std::vector<uint8_t> second(in.mesh.triangles.size(), 0);
  for (size_t t = 0; t < in.input_to_mesh.size(); ++t)
    if (in.input_to_mesh[t] != UINT32_MAX) second[in.input_to_mesh[t]] = t >= first;
  std::vector<std::pair<uint32_t, uint32_t>> pairs;
  for (const auto& s : in.intersections) pairs.emplace_back(s.tri_a, s.tri_b);
  const std::vector<uint8_t> fold = mesh::fold_crossings(in.mesh.points.size(), in.mesh.triangles, pairs);
  size_t between = 0, within = 0, folds_within = 0;
  for (size_t i = 0; i < pairs.size(); ++i) {
    if (second[pairs[i].first] != second[pairs[i].second]) {
      ++between;
      EXPECT_FALSE(fold[i]);
    } else {
      ++within, folds_within += fold[i];
    }
  }
  std::printf("[two rough spheres] crossings between them %zu, within one %zu (folds %zu)\n", between, within,
              folds_within);
  EXPECT_GT(between, 50u);  // the circle where they cross, 5 units round, faces 0.04 across
  EXPECT_GT(folds_within, within * 9 / 10);
}

// A crease amid noise as coarse as the faces (a rough scan of a machined part) has a smooth
// side on each hand at the cell scale: it stays. A unit cube with every face a 20 x 20 grid,
// its faces all taken for noise (every corner on a sharp edge, every face sharp all round):
// the cube's edges, 90 degrees between flat sides, are kept; with the sides' smoothness not
// asked, all 240 went.
TEST(NoiseFeatures, ACreaseWithSmoothSidesStaysAmidNoise) {
  Mesh cube;
  const int n = 20;
  auto add_face = [&](const Vec3& o, const Vec3& u, const Vec3& v) {
    const uint32_t first = uint32_t(cube.points.size());
    for (int j = 0; j <= n; ++j)
      for (int i = 0; i <= n; ++i) cube.points.push_back(o + u * (double(i) / n) + v * (double(j) / n));
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i) {
        const uint32_t a = first + j * (n + 1) + i, b = a + 1, c = a + n + 1, d = c + 1;
        cube.triangles.push_back({a, b, d});
        cube.triangles.push_back({a, d, c});
      }
  };
  add_face({0, 0, 0}, {0, 1, 0}, {1, 0, 0});  // z = 0, facing down
  add_face({0, 0, 1}, {1, 0, 0}, {0, 1, 0});  // z = 1, facing up
  add_face({0, 0, 0}, {1, 0, 0}, {0, 0, 1});  // y = 0
  add_face({0, 1, 0}, {0, 0, 1}, {1, 0, 0});  // y = 1
  add_face({0, 0, 0}, {0, 0, 1}, {0, 1, 0});  // x = 0
  add_face({1, 0, 0}, {0, 1, 0}, {0, 0, 1});  // x = 1
  prep::PreparedInput in = prep::prepare(cube, prep::PrepareParams{}, nullptr);
  ASSERT_EQ(sharp(in.feature_edges), size_t(12 * n));
  mesh::Roughness noise = mesh::roughness(in.mesh.points.size(), in.mesh.triangles, in.feature_edges);
  std::fill(noise.on_sharp.begin(), noise.on_sharp.end(), 1);
  std::fill(noise.sharp_all_round.begin(), noise.sharp_all_round.end(), 1);
  EXPECT_EQ(mesh::drop_edges_smooth_at_scale(in.mesh.points, in.mesh.triangles, in.feature_edges, noise, 0.12, 30), 0u);
  EXPECT_EQ(sharp(in.feature_edges), size_t(12 * n));
}

namespace {

// An open card, nu x nv quads over the rectangle from c spanning u and v (full lengths).
void add_card(Mesh& m, const Vec3& c, const Vec3& u, const Vec3& v, int nu, int nv) {
  const uint32_t first = uint32_t(m.points.size());
  for (int j = 0; j <= nv; ++j)
    for (int i = 0; i <= nu; ++i) m.points.push_back(c + u * (double(i) / nu - 0.5) + v * (double(j) / nv - 0.5));
  auto at = [&](int i, int j) { return first + uint32_t(j * (nu + 1) + i); };
  for (int j = 0; j < nv; ++j)
    for (int i = 0; i < nu; ++i) {
      m.triangles.push_back({at(i, j), at(i + 1, j), at(i + 1, j + 1)});
      m.triangles.push_back({at(i, j), at(i + 1, j + 1), at(i, j + 1)});
    }
}

Vec3 random_direction(std::mt19937& rng) {
  std::normal_distribution<double> g(0.0, 1.0);
  const Vec3 d{g(rng), g(rng), g(rng)};
  return d * (1.0 / norm(d));
}

}  // namespace

// Leaves or hair cards in a clump: open sheets a few base cells long and one or two wide,
// crossing each other in runs about as short as they are wide, many to a cell. Traced, those
// crossings were most of the feature curves of a plant with 2,000 leaves (4.8x alpha wrap's time,
// the wrap 10 % nearer with them than without any curve). They go (prepare's stage, at 2 %:
// cards 4 x 1.4 base cells); two wide sheets crossing keep their long line, and the wrap follows it.
TEST(NoiseFeatures, OpenSheetsCrossingInAClumpAreNoCreases) {
  Mesh clump;
  std::mt19937 rng(35);
  std::uniform_real_distribution<double> in(-1, 1), size(0.8, 1.2);
  for (int k = 0; k < 2500; ++k) {
    Vec3 c{in(rng), in(rng), in(rng)};
    const Vec3 d = random_direction(rng);
    Vec3 across = cross(d, random_direction(rng));
    across = across * (1.0 / norm(across));
    add_card(clump, c, d * (0.3 * size(rng)), across * (0.1 * size(rng)), 2, 1);
  }
  WrapParams params;
  params.base_size = Length{2, true};
  pipeline::WrapRun run(clump, params, nullptr);
  pipeline::diagnose_input(run);
  pipeline::prepare_input(run);
  const auto& f = run.report.features;
  std::printf("[card clump] intersection segments %zu, dropped %zu\n", f.intersection_segments,
              f.noise_intersection_segments);
  ASSERT_GT(f.intersection_segments, 5000u);
  EXPECT_GT(f.noise_intersection_segments, f.intersection_segments * 4 / 5);
  // (the cards' rims lie within a finest cell of one another's: some crossings go along those gaps)
  EXPECT_EQ(run.prepared.intersections.size(),
            f.intersection_segments - f.noise_intersection_segments - f.crack_intersection_segments);

  Mesh two;
  add_card(two, {0, 0, 0}, {2, 0, 0}, {0, 2, 0}, 40, 40);
  add_card(two, {0, 0, 0}, {2, 0, 0}, {0, 0, 2}, 40, 39);  // no vertex on the other
  const WrapResult x = valid_wrap_at_2_percent(two);
  EXPECT_GT(x.report.features.intersection_segments, 30u);
  EXPECT_EQ(x.report.features.noise_intersection_segments, 0u);
  std::vector<Vec3> line;
  for (int i = -18; i <= 18; ++i) line.push_back({0.05 * i, 0, 0});
  const DistanceStats d = check::distances_to(line, x.surface, x.report.diagonal);
  EXPECT_LT(d.max, 0.05 * x.report.base_size);
}
