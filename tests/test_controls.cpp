// User controls of the voxel stage (issue 5): contact prevention, volume by seed points,
// gap closure, leak detection, closedness report, control volumes, part sizes, part labels.
// Every wrap these tests make must be a valid closed surface.
#include <gtest/gtest.h>

#include <cmath>

#include "common/vec.h"
#include "test_meshes.h"
#include "vdbwrap/wrap.h"

using namespace vdbwrap;
using namespace vdbwrap::testing;

namespace {

WrapParams quick(const std::string& base = "1%") {
  WrapParams p;
  p.base_size = Length::parse(base);
  p.compute_distances = false;
  p.coarsen_tolerance = 0;  // triangle counts here measure refinement
  return p;
}

void expect_valid(const Mesh& m) {
  auto v = valid_closed_surface(m);
  EXPECT_TRUE(v.ok) << v.why;
}

size_t triangles_with_centroid_in(const Mesh& m, const Vec3& lo, const Vec3& hi) {
  size_t n = 0;
  for (const Tri& t : m.triangles) {
    Vec3 c = (m.points[t[0]] + m.points[t[1]] + m.points[t[2]]) * (1.0 / 3.0);
    if (c[0] >= lo[0] && c[1] >= lo[1] && c[2] >= lo[2] && c[0] <= hi[0] && c[1] <= hi[1] && c[2] <= hi[2]) ++n;
  }
  return n;
}

}  // namespace

TEST(ContactPrevention, TwoBoxesCloseTogetherFuseWithoutItAndStayApartWithIt) {
  // Two unit boxes 0.3 % of the diagonal apart: far closer than a 1 % cell.
  Mesh m;
  const double gap = 0.003 * std::sqrt(2.003 * 2.003 + 2.0);
  add_box(m, {0, 0, 0}, {1, 1, 1}, 0);
  add_box(m, {1 + gap, 0, 0}, {2 + gap, 1, 1}, 1);
  m.part_names = {"hot", "cold"};

  WrapResult fused = wrap(m, quick());
  expect_valid(fused.surface);
  EXPECT_EQ(fused.report.output.components, 1u) << "without contact prevention the 1 % cells bridge the gap";

  WrapParams p = quick();
  p.contact_prevention.push_back(ContactRule::parse("hot,cold"));
  WrapResult apart = wrap(m, p);
  expect_valid(apart.surface);
  EXPECT_EQ(apart.report.output.components, 2u);
  EXPECT_EQ(apart.report.contact.separate_bodies, 2u);
  EXPECT_EQ(apart.report.contact.unresolved_cells, 0u);
  // Each body's triangles carry its part, and none crosses the gap.
  for (size_t t = 0; t < apart.surface.triangles.size(); ++t) {
    const Tri& tri = apart.surface.triangles[t];
    double x =
        (apart.surface.points[tri[0]][0] + apart.surface.points[tri[1]][0] + apart.surface.points[tri[2]][0]) / 3;
    EXPECT_EQ(apart.surface.part_of(t), x < 1 + gap / 2 ? 0 : 1) << "triangle " << t << " at x " << x;
    if (::testing::Test::HasFailure()) break;
  }

  // Group against group spelling, and a floor too coarse to separate them: reported.
  WrapParams coarse = quick();
  coarse.contact_prevention.push_back(ContactRule::parse("hot:cold"));
  coarse.contact_floor = Length::parse("1%");
  WrapResult unresolved = wrap(m, coarse);
  expect_valid(unresolved.surface);
  EXPECT_GT(unresolved.report.contact.unresolved_cells, 0u);
  ASSERT_FALSE(unresolved.report.contact.unresolved_locations.empty());
  EXPECT_NEAR(unresolved.report.contact.unresolved_locations.front()[0], 1 + gap / 2, 0.05);
}

TEST(ContactPrevention, UnknownPartNamesAreRejectedWithTheKnownOnes) {
  Mesh m;
  add_box(m, {0, 0, 0}, {1, 1, 1}, 0);
  add_box(m, {2, 0, 0}, {3, 1, 1}, 1);
  m.part_names = {"hot", "cold"};
  WrapParams p = quick();
  p.contact_prevention.push_back(ContactRule::parse("hot,lukewarm"));
  try {
    wrap(m, p);
    FAIL() << "an unknown part must be an argument error";
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::InvalidArgument);
    EXPECT_NE(std::string(e.what()).find("lukewarm"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("cold"), std::string::npos) << e.what();
  }
}

// A cube with a hole 0.1 wide in its top, beside two blocks with a slot 0.06 wide between
// them, wrapped from outside with a gap closure of 0.15: the hole is bridged (the cube's
// inside stays out of the wrap), and the slot, which leads nowhere, is wrapped as without gap
// closure. The opening of the free space alone filled the slot (the gap's ball does not enter
// it): its walls' middle ended half a block from the wrap.
TEST(GapClosure, OnlyTheOpeningsAreBridgedASlotThatLeadsNowhereIsFollowed) {
  Mesh m = holed_cube(0.1);
  add_box(m, {1.3, 0, 0}, {1.7, 1, 1});
  add_box(m, {1.76, 0, 0}, {2.16, 1, 1});
  m.triangle_part.clear();  // one part, as the holed cube has no part list
  WrapParams p;
  p.base_size = Length::parse("1%");
  p.gap_closure = Length{0.15, false};
  const WrapResult r = wrap(m, p);
  expect_valid(r.surface);
  EXPECT_GT(r.report.output.volume, 0.95 * (1.0 + 2 * 0.4)) << "the cube's inside is not wrapped";
  EXPECT_LT(r.report.output.volume, 1.05 * (1.0 + 2 * 0.4));
  EXPECT_LT(r.report.input_to_output.max, 2 * r.report.finest_size) << "every wall of the slot is followed";
  // The same without the hole: the wrap over the slot is the same as with a closed cube.
  WrapParams plain = p;
  plain.gap_closure.reset();
  Mesh closed = box_mesh({0, 0, 0}, {1, 1, 1});
  add_box(closed, {1.3, 0, 0}, {1.7, 1, 1});
  add_box(closed, {1.76, 0, 0}, {2.16, 1, 1});
  const WrapResult c = wrap(closed, plain);
  EXPECT_NEAR(r.report.output.volume, c.report.output.volume, 0.01);
}

TEST(GapClosure, HoleSmallerThanTheGapIsClosedAndTheLeakIsFoundBelowIt) {
  const Mesh m = holed_cube(0.1);

  // Closedness report: the input as given encloses nothing at 1 %.
  WrapParams outside = quick();
  WrapResult around = wrap(m, outside);
  expect_valid(around.surface);
  EXPECT_FALSE(around.report.volumes.encloses_volume);
  EXPECT_EQ(around.report.volumes.enclosed_volumes, 0u);

  // A seed point inside and a gap closure above the hole: a closed inside wrap.
  WrapParams closed = quick();
  closed.volume = VolumeChoice::SeedPoints;
  closed.seed_points = {{0.5, 0.5, 0.5}};
  closed.gap_closure = Length{0.15, false};
  WrapResult inside = wrap(m, closed);
  expect_valid(inside.surface);
  EXPECT_TRUE(inside.report.volumes.encloses_volume);
  EXPECT_NEAR(inside.report.output.volume, 1.0, 0.02) << "the whole cube's inside, the hole capped";

  // Gap closure below the hole: a leak, with the hole's location within one cell.
  WrapParams leaky = closed;
  leaky.gap_closure = Length{0.05, false};
  for (bool with_gap : {true, false}) {
    if (!with_gap) leaky.gap_closure.reset();
    try {
      wrap(m, leaky);
      FAIL() << "the seed's volume reaches the outside through the hole";
    } catch (const WrapFailure& f) {
      const LeakReport& leak = f.report().leak;
      ASSERT_TRUE(leak.detected);
      EXPECT_EQ(f.kind(), ErrorKind::WrapFailed);
      EXPECT_NE(leak.description.find("outside"), std::string::npos);
      // Distance from the reported location to the hole (the square [0.45, 0.55]^2 at z = 1).
      Vec3 nearest{std::clamp(leak.location[0], 0.45, 0.55), std::clamp(leak.location[1], 0.45, 0.55), 1.0};
      EXPECT_LE(norm(leak.location - nearest), f.report().finest_size)
          << "leak at " << leak.location[0] << " " << leak.location[1] << " " << leak.location[2];
      EXPECT_GT(leak.width, 0.05);
      EXPECT_LT(leak.width, 0.15);
      EXPECT_GE(leak.path.size(), 2u);
      EXPECT_NE(leak_to_obj(leak).find("\nl "), std::string::npos);
    }
  }
}

TEST(VolumeChoice, NestedShellsLargestInsideAndSeedPointsInTwoChambers) {
  // Nested shells: the shell between the boxes (56) is larger than the inner cube (8).
  Mesh nested = box_mesh({0, 0, 0}, {4, 4, 4});
  add_box(nested, {1, 1, 1}, {3, 3, 3});
  WrapParams inside = quick("2%");
  inside.volume = VolumeChoice::Inside;
  WrapResult shell = wrap(nested, inside);
  expect_valid(shell.surface);
  EXPECT_EQ(shell.report.volumes.enclosed_volumes, 2u);
  EXPECT_EQ(shell.report.output.components, 2u) << "the shell's outer and inner boundary";
  EXPECT_NEAR(shell.report.output.volume, 56.0, 1.0);

  // The inner cube by a seed point.
  WrapParams seed = quick("2%");
  seed.volume = VolumeChoice::SeedPoints;
  seed.seed_points = {{2, 2, 2}};
  WrapResult inner = wrap(nested, seed);
  expect_valid(inner.surface);
  EXPECT_NEAR(inner.report.output.volume, 8.0, 0.2);

  // A box split by a wall into two chambers: a seed point in each gives both, one body each.
  Mesh chambers = box_mesh({0, 0, 0}, {2, 1, 1});
  uint32_t b = uint32_t(chambers.points.size());
  for (Vec3 p : {Vec3{1, 0, 0}, Vec3{1, 1, 0}, Vec3{1, 1, 1}, Vec3{1, 0, 1}}) chambers.points.push_back(p);
  chambers.triangles.push_back({b, b + 1, b + 2});
  chambers.triangles.push_back({b, b + 2, b + 3});
  chambers.triangle_part.resize(chambers.triangles.size(), 0);
  WrapParams two = quick();
  two.volume = VolumeChoice::SeedPoints;
  two.seed_points = {{0.5, 0.5, 0.5}, {1.5, 0.5, 0.5}};
  WrapResult both = wrap(chambers, two);
  expect_valid(both.surface);
  EXPECT_EQ(both.report.output.components, 2u);
  EXPECT_NEAR(both.report.output.volume, 2.0, 0.05);
  two.seed_points = {{0.5, 0.5, 0.5}};
  WrapResult one = wrap(chambers, two);
  expect_valid(one.surface);
  EXPECT_NEAR(one.report.output.volume, 1.0, 0.03);

  // Two seed points in one chamber: its volume reaches the other seed's, a leak.
  two.seed_points = {{0.3, 0.5, 0.5}, {0.7, 0.5, 0.5}};
  try {
    wrap(chambers, two);
    FAIL() << "two seeds in one chamber";
  } catch (const WrapFailure& f) {
    EXPECT_TRUE(f.report().leak.detected);
    EXPECT_NE(f.report().leak.description.find("seed point 1"), std::string::npos) << f.report().leak.description;
  }

  // A seed point outside the model: an argument error.
  two.seed_points = {{5, 5, 5}};
  try {
    wrap(chambers, two);
    FAIL() << "a seed point outside the bounding box";
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::InvalidArgument);
  }
}

// A seed point between two nested spheres 0.1 apart (about three base cells at 1 %): the
// flood fill at the base size keeps only part of that thin volume, and the inside and seed
// volumes are not refined where far (a finer grid could open a leak). The wrap is valid, and
// the progress log says how far it stays and what to do; the inside of a plain box says nothing.
TEST(VolumeChoice, AThinSeedVolumeLeftFarFromTheInputIsReportedWithTheRemedy) {
  struct Messages : ProgressSink {
    std::vector<std::string> seen;
    void progress(const std::string&, double, const std::string& message) override { seen.push_back(message); }
  };
  auto remedy_said = [](const Messages& m) {
    for (const std::string& text : m.seen)
      if (text.find("smaller --base-size") != std::string::npos &&
          text.find("base cells off the input") != std::string::npos)
        return true;
    return false;
  };
  Mesh shells = sphere_mesh(1.0, 48, 96);
  Mesh inner = sphere_mesh(0.9, 48, 96);
  const uint32_t k = uint32_t(shells.points.size());
  shells.points.insert(shells.points.end(), inner.points.begin(), inner.points.end());
  for (const Tri& t : inner.triangles) shells.triangles.push_back({k + t[0], k + t[2], k + t[1]});  // facing inward
  WrapParams seed;
  seed.base_size = Length::parse("1%");
  seed.volume = VolumeChoice::SeedPoints;
  seed.seed_points = {{0.95, 0, 0}};
  Messages thin;
  WrapResult r = wrap(shells, seed, &thin);
  expect_valid(r.surface);
  ASSERT_GT(r.report.output_to_input.p95, 0.5 * r.report.base_size) << "the case the test is about";
  EXPECT_TRUE(remedy_said(thin));

  WrapParams inside;
  inside.base_size = Length::parse("1%");
  inside.volume = VolumeChoice::Inside;
  Messages box;
  WrapResult plain = wrap(box_mesh({0, 0, 0}, {1, 1, 1}), inside, &box);
  expect_valid(plain.surface);
  EXPECT_LE(plain.report.output_to_input.p95, 0.5 * plain.report.base_size);
  EXPECT_FALSE(remedy_said(box));
}

TEST(ControlVolumes, RefineOnlyWhereTheyAre) {
  const Mesh sphere = sphere_mesh(1.0, 48, 96);
  WrapParams plain = quick("4%");
  plain.levels = 0;
  WrapResult before = wrap(sphere, plain);
  expect_valid(before.surface);

  // A box over the +x+y+z octant's cap with cells 4 times smaller.
  WrapParams controlled = plain;
  controlled.control_volumes.push_back(ControlVolume::parse("box:0.3,0.3,0.3,1.2,1.2,1.2:1%"));
  WrapResult after = wrap(sphere, controlled);
  expect_valid(after.surface);
  EXPECT_EQ(after.report.control_sizes.size(), 1u);

  const Vec3 lo{0.35, 0.35, 0.35}, hi{1.2, 1.2, 1.2};
  const size_t in_before = triangles_with_centroid_in(before.surface, lo, hi);
  const size_t in_after = triangles_with_centroid_in(after.surface, lo, hi);
  EXPECT_GT(double(in_after), 8.0 * double(in_before)) << in_before << " -> " << in_after;
  // Far from it (the -x-y-z octant) nothing changes.
  const Vec3 flo{-1.2, -1.2, -1.2}, fhi{-0.1, -0.1, -0.1};
  const double far_before = double(triangles_with_centroid_in(before.surface, flo, fhi));
  const double far_after = double(triangles_with_centroid_in(after.surface, flo, fhi));
  EXPECT_NEAR(far_after, far_before, 0.05 * far_before);

  // The other shapes parse and refine too (a sphere and a cone here).
  for (const char* spec :
       {"sphere:0.8,0.8,0.8,0.4:1%", "cone:0,0,0,1,1,1,0.05,0.5:1%", "cylinder:0,0,0,1,1,1,0.3:1%"}) {
    WrapParams p = plain;
    p.control_volumes.push_back(ControlVolume::parse(spec));
    WrapResult r = wrap(sphere, p);
    expect_valid(r.surface);
    EXPECT_GT(triangles_with_centroid_in(r.surface, lo, hi), 2 * in_before) << spec;
  }
}

TEST(ControlVolumes, ShapeDistancesAndParsing) {
  ControlVolume cone = ControlVolume::parse("cone:0,0,0,0,0,2,1,0:0.1");
  EXPECT_EQ(cone.shape, ControlVolume::Shape::Cone);
  EXPECT_FALSE(cone.size.percent_of_diagonal);
  for (const char* bad :
       {"box:0,0,0,1,1:1%", "ball:0,0,0,1:1%", "sphere:0,0,0,1", "cylinder:0,0,0,0,0,0,1:1%", "box:0,0,0,1,1,1:-1"})
    EXPECT_THROW(ControlVolume::parse(bad), Error) << bad;
  EXPECT_THROW(ContactRule::parse("hot"), Error);
  EXPECT_THROW(ContactRule::parse("a:b:c"), Error);
  EXPECT_EQ(ContactRule::parse("a, b : c").groups.size(), 2u);
  EXPECT_EQ(PartSize::parse("wing=0.5%").part, "wing");
  // A blank name is refused as the API's empty one is (found by fuzz_params_text: " =1").
  for (const char* bad : {"=1", " =1", "\t =0.5%", "wing"}) EXPECT_THROW(PartSize::parse(bad), Error) << bad;
  VolumeChoice choice;
  std::vector<Vec3> seeds;
  parse_volume_choice("1,2,3;4,5,6", choice, seeds);
  EXPECT_EQ(choice, VolumeChoice::SeedPoints);
  ASSERT_EQ(seeds.size(), 2u);
  EXPECT_EQ(seeds[1][2], 6);
  EXPECT_THROW(parse_volume_choice("1,2", choice, seeds), Error);
  EXPECT_THROW(parse_volume_choice("insid", choice, seeds), Error);
}

TEST(PartSizes, RefineOnlyTheNamedPart) {
  Mesh m;
  add_box(m, {0, 0, 0}, {1, 1, 1}, 0);
  add_box(m, {2, 0, 0}, {3, 1, 1}, 1);
  m.part_names = {"left", "right"};
  WrapParams plain = quick("3%");
  plain.levels = 0;
  plain.snap_features = false;
  WrapResult before = wrap(m, plain);
  WrapParams sized = plain;
  sized.part_sizes.push_back(PartSize::parse("right=0.75%"));
  WrapResult after = wrap(m, sized);
  expect_valid(after.surface);
  const Vec3 llo{-1, -1, -1}, lhi{1.5, 2, 2}, rlo{1.5, -1, -1}, rhi{4, 2, 2};
  // The left box keeps its cells. Its triangle count may move by a few: coarsening and
  // remeshing take nodes in an order that interleaves both boxes' nodes, and the right box's
  // finer lattice renumbers them. Refinement of the left box would multiply it by 16.
  const double left_before = double(triangles_with_centroid_in(before.surface, llo, lhi));
  EXPECT_NEAR(double(triangles_with_centroid_in(after.surface, llo, lhi)), left_before, 0.02 * left_before);
  EXPECT_GT(triangles_with_centroid_in(after.surface, rlo, rhi),
            8 * triangles_with_centroid_in(before.surface, rlo, rhi));
}
