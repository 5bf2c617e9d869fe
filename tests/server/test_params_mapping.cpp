// The one mapping between the vdbwrap.v1 messages and the core API: every field both ways,
// out-of-range values refused.
#include "service_harness.h"

using namespace server_test;

namespace {

// True when `map` refuses the message that `set` fills, as bad parameters.
template <typename Message, typename Map, typename Set>
bool refused_by(Map map, Set set) {
  Message m;
  set(m);
  try {
    map(m);
  } catch (const vdbwrap::Error& e) {
    return e.kind() == vdbwrap::ErrorKind::InvalidArgument;
  }
  return false;
}

// --- tests ----------------------------------------------------------------------------

TEST(ParamsMapping, RoundTripsEveryFieldAndRefusesOutOfRange) {
  vdbwrap::WrapParams p;
  p.base_size = {0.25, false};
  p.levels = 4;
  p.feature_angle_deg = 42;
  p.volume = vdbwrap::VolumeChoice::Inside;
  p.threads = 3;
  p.refine_max_triangles = 7;
  p.refine_normal_spread_deg = 11;
  p.refine_at_features = false;
  p.weld_tolerance = 1e-5;
  p.surface_offset = 0.1;
  p.presmooth_iterations = 5;
  p.validity_rounds = 7;
  p.snap_features = !vdbwrap::WrapParams().snap_features;
  p.remesh = !vdbwrap::WrapParams().remesh;
  p.remove_slivers = !vdbwrap::WrapParams().remove_slivers;
  p.proximity_refinement = !vdbwrap::WrapParams().proximity_refinement;
  p.two_sided_sheets = !vdbwrap::WrapParams().two_sided_sheets;
  p.refine_far_cells = !vdbwrap::WrapParams().refine_far_cells;
  p.refine_where_far = !vdbwrap::WrapParams().refine_where_far;
  p.corner_angle_deg = 55;
  p.thin_part_levels = 3;
  p.compute_distances = false;
  vdbwrap::WrapParams q = vdbwrap::api::to_wrap_params(vdbwrap::api::to_proto(p));
  EXPECT_EQ(q.base_size.value, 0.25);
  EXPECT_FALSE(q.base_size.percent_of_diagonal);
  EXPECT_EQ(q.levels, 4);
  EXPECT_EQ(q.feature_angle_deg, 42);
  EXPECT_EQ(q.volume, vdbwrap::VolumeChoice::Inside);
  EXPECT_EQ(q.threads, 3);
  EXPECT_EQ(q.refine_max_triangles, 7);
  EXPECT_EQ(q.refine_normal_spread_deg, 11);
  EXPECT_FALSE(q.refine_at_features);
  EXPECT_EQ(q.weld_tolerance, 1e-5);
  EXPECT_EQ(q.surface_offset, 0.1);
  EXPECT_EQ(q.presmooth_iterations, 5);
  EXPECT_EQ(q.validity_rounds, 7);
  EXPECT_EQ(q.snap_features, p.snap_features);
  EXPECT_EQ(q.remesh, p.remesh);
  EXPECT_EQ(q.remove_slivers, p.remove_slivers);
  EXPECT_EQ(q.proximity_refinement, p.proximity_refinement);
  EXPECT_EQ(q.two_sided_sheets, p.two_sided_sheets);
  EXPECT_EQ(q.refine_far_cells, p.refine_far_cells);
  EXPECT_EQ(q.refine_where_far, p.refine_where_far);
  EXPECT_EQ(q.corner_angle_deg, 55);
  EXPECT_EQ(q.thin_part_levels, 3);
  EXPECT_FALSE(q.compute_distances);
  // The voxel-stage controls (issue 5), through the API and back.
  vdbwrap::WrapParams c;
  vdbwrap::parse_volume_choice("1,2,3;4,5,6", c.volume, c.seed_points);
  c.gap_closure = vdbwrap::Length{0.5, false};
  c.contact_floor = vdbwrap::Length{0.05, true};
  for (const char* cv : {"box:0,0,0,1,2,3:1%", "sphere:1,1,1,0.5:0.2", "cylinder:0,0,0,0,0,1,0.3:0.5%",
                         "cone:0,0,0,1,0,0,0.5,0.1:0.25%"})
    c.control_volumes.push_back(vdbwrap::ControlVolume::parse(cv));
  c.part_sizes.push_back(vdbwrap::PartSize::parse("wing=0.1%"));
  c.contact_prevention.push_back(vdbwrap::ContactRule::parse("a,b:c"));
  c.contact_prevention.push_back(vdbwrap::ContactRule::parse("x,y,z"));
  vdbwrap::WrapParams c2 = vdbwrap::api::to_wrap_params(vdbwrap::api::to_proto(c));
  EXPECT_EQ(c2.volume, vdbwrap::VolumeChoice::SeedPoints);
  EXPECT_EQ(c2.seed_points, c.seed_points);
  ASSERT_TRUE(c2.gap_closure && c2.contact_floor);
  EXPECT_EQ(c2.gap_closure->to_string(), "0.5");
  EXPECT_EQ(c2.contact_floor->to_string(), "0.05%");
  ASSERT_EQ(c2.control_volumes.size(), 4u);
  for (size_t i = 0; i < 4; ++i) EXPECT_EQ(c2.control_volumes[i].to_string(), c.control_volumes[i].to_string());
  ASSERT_EQ(c2.part_sizes.size(), 1u);
  EXPECT_EQ(c2.part_sizes[0].part, "wing");
  ASSERT_EQ(c2.contact_prevention.size(), 2u);
  EXPECT_EQ(c2.contact_prevention[0].to_string(), "a,b:c");
  EXPECT_EQ(c2.contact_prevention[1].to_string(), "x,y,z");
  pb::WrapParameters seeds_without_points;
  seeds_without_points.set_volume(pb::VOLUME_SEED_POINTS);
  EXPECT_THROW(vdbwrap::api::to_wrap_params(seeds_without_points), vdbwrap::Error);

  // Unset fields: the core's (the CLI's) defaults.
  vdbwrap::WrapParams d = vdbwrap::api::to_wrap_params(pb::WrapParameters());
  EXPECT_EQ(d.levels, vdbwrap::WrapParams().levels);
  EXPECT_EQ(d.base_size.value, vdbwrap::WrapParams().base_size.value);
  EXPECT_EQ(d.surface_offset, vdbwrap::WrapParams().surface_offset);
  // Out of range.
  auto refused = [](auto set) {
    return refused_by<pb::WrapParameters>([](const auto& w) { vdbwrap::api::to_wrap_params(w); }, set);
  };
  EXPECT_TRUE(refused([](pb::WrapParameters& w) { w.set_levels(7); }));
  EXPECT_TRUE(refused([](pb::WrapParameters& w) { w.set_base_size_percent(0); }));
  EXPECT_TRUE(refused([](pb::WrapParameters& w) { w.set_base_size_model_units(std::nan("")); }));
  EXPECT_TRUE(refused([](pb::WrapParameters& w) { w.set_feature_angle_deg(180); }));
  EXPECT_TRUE(refused([](pb::WrapParameters& w) { w.set_threads(-1); }));
  EXPECT_TRUE(refused([](pb::WrapParameters& w) { w.set_refine_max_triangles(0); }));
  EXPECT_TRUE(refused([](pb::WrapParameters& w) { w.set_presmooth_iterations(101); }));
  EXPECT_TRUE(refused([](pb::WrapParameters& w) { w.set_validity_rounds(-1); }));
  EXPECT_TRUE(refused([](pb::WrapParameters& w) { w.set_corner_angle_deg(0); }));
  EXPECT_TRUE(refused([](pb::WrapParameters& w) { w.set_surface_offset(0.5); }));
  EXPECT_TRUE(refused([](pb::WrapParameters& w) { w.set_volume(static_cast<pb::Volume>(9)); }));
}

TEST(ParamsMapping, RepairParametersRoundTripRefuseOutOfRangeAndMatchTheJobKind) {
  vdbwrap::RepairParams p;
  p.local_iterations = 7;
  p.alpha = 0.3;
  p.beta = 0.2;
  p.delta = 0.4;
  p.gamma = 0.002;
  p.area_ratio = 0.9;
  p.accuracy = 1e-4;
  p.refill_iterations = 2;
  p.refill_area_ratio = 0.6;
  p.fair = false;
  p.max_deviation = {0.05, false};
  p.remove_small_pieces = false;
  p.small_piece_triangles = 5;
  p.small_piece_area = 0.01;
  p.threads = 2;
  p.compute_distances = false;
  p.unite_bodies = false;
  const vdbwrap::RepairParams q = vdbwrap::api::to_repair_params(vdbwrap::api::to_proto(p));
  EXPECT_EQ(q.local_iterations, 7);
  EXPECT_EQ(q.alpha, 0.3);
  EXPECT_EQ(q.beta, 0.2);
  EXPECT_EQ(q.delta, 0.4);
  EXPECT_EQ(q.gamma, 0.002);
  EXPECT_EQ(q.area_ratio, 0.9);
  EXPECT_EQ(q.accuracy, 1e-4);
  EXPECT_EQ(q.refill_iterations, 2);
  EXPECT_EQ(q.refill_area_ratio, 0.6);
  EXPECT_FALSE(q.fair);
  EXPECT_EQ(q.max_deviation.to_string(), "0.05");
  EXPECT_FALSE(q.remove_small_pieces);
  EXPECT_EQ(q.small_piece_triangles, 5);
  EXPECT_EQ(q.small_piece_area, 0.01);
  EXPECT_EQ(q.threads, 2);
  EXPECT_FALSE(q.compute_distances);
  EXPECT_FALSE(q.unite_bodies);
  // Unset: `vdbwrap repair`'s defaults.
  const vdbwrap::RepairParams d = vdbwrap::api::to_repair_params(pb::RepairParameters());
  EXPECT_EQ(d.alpha, vdbwrap::RepairParams().alpha);
  EXPECT_EQ(d.max_deviation.to_string(), vdbwrap::RepairParams().max_deviation.to_string());
  EXPECT_TRUE(d.fair);
  EXPECT_TRUE(d.unite_bodies);
  auto refused = [](auto set) {
    return refused_by<pb::RepairParameters>([](const auto& r) { vdbwrap::api::to_repair_params(r); }, set);
  };
  EXPECT_TRUE(refused([](pb::RepairParameters& r) { r.set_alpha(1); }));
  EXPECT_TRUE(refused([](pb::RepairParameters& r) { r.set_alpha(std::nan("")); }));
  EXPECT_TRUE(refused([](pb::RepairParameters& r) { r.set_beta(0); }));
  EXPECT_TRUE(refused([](pb::RepairParameters& r) { r.set_area_ratio(1.5); }));
  EXPECT_TRUE(refused([](pb::RepairParameters& r) { r.set_local_iterations(-1); }));
  EXPECT_TRUE(refused([](pb::RepairParameters& r) { r.set_refill_iterations(101); }));
  EXPECT_TRUE(refused([](pb::RepairParameters& r) { r.set_accuracy(-1); }));
  EXPECT_TRUE(refused([](pb::RepairParameters& r) { r.set_small_piece_area(2); }));
  EXPECT_TRUE(refused([](pb::RepairParameters& r) { r.set_threads(-1); }));
  EXPECT_TRUE(refused([](pb::RepairParameters& r) { r.mutable_max_deviation()->set_percent(0); }));
  EXPECT_FALSE(refused([](pb::RepairParameters& r) { r.set_small_piece_area(0); }));
  // A job names its own kind's parameters only.
  pb::JobSpec repair_job;
  repair_job.set_kind(pb::JOB_KIND_REPAIR);
  EXPECT_NO_THROW(vdbwrap::api::check_job_parameters(repair_job));
  repair_job.mutable_params()->set_levels(2);
  EXPECT_THROW(vdbwrap::api::check_job_parameters(repair_job), vdbwrap::Error);
  pb::JobSpec wrap_job;
  EXPECT_NO_THROW(vdbwrap::api::check_job_parameters(wrap_job));
  wrap_job.mutable_repair_params()->set_alpha(0.3);
  EXPECT_THROW(vdbwrap::api::check_job_parameters(wrap_job), vdbwrap::Error);
  pb::JobSpec unknown;
  unknown.set_kind(static_cast<pb::JobKind>(9));
  EXPECT_THROW(vdbwrap::api::check_job_parameters(unknown), vdbwrap::Error);
}

}  // namespace
