// Stage 1: weld, degenerate removal, orientation, feature edges.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <random>

#include "check/intersections.h"
#include "common/exact_weld.h"
#include "common/sorted_point_grid.h"
#include "common/vec.h"
#include "mesh/orient.h"
#include "mesh/weld.h"
#include "prep/prepare.h"
#include "test_meshes.h"
#include "pipeline/stage_params.h"

using namespace vdbwrap;
using namespace vdbwrap::testing;

TEST(Weld, MergesPointsWithinToleranceOnly) {
  std::vector<Vec3> pts = {{0, 0, 0}, {1e-9, 0, 0}, {1, 0, 0}, {1 + 2e-3, 0, 0}, {0, 0, 1e-9}};
  std::vector<Vec3> welded;
  auto remap = mesh::weld_points(pts, 1e-6, welded);
  EXPECT_EQ(welded.size(), 3u);
  EXPECT_EQ(remap[0], remap[1]);
  EXPECT_EQ(remap[0], remap[4]);
  EXPECT_NE(remap[2], remap[3]);
}

// Thousands of points, most with exact copies, some in clusters within the tolerance (and
// straddling the welding grid's cells), -0 beside +0: every point goes to a weld within the
// tolerance, exact copies to the same one, no two welds within the tolerance of each other,
// and welds numbered in the order their first point comes.
TEST(Weld, CopiesAndClustersWeldLikeTheOrderedGreedyPass) {
  const double tol = 1e-3;
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(-1, 1), jitter(-0.4 * tol, 0.4 * tol);
  std::vector<Vec3> pts;
  for (int i = 0; i < 3000; ++i) {
    Vec3 p{u(rng), u(rng), u(rng)};
    if (i % 7 == 0) p = {std::round(p[0] * 100) / 100 * 1024 * tol / 10.24, p[1], p[2]};  // on cell boundaries
    pts.push_back(p);
    if (i % 2 == 0) pts.push_back(p);                                                // an exact copy
    if (i % 5 == 0) pts.push_back(p + Vec3{jitter(rng), jitter(rng), jitter(rng)});  // a near one
    if (i % 11 == 0) pts.push_back(p + Vec3{0.9 * tol, 0, 0}), pts.push_back(p + Vec3{1.8 * tol, 0, 0});  // a chain
  }
  pts.push_back({0.0, 0.5, 0.5});
  pts.push_back({-0.0, 0.5, 0.5});
  std::shuffle(pts.begin(), pts.end(), rng);
  std::vector<Vec3> welded;
  const auto remap = mesh::weld_points(pts, tol, welded);
  ASSERT_EQ(remap.size(), pts.size());
  uint32_t next = 0;
  for (size_t i = 0; i < pts.size(); ++i) {
    ASSERT_LT(remap[i], welded.size());
    EXPECT_LE(norm(welded[remap[i]] - pts[i]), tol) << "point " << i;
    EXPECT_LE(remap[i], next) << "welds are numbered in order of first use";
    if (remap[i] == next) ++next;
  }
  EXPECT_EQ(next, welded.size());
  for (size_t i = 0; i < pts.size(); ++i)
    for (size_t j = i + 1; j < pts.size(); ++j)
      if (pts[i] == pts[j]) EXPECT_EQ(remap[i], remap[j]) << i << " " << j;
  size_t close = 0;
  for (size_t a = 0; a < welded.size(); ++a)
    for (size_t b = a + 1; b < welded.size(); ++b) close += norm(welded[a] - welded[b]) <= tol;
  EXPECT_EQ(close, 0u);
  // At least one weld per random point (with this seed no two lie within the tolerance), at
  // most three per chain.
  EXPECT_GE(welded.size(), 3001u);
  EXPECT_LE(welded.size(), 3001u + 2 * (3000 / 11 + 1));
}

// Enough points for the exact weld's matching to be cut into many slices, copies spread far
// apart in the input, +0 beside -0: the same numbering as a map filled point by point.
// The sorted point grid's "any point this close?" against every pair measured directly:
// clusters of points a little closer and a little farther apart than the distance asked,
// some straddling cell boundaries (cells of 1, points near integer coordinates), and negative
// coordinates.
TEST(SortedPointGrid, FindsEveryPointWithinTheDistance) {
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(-3.0, 3.0), jitter(-0.002, 0.002);
  std::vector<Vec3> points;
  for (int k = 0; k < 400; ++k) {
    const Vec3 centre{std::round(u(rng)) + jitter(rng), std::round(u(rng)) + jitter(rng), u(rng)};
    points.push_back(centre);
    if (k % 3 == 0) points.push_back(centre + Vec3{jitter(rng), jitter(rng), jitter(rng)});
  }
  const double within = 0.002;
  const SortedPointGrid grid(points, 1.0);
  size_t crowded = 0;
  for (uint32_t i = 0; i < points.size(); ++i) {
    bool expected = false;
    for (uint32_t j = 0; j < points.size(); ++j) expected |= j != i && norm(points[j] - points[i]) <= within;
    const bool found =
        grid.any_near(points[i], within, [&](uint32_t j) { return j != i && norm(points[j] - points[i]) <= within; });
    EXPECT_EQ(found, expected) << "point " << i;
    crowded += found ? 1 : 0;
  }
  EXPECT_GT(crowded, 20u);
  EXPECT_LT(crowded, points.size() / 2);
}

TEST(ExactWeld, ManySlicesNumberPointsLikeAMapFilledInOrder) {
  std::mt19937 rng(5);
  std::uniform_int_distribution<int> grid(-40, 40);
  std::vector<Vec3> pts;
  for (int i = 0; i < 400000; ++i) {
    Vec3 p{grid(rng) * 0.25, grid(rng) * 0.25, grid(rng) * 0.25};  // about 530k cells: many copies
    if (i % 97 == 0) p[0] = p[0] == 0 ? -0.0 : p[0];
    pts.push_back(p);
  }
  std::vector<Vec3> unique;
  const std::vector<uint32_t> remap = exact_weld(pts, unique);
  std::map<std::array<double, 3>, uint32_t> first;  // +0 and -0 compare equal here too
  std::vector<Vec3> expected;
  ASSERT_EQ(remap.size(), pts.size());
  for (size_t i = 0; i < pts.size(); ++i) {
    auto [it, added] = first.emplace(pts[i], uint32_t(expected.size()));
    if (added) expected.push_back(pts[i]);
    ASSERT_EQ(remap[i], it->second) << "point " << i;
  }
  EXPECT_EQ(unique, expected);
  EXPECT_GT(pts.size(), 4 * unique.size() / 3);  // the copies were there to find
}

TEST(Orient, FlippedTrianglesOfAClosedBoxComeOutConsistentAndOutward) {
  Mesh m = box_mesh({0, 0, 0}, {1, 2, 3});
  std::swap(m.triangles[3][1], m.triangles[3][2]);
  std::swap(m.triangles[7][1], m.triangles[7][2]);
  ASSERT_FALSE(diagnose(m, false).oriented);
  mesh::orient_pieces(m.points, m.triangles);
  MeshDiagnostics d = diagnose(m, false);
  EXPECT_TRUE(d.oriented);
  EXPECT_TRUE(d.outward);
}

TEST(Orient, AnInsideOutBoxIsTurnedOver) {
  Mesh m = box_mesh({0, 0, 0}, {1, 1, 1});
  for (auto& t : m.triangles) std::swap(t[1], t[2]);
  ASSERT_LT(diagnose(m, false).volume, 0);
  EXPECT_EQ(mesh::orient_pieces(m.points, m.triangles), 12u);
  EXPECT_GT(diagnose(m, false).volume, 0);
}

// Two rods touching along a whole edge, as an unmerged export welds them: the edge has four
// triangles. Each rod is still a closed solid (its own two triangles there pair around the
// edge), so its material side is known; a rod turned inside out pairs nothing there.
TEST(Orient, SolidsWeldedAlongAnEdgeStayClosedPieces) {
  Mesh m;
  add_box(m, {0, 0, 0}, {1, 1, 10});
  add_box(m, {1, 1, 0}, {2, 2, 10});
  auto prepared_closed = [](const Mesh& mesh) {
    return prep::prepare(mesh, prep::PrepareParams{}, nullptr).closed_piece;
  };
  const std::vector<uint32_t> closed = prepared_closed(m);
  ASSERT_EQ(closed.size(), 24u);
  EXPECT_EQ(std::count(closed.begin(), closed.end(), 0u), 12);
  EXPECT_EQ(std::count(closed.begin(), closed.end(), 1u), 12);
  // Outward as given: nothing flipped.
  Mesh same = m;
  prep::PreparedInput in = prep::prepare(same, prep::PrepareParams{}, nullptr);
  EXPECT_EQ(in.flipped_triangles, 0u);
  // The second rod inside out: the four triangles do not bound two wedges of solid.
  Mesh turned = m;
  for (size_t t = 12; t < 24; ++t) std::swap(turned.triangles[t][1], turned.triangles[t][2]);
  const std::vector<uint32_t> open = prepared_closed(turned);
  EXPECT_EQ(std::count(open.begin(), open.end(), mesh::kOpenPiece), 24);
}

TEST(Features, BoxHasTwelveSharpEdgesAndAnOpenSquareFourBoundaryEdges) {
  Mesh box = box_mesh({0, 0, 0}, {1, 1, 1});
  std::vector<Vec3> normals;
  auto prepared = prep::prepare(box, prep::PrepareParams{}, nullptr);
  size_t sharp = 0;
  for (const auto& f : prepared.feature_edges) sharp += f.kind == prep::FeatureKind::Sharp;
  EXPECT_EQ(sharp, 12u);
  EXPECT_EQ(prepared.feature_edges.size(), 12u);

  Mesh square;
  square.points = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}};
  square.triangles = {{0, 1, 2}, {0, 2, 3}};
  auto open = prep::prepare(square, prep::PrepareParams{}, nullptr);
  size_t boundary = 0;
  for (const auto& f : open.feature_edges) boundary += f.kind == prep::FeatureKind::Boundary;
  EXPECT_EQ(boundary, 4u);
}

// Every face of a box given twice, the second time each triangle split in three at its centre
// (one body tessellated twice): each edge of the box has four triangles, two sheets on each
// side. Counted once each, the sheets make the box's twelve sharp edges and no non-manifold one.
// Where the sheets go three ways (a fin on the box's edge), the edge stays non-manifold.
TEST(Features, AFaceGivenTwiceMakesNoNonManifoldEdges) {
  const Mesh box = tessellated_twice(box_mesh({0, 0, 0}, {1, 1, 1}));
  auto count = [](const prep::PreparedInput& in, prep::FeatureKind kind) {
    return size_t(std::count_if(in.feature_edges.begin(), in.feature_edges.end(),
                                [&](const prep::FeatureEdge& f) { return f.kind == kind; }));
  };
  const prep::PreparedInput twice = prep::prepare(box, prep::PrepareParams{}, nullptr);
  EXPECT_EQ(count(twice, prep::FeatureKind::NonManifold), 0u);
  EXPECT_EQ(count(twice, prep::FeatureKind::Sharp), 12u);
  // A fin on the edge from (1, 0, 0) to (1, 1, 0), pointing out diagonally: three ways there.
  Mesh fin = box;
  const uint32_t f = uint32_t(fin.points.size());
  fin.points.push_back({2, 0, -1});
  fin.points.push_back({2, 1, -1});
  uint32_t a = 0, b = 0;
  for (uint32_t v = 0; v < 8; ++v) {
    if (fin.points[v] == Vec3{1, 0, 0}) a = v;
    if (fin.points[v] == Vec3{1, 1, 0}) b = v;
  }
  fin.triangles.push_back({a, b, f});
  fin.triangles.push_back({b, f + 1, f});
  const prep::PreparedInput finned = prep::prepare(fin, prep::PrepareParams{}, nullptr);
  EXPECT_EQ(count(finned, prep::FeatureKind::NonManifold), 1u);
}

TEST(Prepare, DropsDegenerateAndDuplicateTrianglesAndWeldsCracks) {
  Mesh m = box_mesh({0, 0, 0}, {1, 1, 1});
  m.triangles.push_back({0, 0, 1});       // repeated vertex
  m.triangles.push_back(m.triangles[0]);  // duplicate
  m.points.push_back({0.5, 0, 0});        // collinear with 0 and 1
  m.triangles.push_back({0, 8, 1});
  m.triangle_part.resize(m.triangles.size(), 0);
  auto p = prep::prepare(m, prep::PrepareParams{}, nullptr);
  EXPECT_EQ(p.mesh.triangles.size(), 12u);
  EXPECT_EQ(p.dropped_degenerate, 2u);
  EXPECT_EQ(p.dropped_duplicate, 1u);
}

// A needle that shares no side with another triangle is a segment, not a surface: the
// generator's csg_export has one between two solids (collinear points rounded to float), and
// its wrap, a hair-thin tube with two feature curves on one line, left 1-1.5 % of the
// triangles under 10 degrees. One inside a surface stays (dropping it opens a crack).
TEST(Prepare, DropsStrayNeedlesButNotNeedlesInASurface) {
  Mesh m = box_mesh({0, 0, 0}, {1, 1, 1});
  add_box(m, {3, 0, 0}, {4, 1, 1});
  // From a corner of one box to a corner of the other, its middle 3e-6 off the line (half a
  // millionth of the diagonal; past the weld tolerance, a tenth of a millionth).
  const uint32_t a = 1, b = 8;  // (1, 0, 0) and (3, 0, 0)
  ASSERT_EQ(m.points[a], (Vec3{1, 0, 0}));
  ASSERT_EQ(m.points[b], (Vec3{3, 0, 0}));
  m.points.push_back({2, 3e-6, 0});
  m.triangles.push_back({a, uint32_t(m.points.size() - 1), b});
  // A needle of the same shape at the edge of a fan of three triangles, two of its sides shared.
  const uint32_t q = uint32_t(m.points.size());
  m.points.insert(m.points.end(), {{0, 0, 5}, {2, 0, 5}, {2, 3e-6, 5}, {0, 2, 5}});
  m.triangles.push_back({q, q + 1, q + 2});  // the needle
  m.triangles.push_back({q, q + 2, q + 3});
  m.triangles.push_back({q + 1, q + 3, q + 2});
  m.triangle_part.resize(m.triangles.size(), 0);
  const auto p = prep::prepare(m, prep::PrepareParams{}, nullptr);
  EXPECT_EQ(p.dropped_degenerate, 1u);
  EXPECT_EQ(p.mesh.triangles.size(), 24u + 3u);
  EXPECT_EQ(p.input_to_mesh[24], UINT32_MAX);  // the stray one
  EXPECT_NE(p.input_to_mesh[25], UINT32_MAX);  // the one in the fan
  // A stray sliver a thousandth of the scene high is a surface: kept (the bound is on the
  // height, a millionth of the diagonal).
  Mesh wide = box_mesh({0, 0, 0}, {1, 1, 1});
  wide.points.insert(wide.points.end(), {{2, 0, 0}, {4, 0, 0}, {3, 1e-3, 0}});
  wide.triangles.push_back({8, 9, 10});
  wide.triangle_part.resize(wide.triangles.size(), 0);
  EXPECT_EQ(prep::prepare(wide, prep::PrepareParams{}, nullptr).dropped_degenerate, 0u);
}

TEST(Prepare, FindsTheJunctionLineOfTwoInterpenetratingBoxes) {
  Mesh m = box_mesh({0, 0, 0}, {2, 2, 2});
  add_box(m, {1, 1, 1}, {3, 3, 3}, 1);
  auto p = prep::prepare(m, prep::PrepareParams{}, nullptr);
  ASSERT_FALSE(p.intersections.empty());
  double length = 0;
  for (const auto& s : p.intersections)
    length += std::sqrt((s.a[0] - s.b[0]) * (s.a[0] - s.b[0]) + (s.a[1] - s.b[1]) * (s.a[1] - s.b[1]) +
                        (s.a[2] - s.b[2]) * (s.a[2] - s.b[2]));
  // Two unit-offset cubes meet along 6 unit segments; triangle diagonals may split them.
  EXPECT_NEAR(length, 6.0, 1e-9);
}

// Random triangles over one tilted plane, overlapping one another many times over: coplanar
// but for the rounding of the tilt, so each crossing pair has an "intersection line" made of
// rounding noise. They made thousands of feature curves (400 triangles: 24,000 curves, the
// exact constructions 15 s, the feature snapping past 3 minutes). Lines of planes meeting at
// the feature angle or less are not sharp edges and are not kept.
Mesh tilted_coplanar_soup(int count, uint32_t seed) {
  std::mt19937 rng(seed);
  auto unit = [&] { return double(rng()) / 4294967296.0; };
  const Vec3 n = normalized(Vec3{1, 2, 3});
  const Vec3 u = normalized(cross(n, Vec3{0, 0, 1})), w = cross(n, u);
  Mesh m;
  for (int i = 0; i < 3 * count / 4; ++i) m.points.push_back(u * unit() + w * unit() + Vec3{5, 5, 5});
  for (int i = 0; i < count; ++i) {
    const uint32_t a = rng() % m.points.size(), b = rng() % m.points.size(), c = rng() % m.points.size();
    m.triangles.push_back({a, b, c});
    m.triangle_part.push_back(0);
  }
  return m;
}

TEST(Prepare, NearlyCoplanarOverlapsGiveNoIntersectionLines) {
  const Mesh m = tilted_coplanar_soup(400, 7);
  const auto p = prep::prepare(m, prep::PrepareParams{}, nullptr);
  EXPECT_GT(p.intersecting_pairs.size(), 1000u);  // they do cross
  EXPECT_EQ(p.intersections.size(), 0u);
  // Without the angle, the noise is constructed (a few hundred pairs are enough to show it).
  const std::vector<check::TrianglePair> some(p.intersecting_pairs.begin(), p.intersecting_pairs.begin() + 300);
  EXPECT_GT(check::intersection_segments(p.mesh.points, p.mesh.triangles, some).size(), 0u);
}

TEST(Prepare, IntersectionLinesAreKeptWherePlanesMeetOverTheFeatureAngle) {
  // Two squares through the x axis, the second turned about it by `deg` degrees: they cross
  // along the axis, their planes at min(deg, 180 - deg) degrees.
  for (double deg : {5.0, 25.0, 35.0, 60.0, 90.0, 120.0, 160.0}) {
    SCOPED_TRACE(deg);
    const double c = std::cos(deg * M_PI / 180), s = std::sin(deg * M_PI / 180);
    Mesh m;
    m.points = {{-1, -1, 0}, {1, -1, 0}, {1, 1, 0}, {-1, 1, 0}, {-1, -c, -s}, {1, -c, -s}, {1, c, s}, {-1, c, s}};
    m.triangles = {{0, 1, 2}, {0, 2, 3}, {4, 5, 6}, {4, 6, 7}};
    m.triangle_part = {0, 0, 0, 0};
    const auto p = prep::prepare(m, prep::PrepareParams{}, nullptr);
    ASSERT_FALSE(p.intersecting_pairs.empty());
    const bool sharp = std::min(deg, 180 - deg) > 30;
    EXPECT_EQ(!p.intersections.empty(), sharp);
    prep::PrepareParams wide;
    wide.feature_angle_deg = 4;  // every one of them is sharp at 4 degrees
    EXPECT_FALSE(prep::prepare(m, wide, nullptr).intersections.empty());
  }
}

// Welding from the input's exact weld (what the pipeline does after diagnosing) must give
// what welding every point gives: also where two points differ in the input only below the
// rounding of the move to the local frame (x = 1 and the next double, the box centred at
// x = -3: both become 4), with and without a tolerance.
TEST(Prepare, WeldingFromTheInputsExactWeldGivesTheSameMesh) {
  Mesh soup = box_mesh({-7, -7, -7}, {-6, -6, -6});
  Mesh sheet;
  const double x1 = 1.0, x2 = std::nextafter(1.0, 2.0);
  for (int k = 0; k < 4; ++k) {  // each triangle with its own points, as STL files have them
    const double x = k % 2 ? x2 : x1, y = 0.25 * k;
    const uint32_t first = uint32_t(soup.points.size());
    soup.points.push_back({x, y, 0});
    soup.points.push_back({x, y + 0.25, 0});
    soup.points.push_back({x, y, 0.5});
    soup.triangles.push_back({first, first + 1, first + 2});
  }
  for (const double tolerance : {0.0, 1e-7}) {
    WrapParams params;
    params.weld_tolerance = tolerance;
    const prep::PreparedInput all = prep::prepare(soup, pipeline::prepare_params(params), nullptr);
    const ExactWeld weld = exact_weld(soup.points);
    const prep::PreparedInput shared = prep::prepare(soup, pipeline::prepare_params(params), nullptr, &weld);
    EXPECT_EQ(all.mesh.points, shared.mesh.points) << "tolerance " << tolerance;
    EXPECT_EQ(all.mesh.triangles, shared.mesh.triangles) << "tolerance " << tolerance;
    EXPECT_EQ(all.input_to_mesh, shared.input_to_mesh) << "tolerance " << tolerance;
    EXPECT_EQ(all.welded_vertices, shared.welded_vertices) << "tolerance " << tolerance;
    // The two x values met in the local frame: fewer points than the input's exact weld has.
    EXPECT_LT(all.mesh.points.size(), weld.unique.size()) << "tolerance " << tolerance;
  }
}

TEST(Prepare, RejectsInputWithNothingUsable) {
  Mesh empty;
  try {
    prep::prepare(empty, prep::PrepareParams{}, nullptr);
    FAIL();
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::InvalidInput);
  }
  Mesh flat;
  flat.points = {{0, 0, 0}, {1, 0, 0}, {2, 0, 0}};
  flat.triangles = {{0, 1, 2}};
  EXPECT_THROW(prep::prepare(flat, prep::PrepareParams{}, nullptr), Error);
}

TEST(Intersections, FansMeetOnlyAtTheirCentreUnlessTheyOverlapOrFold) {
  // A flat fan of 64 triangles (a cylinder cap) and a cone fan: no pair intersects.
  for (double height : {0.0, 0.3}) {
    Mesh fan;
    fan.points.push_back({0, 0, height});
    for (int j = 0; j < 64; ++j) fan.points.push_back({std::cos(2 * M_PI * j / 64), std::sin(2 * M_PI * j / 64), 0});
    for (uint32_t j = 0; j < 64; ++j) fan.triangles.push_back({0, 1 + j, 1 + (j + 1) % 64});
    EXPECT_TRUE(check::find_intersecting_pairs(fan.points, fan.triangles).empty()) << "height " << height;
    // In the flat fan, a triangle from the centre over several sectors overlaps them.
    if (height == 0) {
      Mesh overlap = fan;
      overlap.triangles.push_back({0, 3, 9});
      EXPECT_GE(check::find_intersecting_pairs(overlap.points, overlap.triangles).size(), 5u);
    }
  }
  // Two triangles sharing a vertex, one folded through the other.
  std::vector<Vec3> p = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0.2, 0.2, -0.5}, {0.3, 0.3, 0.5}};
  EXPECT_TRUE(check::triangle_pair_intersects(p, {0, 1, 2}, {0, 3, 4}));
  // The same pair with the second triangle lifted off the plane on one side: apart.
  p[3] = {0.2, 0.2, 0.1};
  EXPECT_FALSE(check::triangle_pair_intersects(p, {0, 1, 2}, {0, 3, 4}));
}

// A triangle with a corner twice (a float weld can make one) is a segment: it meets what it
// touches, and the shared-corner logic, which counts matches of distinct corners, must not
// read past the three. Before, {0, 0, 1} against {0, 2, 3} read a fourth corner of a triangle,
// a wild index: a SIGBUS in the proximity refinement.
TEST(Intersections, TriangleWithACornerTwiceMeetsItsNeighbours) {
  const std::vector<Vec3> p = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}, {1, 1, 1}};
  const std::vector<std::pair<Tri, Tri>> pairs = {
      {{0, 0, 1}, {0, 2, 3}}, {{0, 1, 1}, {1, 1, 2}}, {{0, 2, 3}, {3, 4, 3}}, {{2, 2, 2}, {0, 1, 2}}};
  for (const auto& [a, b] : pairs) {
    EXPECT_TRUE(check::triangle_pair_intersects(p, a, b));
    EXPECT_TRUE(check::triangle_pair_intersects(p, b, a));
  }
}

// The pair search buckets triangles on a grid sized by the typical triangle; the ones spanning
// many cells are tested against all boxes directly when they are few, else they go to CGAL's
// box intersection. Against every pair tested directly, on a soup of small triangles, long
// slivers, large triangles (few, and many) and a flat fan (many in one cell), with shared
// vertices and exact touches on cell boundaries: the same pairs, each once.
static void expect_pair_search_finds_every_pair_once(int long_ones) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  Mesh m;
  auto add = [&](const Vec3& a, const Vec3& b, const Vec3& c) {
    const uint32_t n = uint32_t(m.points.size());
    m.points.insert(m.points.end(), {a, b, c});
    m.triangles.push_back({n, n + 1, n + 2});
  };
  for (int k = 0; k < 1500; ++k) {  // small ones, on a lattice of 0.01 so boxes meet on cell faces
    const Vec3 o{std::round(u(rng) * 100) / 100, std::round(u(rng) * 100) / 100, std::round(u(rng) * 100) / 100};
    add(o, o + Vec3{0.02, 0, 0}, o + Vec3{0, 0.01 * std::round(u(rng) * 2 + 1), 0.01 * std::round(u(rng) * 2)});
  }
  for (int k = 0; k < long_ones; ++k) {  // slivers and large ones
    const Vec3 a{u(rng), u(rng), u(rng)}, b{u(rng), u(rng), u(rng)};
    add(a, b, a + Vec3{0.003, 0.002 * u(rng), 0.001});
    add(a, b, Vec3{u(rng), u(rng), u(rng)});
  }
  const uint32_t centre = uint32_t(m.points.size());  // a flat fan: its spokes all meet at the centre
  m.points.push_back({0.5, 0.5, 0.505});
  for (int j = 0; j < 40; ++j)
    m.points.push_back({0.5 + 0.03 * std::cos(2 * M_PI * j / 40), 0.5 + 0.03 * std::sin(2 * M_PI * j / 40), 0.505});
  for (uint32_t j = 0; j < 40; ++j) m.triangles.push_back({centre, centre + 1 + j, centre + 1 + (j + 1) % 40});
  std::vector<std::pair<uint32_t, uint32_t>> expected;
  for (uint32_t a = 0; a < m.triangles.size(); ++a) {
    if (check::triangle_is_degenerate(m.points, m.triangles[a])) continue;
    for (uint32_t b = a + 1; b < m.triangles.size(); ++b)
      if (!check::triangle_is_degenerate(m.points, m.triangles[b]) &&
          check::triangle_pair_intersects(m.points, m.triangles[a], m.triangles[b]))
        expected.push_back({a, b});
  }
  ASSERT_GT(expected.size(), 20u);
  std::vector<std::pair<uint32_t, uint32_t>> found;
  for (const auto& p : check::find_intersecting_pairs(m.points, m.triangles)) found.push_back({p.a, p.b});
  EXPECT_EQ(found, expected);
}

TEST(Intersections, PairSearchFindsEveryPairOnceAmongFewLargeTriangles) { expect_pair_search_finds_every_pair_once(4); }
TEST(Intersections, PairSearchFindsEveryPairOnceAmongManyLargeTriangles) {
  expect_pair_search_finds_every_pair_once(200);
}

// Pieces proved closed and star-shaped skip their own pairs, and long triangles are cut into
// slabs for the search. On tilted CAD cylinders crossing each other (one with two dropped
// wedges of one cap, whose holes touch at the hub, and a dropped side triangle), an
// inside-out sphere, a sphere whose pole is pushed through its far side, and a soup of small
// triangles: the holed cylinders and the spheres that do not fold are proved, the folded one
// is not, and the pairs found are those of every pair tested directly (also when searched as
// a wrap, where no pieces are looked for).
TEST(Intersections, StarShapedPiecesSkipTheirOwnPairsAndLoseNone) {
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  Mesh m;
  std::vector<std::pair<uint32_t, uint32_t>> pieces;  // triangle ranges
  auto tilt = [&](uint32_t first_point, double a, double b, const Vec3& at) {
    for (uint32_t i = first_point; i < m.points.size(); ++i) {
      Vec3 q = m.points[i];
      q = {q[0], std::cos(a) * q[1] - std::sin(a) * q[2], std::sin(a) * q[1] + std::cos(a) * q[2]};
      q = {std::cos(b) * q[0] + std::sin(b) * q[2], q[1], -std::sin(b) * q[0] + std::cos(b) * q[2]};
      m.points[i] = q + at;
    }
  };
  for (int k = 0; k < 4; ++k) {
    const uint32_t points = uint32_t(m.points.size()), tris = uint32_t(m.triangles.size());
    add_cylinder(m, {0, 0, -1}, 0.3, 2.0, 40);
    tilt(points, 0.4 + 0.5 * k, 0.3 * k, {0.35 * k, 0.2 * k, 0});
    pieces.push_back({tris, uint32_t(m.triangles.size())});
  }
  std::vector<uint8_t> dropped(m.triangles.size(), 0);
  dropped[4 * 3] = dropped[4 * 10] = 1;       // two bottom-cap wedges of cylinder 0: holes meeting at its hub
  dropped[pieces[1].first + 4 * 20 + 2] = 1;  // a side triangle of cylinder 1
  auto add_sphere = [&](bool inside_out, bool pushed, const Vec3& at) {
    Mesh s = sphere_mesh(0.5, 12, 24);
    if (pushed) s.points[0] = {0.05, 0, -0.8};  // the north pole through the south
    const uint32_t o = uint32_t(m.points.size()), tris = uint32_t(m.triangles.size());
    for (const Vec3& q : s.points) m.points.push_back(q + at);
    for (Tri t : s.triangles) {
      if (inside_out) std::swap(t[1], t[2]);
      m.triangles.push_back({o + t[0], o + t[1], o + t[2]});
    }
    pieces.push_back({tris, uint32_t(m.triangles.size())});
  };
  add_sphere(true, false, {0.6, 0.3, 0.4});
  add_sphere(false, true, {0.2, 0.9, -0.2});
  for (int k = 0; k < 300; ++k) {  // small triangles: the typical size, so the long ones are cut
    const Vec3 o{u(rng) * 1.6 - 0.4, u(rng) * 1.6 - 0.4, u(rng) * 2 - 1};
    const uint32_t n = uint32_t(m.points.size());
    m.points.insert(m.points.end(), {o, o + Vec3{0.04 * u(rng), 0.04, 0}, o + Vec3{0, 0.03 * u(rng), 0.04}});
    m.triangles.push_back({n, n + 1, n + 2});
  }
  dropped.resize(m.triangles.size(), 0);
  // Drop the chosen triangles, keeping the piece ranges in the new numbering.
  std::vector<uint32_t> renumber(m.triangles.size() + 1, 0);
  std::vector<Tri> kept;
  for (uint32_t t = 0; t < m.triangles.size(); ++t) {
    renumber[t] = uint32_t(kept.size());
    if (!dropped[t]) kept.push_back(m.triangles[t]);
  }
  renumber[m.triangles.size()] = uint32_t(kept.size());
  m.triangles = kept;
  for (auto& [first, end] : pieces) first = renumber[first], end = renumber[end];

  const std::vector<uint32_t> piece = check::star_shaped_pieces(m.points, m.triangles);
  for (size_t k = 0; k < pieces.size(); ++k) {
    const bool folded = k == 5;
    for (uint32_t t = pieces[k].first; t < pieces[k].second; ++t) {
      if (folded) {
        ASSERT_EQ(piece[t], UINT32_MAX) << "the folded sphere, triangle " << t;
      } else {
        ASSERT_NE(piece[t], UINT32_MAX) << "piece " << k << ", triangle " << t;
        ASSERT_EQ(piece[t], piece[pieces[k].first]) << "piece " << k;
      }
    }
  }
  for (size_t k = 0; k + 1 < 5; ++k) EXPECT_NE(piece[pieces[k].first], piece[pieces[k + 1].first]);
  for (uint32_t t = pieces.back().second; t < m.triangles.size(); ++t)
    EXPECT_EQ(piece[t], UINT32_MAX) << "a lone triangle is open";

  std::vector<std::pair<uint32_t, uint32_t>> expected;
  size_t within_folded = 0;
  for (uint32_t a = 0; a < m.triangles.size(); ++a) {
    if (check::triangle_is_degenerate(m.points, m.triangles[a])) continue;
    for (uint32_t b = a + 1; b < m.triangles.size(); ++b)
      if (!check::triangle_is_degenerate(m.points, m.triangles[b]) &&
          check::triangle_pair_intersects(m.points, m.triangles[a], m.triangles[b])) {
        expected.push_back({a, b});
        within_folded += a >= pieces[5].first && b < pieces[5].second;
      }
  }
  ASSERT_GT(within_folded, 10u);
  ASSERT_GT(expected.size(), 200u);
  std::vector<std::pair<uint32_t, uint32_t>> found;
  for (const auto& p : check::find_intersecting_pairs(m.points, m.triangles)) found.push_back({p.a, p.b});
  EXPECT_EQ(found, expected);
  // Searched as a wrap, without looking for star-shaped pieces: the same pairs.
  found.clear();
  for (const auto& p : check::find_intersecting_pairs(m.points, m.triangles, check::SoupKind::kWrap))
    found.push_back({p.a, p.b});
  EXPECT_EQ(found, expected);
}

// Flat unfolded fans (CAD caps) skip the exact tests of spoke pairs that share only the
// centre. The search must still find every real intersection: a triangle through a cap, a
// coplanar triangle over it, and fans that fold onto themselves (an open one turning one and a
// half times, a closed one turning twice), where spokes sharing only the centre do overlap.
TEST(Intersections, FlatFansSkipOnlyPairsProvedApart) {
  Mesh m;
  // Tilted plane frame: e1, e2 in the plane.
  const Vec3 tilted1 = normalized(Vec3{1, 0.3, 0.2}), tilted2 = normalized(cross(Vec3{0.1, 0.2, 1}, tilted1));
  auto fan = [&](const Vec3& centre, int spokes, double turns, bool closed, double lift, Vec3 e1 = {}, Vec3 e2 = {}) {
    if (e1 == Vec3{}) e1 = tilted1, e2 = tilted2;
    const uint32_t c = uint32_t(m.points.size());
    m.points.push_back(centre);
    const int ring = closed ? spokes : spokes + 1;
    for (int j = 0; j < ring; ++j) {
      const double a = 2 * M_PI * turns * j / spokes, r = 1.0 + 0.3 * j / ring;
      m.points.push_back(centre + e1 * (r * std::cos(a)) + e2 * (r * std::sin(a)) + cross(e1, e2) * lift);
    }
    for (int j = 0; j < spokes; ++j) m.triangles.push_back({c, c + 1 + uint32_t(j), c + 1 + uint32_t((j + 1) % ring)});
  };
  fan({0, 0, 0}, 64, 1.0, true, 0.0);    // a flat closed cap
  fan({5, 0, 0}, 48, 0.75, false, 0.0);  // a flat open fan
  fan({0, 5, 0}, 40, 1.0, true, 0.4);    // a cone tip: not flat, still unfolded
  // The folding ones in the plane z = 0, so that overlapping spokes are exactly coplanar.
  const uint32_t fold_start = uint32_t(m.triangles.size());
  fan({5, 5, 0}, 96, 1.5, false, 0.0, {1, 0, 0}, {0, 1, 0});   // folds: turns one and a half times
  fan({0, 10, 0}, 128, 2.0, true, 0.0, {1, 0, 0}, {0, 1, 0});  // closed, turning twice
  const uint32_t spiral_end = uint32_t(m.triangles.size());
  auto add = [&](const Vec3& a, const Vec3& b, const Vec3& c) {
    const uint32_t n = uint32_t(m.points.size());
    m.points.insert(m.points.end(), {a, b, c});
    m.triangles.push_back({n, n + 1, n + 2});
  };
  const Vec3 &e1 = tilted1, &e2 = tilted2, up = cross(e1, e2);
  add(up * 0.5 + e1 * 0.1, up * -0.5 + e1 * 0.1, e2 * 0.3 + e1 * 0.05);  // through the cap, near its centre
  add(e1 * 0.2, e1 * 0.6 + e2 * 0.1, e1 * 0.3 + e2 * 0.5);               // in the cap's plane, over it
  std::vector<std::pair<uint32_t, uint32_t>> expected;
  size_t folded = 0;
  for (uint32_t a = 0; a < m.triangles.size(); ++a)
    for (uint32_t b = a + 1; b < m.triangles.size(); ++b)
      if (check::triangle_pair_intersects(m.points, m.triangles[a], m.triangles[b])) {
        expected.push_back({a, b});
        folded += a >= fold_start && b < spiral_end;
      }
  ASSERT_GT(folded, 100u) << "the folded fans must overlap themselves";
  // As an input (large fans only, gaps allowed) and as a wrap (closed fans of any size).
  for (const auto kind : {check::SoupKind::kInput, check::SoupKind::kWrap}) {
    std::vector<std::pair<uint32_t, uint32_t>> found;
    for (const auto& p : check::find_intersecting_pairs(m.points, m.triangles, kind)) found.push_back({p.a, p.b});
    EXPECT_EQ(found, expected) << (kind == check::SoupKind::kWrap ? "wrap" : "input");
  }
}

// A fan of `spokes` triangles round the origin (closed unless `open`), its spokes at the
// given angles (radians, in fan order) and heights, in a plane tilted by `tilt`, moved by
// `shift`: the points (centre first) and each triangle's corners after the centre.
struct TestFan {
  std::vector<Vec3> points;
  std::vector<std::array<uint32_t, 2>> corners;
  std::vector<Tri> triangles() const {
    std::vector<Tri> out;
    for (const auto& c : corners) out.push_back({0, c[0], c[1]});
    return out;
  }
};
static TestFan make_fan(const std::vector<double>& angle, const std::vector<double>& height, bool open,
                        const Vec3& tilt, const Vec3& shift) {
  const Vec3 up = normalized(tilt), e1 = normalized(cross(up, Vec3{0.3, 0.5, 0.7})), e2 = cross(up, e1);
  TestFan fan;
  fan.points.push_back(shift);
  for (size_t j = 0; j < angle.size(); ++j)
    fan.points.push_back(shift + e1 * std::cos(angle[j]) * (1 + 0.1 * j) + e2 * std::sin(angle[j]) * (1 + 0.1 * j) +
                         up * height[j]);
  const uint32_t n = uint32_t(angle.size());
  for (uint32_t j = 0; j + (open ? 1 : 0) < n; ++j) fan.corners.push_back({1 + j, 1 + (j + 1) % n});
  return fan;
}

TEST(Intersections, ClosedUnfoldedFansAreTheOnesWhosePairsMeetOnlyWhereTheyShare) {
  auto unfolded = [](const TestFan& f) {
    return check::closed_fan_unfolded(f.points, 0, f.corners.data(), f.corners.size());
  };
  auto regular = [](int n, double turns) {
    std::vector<double> a(size_t(n), 0.0);
    for (int j = 0; j < n; ++j) a[size_t(j)] = 2 * M_PI * turns * j / n;
    return a;
  };
  const Vec3 tilt{0.2, -0.4, 1}, far{1e4, -3e4, 2e3};
  EXPECT_TRUE(unfolded(make_fan(regular(6, 1), std::vector<double>(6, 0.0), false, tilt, {})));     // flat
  EXPECT_TRUE(unfolded(make_fan(regular(7, 1), std::vector<double>(7, -0.8), false, tilt, far)));   // a cone, far out
  EXPECT_FALSE(unfolded(make_fan(regular(6, 1), std::vector<double>(6, 0.0), true, tilt, {})));     // open
  EXPECT_FALSE(unfolded(make_fan(regular(12, 2), std::vector<double>(12, 0.0), false, tilt, {})));  // round twice
  std::vector<double> folded = regular(8, 1);
  std::swap(folded[2], folded[3]);  // one sector turns back
  EXPECT_FALSE(unfolded(make_fan(folded, std::vector<double>(8, 0.0), false, tilt, {})));
  TestFan reversed = make_fan(regular(5, 1), std::vector<double>(5, 0.1), false, tilt, far);
  for (auto& c : reversed.corners) std::swap(c[0], c[1]);  // the other way round: still unfolded
  EXPECT_TRUE(unfolded(reversed));

  // Random fans: flat on a lattice (exactly coplanar), nearly flat, cones, wild heights,
  // folded, turning twice, open, far from the origin. Every fan called unfolded has no pair
  // that meets beyond what it shares, by the exact tests alone.
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  size_t called_unfolded = 0, with_crossings = 0;
  for (int trial = 0; trial < 3000; ++trial) {
    const int n = 3 + int(u(rng) * 10);
    const double turns = u(rng) < 0.2 ? 2.0 : 1.0;
    std::vector<double> angle(static_cast<size_t>(n)), height(static_cast<size_t>(n));
    for (int j = 0; j < n; ++j) angle[size_t(j)] = 2 * M_PI * turns * (j + 0.8 * u(rng)) / n;
    if (u(rng) < 0.3) std::swap(angle[0], angle[1]);
    const int shape = trial % 4;
    for (double& h : height)
      h = shape == 0 ? 0.0 : shape == 1 ? 1e-9 * (u(rng) - 0.5) : shape == 2 ? 0.5 : 4 * (u(rng) - 0.5);
    const Vec3 axis = trial % 3 == 0 ? Vec3{0, 0, 1} : Vec3{u(rng) - 0.5, u(rng) - 0.5, 1};
    TestFan fan = make_fan(angle, height, u(rng) < 0.1, axis, trial % 5 == 0 ? far : Vec3{});
    if (shape == 0 && trial % 3 == 0)  // exactly on a lattice in the plane z = 0
      for (Vec3& q : fan.points) q = {std::round(q[0] * 8) / 8, std::round(q[1] * 8) / 8, 0.0};
    const std::vector<Tri> tris = fan.triangles();
    bool degenerate = false, crossing = false;
    for (const Tri& t : tris) degenerate = degenerate || check::triangle_is_degenerate(fan.points, t);
    if (degenerate) continue;
    for (size_t a = 0; a < tris.size(); ++a)
      for (size_t b = a + 1; b < tris.size(); ++b)
        crossing = crossing || check::triangle_pair_intersects(fan.points, tris[a], tris[b], false);
    const bool called = unfolded(fan);
    ASSERT_FALSE(called && crossing) << "trial " << trial;
    called_unfolded += called;
    with_crossings += crossing;
  }
  EXPECT_GT(called_unfolded, 600u);
  EXPECT_GT(with_crossings, 300u);
}

TEST(Intersections, TheFastProofsInDoublesNeverChangeTheExactAnswer) {
  // Pairs sharing 0, 1 or 2 vertices: exactly coplanar on lattice points (an axis plane and a
  // tilted one), nearly coplanar, general, and small triangles far from the origin. With
  // and without the fast proofs, the answers must agree; the coplanar ones are mixed.
  std::mt19937 rng(7);
  std::uniform_int_distribution<int> lattice(-4, 4);
  std::uniform_real_distribution<double> uni(-1, 1);
  size_t checked = 0, intersecting = 0;
  for (int kind = 0; kind < 5; ++kind)
    for (int trial = 0; trial < 4000; ++trial) {
      std::vector<Vec3> p(6);
      for (Vec3& q : p) {
        const double x = lattice(rng), y = lattice(rng);
        switch (kind) {
          case 0:
            q = {x, y, 0};
            break;  // axis plane
          case 1:
            q = {x, y, 3 - x - y};
            break;  // tilted plane
          case 2:
            q = {x, y, 1e-12 * uni(rng)};
            break;  // nearly coplanar
          case 3:
            q = {uni(rng), uni(rng), uni(rng)};
            break;  // general
          default:
            q = {1e4 + 1e-3 * x, -2e4 + 1e-3 * y, 5e3 + 1e-3 * (x - y)};  // far away, tilted
        }
      }
      const int shared = trial % 3;
      Tri a{0, 1, 2}, b{3, 4, 5};
      if (shared >= 1) b[0] = 0;
      if (shared == 2) b[1] = 2, b[2] = 1, b[0] = 3;  // the common edge reversed, as in a mesh
      if (check::triangle_is_degenerate(p, a) || check::triangle_is_degenerate(p, b)) continue;
      const bool exact = check::triangle_pair_intersects(p, a, b, false);
      ASSERT_EQ(check::triangle_pair_intersects(p, a, b), exact) << "kind " << kind << " trial " << trial;
      ++checked;
      intersecting += exact;
    }
  EXPECT_GT(checked, 10000u);
  EXPECT_GT(intersecting, checked / 10);
  EXPECT_LT(intersecting, checked - checked / 10);
}

TEST(InputIntersections, CopiesOfATriangleCountAsTheyDoInTheInput) {
  // Mesh triangle 1 stands for three input triangles (two dropped copies), input triangle 4
  // was degenerate. Mesh pair (0, 1) is three input pairs; the copies make three more.
  std::vector<check::TrianglePair> pairs = {{0, 1}};
  std::vector<uint32_t> input_to_mesh = {0, 1, 1, 1, UINT32_MAX, 2};
  auto c = prep::input_intersections(pairs, input_to_mesh, 3);
  EXPECT_EQ(c.pairs, 3u + 3u);
  EXPECT_EQ(c.triangles, 4u);  // 0 and the three copies of 1; 2 meets nothing
  // A lone duplicate with no other contact still intersects its copy.
  auto d = prep::input_intersections({}, {0, 0, 1}, 2);
  EXPECT_EQ(d.pairs, 1u);
  EXPECT_EQ(d.triangles, 2u);
}

TEST(Prepare, OneSearchGivesTheSegmentsAndTheInputCountsOfASearchOnTheRawInput) {
  // Three interpenetrating boxes with the defects prepare removes: a duplicate of a crossing
  // triangle, a reversed copy of another, a degenerate triangle.
  Mesh m = box_mesh({0, 0, 0}, {2, 2, 2});
  add_box(m, {1, 1, 1}, {3, 3, 3}, 1);
  add_box(m, {0.5, -1, 0.5}, {1.5, 4, 1.5}, 2);
  m.triangles.push_back(m.triangles[13]);
  m.triangles.push_back({m.triangles[2][0], m.triangles[2][2], m.triangles[2][1]});
  m.triangles.push_back({0, 0, 1});
  m.triangle_part.resize(m.triangles.size(), 0);

  auto p = prep::prepare(m, prep::PrepareParams{}, nullptr);
  ASSERT_EQ(p.dropped_duplicate, 2u);
  ASSERT_EQ(p.input_to_mesh.size(), m.triangles.size());
  // The kept pairs are exactly a fresh search of the prepared mesh, and give its segments.
  auto fresh = check::find_intersecting_pairs(p.mesh.points, p.mesh.triangles);
  ASSERT_EQ(p.intersecting_pairs.size(), fresh.size());
  for (size_t i = 0; i < fresh.size(); ++i) {
    EXPECT_EQ(p.intersecting_pairs[i].a, fresh[i].a);
    EXPECT_EQ(p.intersecting_pairs[i].b, fresh[i].b);
  }
  auto segments = check::intersection_segments(p.mesh.points, p.mesh.triangles, fresh);
  ASSERT_EQ(p.intersections.size(), segments.size());
  ASSERT_FALSE(segments.empty());
  for (size_t i = 0; i < segments.size(); ++i) {
    EXPECT_EQ(p.intersections[i].tri_a, segments[i].tri_a);
    EXPECT_EQ(p.intersections[i].tri_b, segments[i].tri_b);
    EXPECT_EQ(p.intersections[i].a, segments[i].a);
    EXPECT_EQ(p.intersections[i].b, segments[i].b);
  }
  // Mapped back to the input, the counts are those of the search on the input as read.
  const MeshDiagnostics raw = diagnose(m, true);
  ASSERT_GT(raw.intersecting_pairs, 0u);
  auto c = prep::input_intersections(p.intersecting_pairs, p.input_to_mesh, p.mesh.triangles.size());
  EXPECT_EQ(c.pairs, raw.intersecting_pairs);
  EXPECT_EQ(c.triangles, raw.intersecting_triangles);
}

TEST(Diagnose, BoxesTouchingAtACornerMakeOneNonManifoldVertex) {
  Mesh m = box_mesh({0, 0, 0}, {1, 1, 1});
  add_box(m, {1, 1, 1}, {2, 2, 2}, 1);  // shares the point (1, 1, 1) only
  MeshDiagnostics d = diagnose(m, false);
  EXPECT_EQ(d.nonmanifold_vertices, 1u);
  EXPECT_EQ(d.nonmanifold_edges, 0u);
  EXPECT_FALSE(d.manifold);
  EXPECT_EQ(d.components, 1u);
}

TEST(Diagnose, AClosedConeWithAWideFanIsManifoldAndOriented) {
  // Thousands of triangles around the apex and the base centre (CAD cones and caps): the
  // fan test must see one fan at each, and stay fast.
  const int n = 4000;
  Mesh m;
  m.points.push_back({0, 0, 1});  // apex
  m.points.push_back({0, 0, 0});  // base centre
  for (int j = 0; j < n; ++j) m.points.push_back({std::cos(2 * M_PI * j / n), std::sin(2 * M_PI * j / n), 0});
  for (uint32_t j = 0; j < uint32_t(n); ++j) {
    const uint32_t a = 2 + j, b = 2 + (j + 1) % n;
    m.triangles.push_back({0, a, b});
    m.triangles.push_back({1, b, a});
  }
  MeshDiagnostics d = diagnose(m, false);
  EXPECT_EQ(d.nonmanifold_vertices, 0u);
  EXPECT_EQ(d.border_edges, 0u);
  EXPECT_EQ(d.misoriented_edges, 0u);
  EXPECT_TRUE(d.oriented);
  EXPECT_TRUE(d.outward);
  // A second cone standing on the first one's apex: the apex then has two fans of n
  // triangles each, joined by no edge, and is the one non-manifold vertex.
  const uint32_t top = uint32_t(m.points.size());
  m.points.push_back({0, 0, 2});
  for (int j = 0; j < n; ++j) m.points.push_back({std::cos(2 * M_PI * j / n), std::sin(2 * M_PI * j / n), 2});
  for (uint32_t j = 0; j < uint32_t(n); ++j) {
    const uint32_t a = top + 1 + j, b = top + 1 + (j + 1) % n;
    m.triangles.push_back({0, b, a});
    m.triangles.push_back({top, a, b});
  }
  d = diagnose(m, false);
  EXPECT_EQ(d.nonmanifold_vertices, 1u);
  EXPECT_EQ(d.nonmanifold_edges, 0u);
  EXPECT_EQ(d.components, 1u);
}
