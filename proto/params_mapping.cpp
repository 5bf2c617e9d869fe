#include "params_mapping.h"

#include <cmath>

namespace vdbwrap::api {

namespace {

[[noreturn]] void bad(const std::string& field, const std::string& what) {
  throw Error(ErrorKind::InvalidArgument, "parameter " + field + ": " + what);
}

double finite(const std::string& field, double v) {
  if (!std::isfinite(v)) bad(field, "must be a finite number");
  return v;
}

Length to_length(const std::string& field, const pb::Size& size) {
  switch (size.value_case()) {
    case pb::Size::kPercent:
      if (!(finite(field, size.percent()) > 0)) bad(field, "must be positive");
      return Length{size.percent(), true};
    case pb::Size::kModelUnits:
      if (!(finite(field, size.model_units()) > 0)) bad(field, "must be positive");
      return Length{size.model_units(), false};
    case pb::Size::VALUE_NOT_SET:
      break;
  }
  bad(field, "set percent or model_units");
}

pb::Size to_proto_size(const Length& l) {
  pb::Size s;
  if (l.percent_of_diagonal)
    s.set_percent(l.value);
  else
    s.set_model_units(l.value);
  return s;
}

pb::Point to_proto_point(const Vec3& v) {
  pb::Point p;
  p.set_x(v[0]), p.set_y(v[1]), p.set_z(v[2]);
  return p;
}

}  // namespace

WrapParams to_wrap_params(const pb::WrapParameters& in) {
  WrapParams p;  // the CLI's defaults
  switch (in.base_size_case()) {
    case pb::WrapParameters::kBaseSizePercent:
      p.base_size = Length{finite("base_size_percent", in.base_size_percent()), true};
      break;
    case pb::WrapParameters::kBaseSizeModelUnits:
      p.base_size = Length{finite("base_size_model_units", in.base_size_model_units()), false};
      break;
    case pb::WrapParameters::BASE_SIZE_NOT_SET:
      break;
  }
  if (in.has_levels()) p.levels = in.levels();
  if (in.has_thin_part_levels()) p.thin_part_levels = in.thin_part_levels();
  if (in.has_feature_angle_deg()) p.feature_angle_deg = in.feature_angle_deg();
  switch (in.volume()) {
    case pb::VOLUME_UNSPECIFIED:
    case pb::VOLUME_OUTSIDE:
      p.volume = VolumeChoice::Outside;
      break;
    case pb::VOLUME_INSIDE:
      p.volume = VolumeChoice::Inside;
      break;
    case pb::VOLUME_SEED_POINTS:
      p.volume = VolumeChoice::SeedPoints;
      break;
    default:
      bad("volume", "unknown value " + std::to_string(int(in.volume())));
  }
  for (const auto& s : in.seed_points())
    p.seed_points.push_back({finite("seed_points", s.x()), finite("seed_points", s.y()), finite("seed_points", s.z())});
  if (in.has_gap_closure()) p.gap_closure = to_length("gap_closure", in.gap_closure());
  if (in.has_contact_floor()) p.contact_floor = to_length("contact_floor", in.contact_floor());
  for (const auto& c : in.control_volumes()) {
    ControlVolume cv;
    switch (c.shape()) {
      case pb::ControlVolume::SHAPE_BOX:
        cv.shape = ControlVolume::Shape::Box;
        break;
      case pb::ControlVolume::SHAPE_SPHERE:
        cv.shape = ControlVolume::Shape::Sphere;
        break;
      case pb::ControlVolume::SHAPE_CYLINDER:
        cv.shape = ControlVolume::Shape::Cylinder;
        break;
      case pb::ControlVolume::SHAPE_CONE:
        cv.shape = ControlVolume::Shape::Cone;
        break;
      default:
        bad("control_volumes", "shape must be SHAPE_BOX, SHAPE_SPHERE, SHAPE_CYLINDER or SHAPE_CONE");
    }
    cv.a = {finite("control_volumes.a", c.a().x()), finite("control_volumes.a", c.a().y()),
            finite("control_volumes.a", c.a().z())};
    cv.b = {finite("control_volumes.b", c.b().x()), finite("control_volumes.b", c.b().y()),
            finite("control_volumes.b", c.b().z())};
    if (cv.shape == ControlVolume::Shape::Sphere) cv.b = cv.a;
    if (cv.shape == ControlVolume::Shape::Box)
      for (int k = 0; k < 3; ++k)
        if (cv.a[k] > cv.b[k]) std::swap(cv.a[k], cv.b[k]);
    cv.radius = finite("control_volumes.radius", c.radius());
    cv.radius_b = cv.shape == ControlVolume::Shape::Cone ? finite("control_volumes.radius_b", c.radius_b()) : cv.radius;
    if ((cv.shape == ControlVolume::Shape::Cylinder || cv.shape == ControlVolume::Shape::Cone) && cv.a == cv.b)
      bad("control_volumes", "the axis a -> b has zero length");
    if (!c.has_size()) bad("control_volumes", "size is required");
    cv.size = to_length("control_volumes.size", c.size());
    cv.name = cv.to_string();
    p.control_volumes.push_back(cv);
  }
  for (const auto& ps : in.part_sizes()) {
    if (!ps.has_size()) bad("part_sizes", "size is required");
    p.part_sizes.push_back({ps.part(), to_length("part_sizes.size", ps.size())});
  }
  for (const auto& rule : in.contact_prevention()) {
    ContactRule r;
    for (const auto& g : rule.groups()) {
      r.groups.emplace_back(g.parts().begin(), g.parts().end());
      if (g.parts().empty()) bad("contact_prevention", "a group has no parts");
    }
    p.contact_prevention.push_back(std::move(r));
  }
  if (in.has_threads()) p.threads = in.threads();
  if (in.has_refine_max_triangles()) p.refine_max_triangles = in.refine_max_triangles();
  if (in.has_refine_normal_spread_deg()) p.refine_normal_spread_deg = in.refine_normal_spread_deg();
  if (in.has_presmooth_iterations()) p.presmooth_iterations = in.presmooth_iterations();
  if (in.has_validity_rounds()) p.validity_rounds = in.validity_rounds();
  if (in.has_snap_features()) p.snap_features = in.snap_features();
  if (in.has_remesh()) p.remesh = in.remesh();
  if (in.has_remove_slivers()) p.remove_slivers = in.remove_slivers();
  if (in.has_proximity_refinement()) p.proximity_refinement = in.proximity_refinement();
  if (in.has_two_sided_sheets()) p.two_sided_sheets = in.two_sided_sheets();
  if (in.has_refine_far_cells()) p.refine_far_cells = in.refine_far_cells();
  if (in.has_refine_held_back()) p.refine_where_far = in.refine_held_back();
  if (in.has_corner_angle_deg()) p.corner_angle_deg = in.corner_angle_deg();
  if (in.has_refine_at_features()) p.refine_at_features = in.refine_at_features();
  if (in.has_weld_tolerance()) p.weld_tolerance = in.weld_tolerance();
  if (in.has_surface_offset()) p.surface_offset = in.surface_offset();
  if (in.has_compute_distances()) p.compute_distances = in.compute_distances();
  if (in.has_coarsen_tolerance()) p.coarsen_tolerance = in.coarsen_tolerance();
  validate(p);  // the ranges: one check for every way in
  return p;
}

pb::WrapParameters to_proto(const WrapParams& in) {
  pb::WrapParameters out;
  if (in.base_size.percent_of_diagonal)
    out.set_base_size_percent(in.base_size.value);
  else
    out.set_base_size_model_units(in.base_size.value);
  out.set_levels(in.levels);
  out.set_thin_part_levels(in.thin_part_levels);
  out.set_feature_angle_deg(in.feature_angle_deg);
  out.set_volume(in.volume == VolumeChoice::Inside       ? pb::VOLUME_INSIDE
                 : in.volume == VolumeChoice::SeedPoints ? pb::VOLUME_SEED_POINTS
                                                         : pb::VOLUME_OUTSIDE);
  for (const Vec3& s : in.seed_points) *out.add_seed_points() = to_proto_point(s);
  if (in.gap_closure) *out.mutable_gap_closure() = to_proto_size(*in.gap_closure);
  if (in.contact_floor) *out.mutable_contact_floor() = to_proto_size(*in.contact_floor);
  for (const ControlVolume& cv : in.control_volumes) {
    auto* c = out.add_control_volumes();
    switch (cv.shape) {
      case ControlVolume::Shape::Box:
        c->set_shape(pb::ControlVolume::SHAPE_BOX);
        break;
      case ControlVolume::Shape::Sphere:
        c->set_shape(pb::ControlVolume::SHAPE_SPHERE);
        break;
      case ControlVolume::Shape::Cylinder:
        c->set_shape(pb::ControlVolume::SHAPE_CYLINDER);
        break;
      case ControlVolume::Shape::Cone:
        c->set_shape(pb::ControlVolume::SHAPE_CONE);
        break;
    }
    *c->mutable_a() = to_proto_point(cv.a);
    *c->mutable_b() = to_proto_point(cv.b);
    c->set_radius(cv.radius);
    c->set_radius_b(cv.radius_b);
    *c->mutable_size() = to_proto_size(cv.size);
  }
  for (const PartSize& ps : in.part_sizes) {
    auto* s = out.add_part_sizes();
    s->set_part(ps.part);
    *s->mutable_size() = to_proto_size(ps.size);
  }
  for (const ContactRule& r : in.contact_prevention) {
    auto* rule = out.add_contact_prevention();
    for (const auto& g : r.groups) {
      auto* group = rule->add_groups();
      for (const auto& name : g) group->add_parts(name);
    }
  }
  out.set_threads(in.threads);
  out.set_refine_max_triangles(in.refine_max_triangles);
  out.set_refine_normal_spread_deg(in.refine_normal_spread_deg);
  out.set_presmooth_iterations(in.presmooth_iterations);
  out.set_validity_rounds(in.validity_rounds);
  out.set_snap_features(in.snap_features);
  out.set_corner_angle_deg(in.corner_angle_deg);
  out.set_refine_at_features(in.refine_at_features);
  out.set_weld_tolerance(in.weld_tolerance);
  out.set_surface_offset(in.surface_offset);
  out.set_compute_distances(in.compute_distances);
  out.set_coarsen_tolerance(in.coarsen_tolerance);
  out.set_remesh(in.remesh);
  out.set_remove_slivers(in.remove_slivers);
  out.set_proximity_refinement(in.proximity_refinement);
  out.set_two_sided_sheets(in.two_sided_sheets);
  out.set_refine_far_cells(in.refine_far_cells);
  out.set_refine_held_back(in.refine_where_far);
  return out;
}

RepairParams to_repair_params(const pb::RepairParameters& in) {
  RepairParams p;  // `vdbwrap repair`'s defaults
  auto fraction = [](const std::string& field, double v, bool zero_ok, bool one_ok) {
    if (!std::isfinite(v) || !((zero_ok ? v >= 0 : v > 0) && (one_ok ? v <= 1 : v < 1)))
      bad(field, std::string("must be in ") + (zero_ok ? "[0" : "(0") + ", 1" + (one_ok ? "]" : ")"));
    return v;
  };
  auto positive = [](const std::string& field, double v) {
    if (!(finite(field, v) > 0)) bad(field, "must be positive");
    return v;
  };
  if (in.has_local_iterations()) {
    if (in.local_iterations() < 0 || in.local_iterations() > 1000)
      bad("local_iterations", "must be between 0 and 1000");
    p.local_iterations = in.local_iterations();
  }
  if (in.has_alpha()) p.alpha = fraction("alpha", in.alpha(), false, false);
  if (in.has_beta()) p.beta = positive("beta", in.beta());
  if (in.has_delta()) p.delta = positive("delta", in.delta());
  if (in.has_gamma()) p.gamma = positive("gamma", in.gamma());
  if (in.has_area_ratio()) p.area_ratio = fraction("area_ratio", in.area_ratio(), false, true);
  if (in.has_accuracy()) {
    if (!(finite("accuracy", in.accuracy()) >= 0)) bad("accuracy", "must be 0 (automatic) or positive");
    p.accuracy = in.accuracy();
  }
  if (in.has_refill_iterations()) {
    if (in.refill_iterations() < 0 || in.refill_iterations() > 100)
      bad("refill_iterations", "must be between 0 and 100");
    p.refill_iterations = in.refill_iterations();
  }
  if (in.has_refill_area_ratio())
    p.refill_area_ratio = fraction("refill_area_ratio", in.refill_area_ratio(), false, true);
  if (in.has_fair()) p.fair = in.fair();
  if (in.has_max_deviation()) p.max_deviation = to_length("max_deviation", in.max_deviation());
  if (in.has_remove_small_pieces()) p.remove_small_pieces = in.remove_small_pieces();
  if (in.has_small_piece_triangles()) {
    if (in.small_piece_triangles() < 0) bad("small_piece_triangles", "must not be negative");
    p.small_piece_triangles = in.small_piece_triangles();
  }
  if (in.has_small_piece_area()) p.small_piece_area = fraction("small_piece_area", in.small_piece_area(), true, true);
  if (in.has_threads()) {
    if (in.threads() < 0) bad("threads", "must be 0 (all cores) or more");
    p.threads = in.threads();
  }
  if (in.has_compute_distances()) p.compute_distances = in.compute_distances();
  if (in.has_unite_bodies()) p.unite_bodies = in.unite_bodies();
  return p;
}

pb::RepairParameters to_proto(const RepairParams& in) {
  pb::RepairParameters out;
  out.set_local_iterations(in.local_iterations);
  out.set_alpha(in.alpha);
  out.set_beta(in.beta);
  out.set_delta(in.delta);
  out.set_gamma(in.gamma);
  out.set_area_ratio(in.area_ratio);
  out.set_accuracy(in.accuracy);
  out.set_refill_iterations(in.refill_iterations);
  out.set_refill_area_ratio(in.refill_area_ratio);
  out.set_fair(in.fair);
  *out.mutable_max_deviation() = to_proto_size(in.max_deviation);
  out.set_remove_small_pieces(in.remove_small_pieces);
  out.set_small_piece_triangles(in.small_piece_triangles);
  out.set_small_piece_area(in.small_piece_area);
  out.set_threads(in.threads);
  out.set_compute_distances(in.compute_distances);
  out.set_unite_bodies(in.unite_bodies);
  return out;
}

bool is_repair(const pb::JobSpec& spec) { return spec.kind() == pb::JOB_KIND_REPAIR; }

void check_job_parameters(const pb::JobSpec& spec) {
  switch (spec.kind()) {
    case pb::JOB_KIND_UNSPECIFIED:
    case pb::JOB_KIND_WRAP:
      if (spec.has_repair_params())
        bad("repair_params", "given, but the job is a wrap (kind JOB_KIND_REPAIR for a repair)");
      to_wrap_params(spec.params());
      return;
    case pb::JOB_KIND_REPAIR:
      if (spec.has_params()) bad("params", "given, but the job is a repair (use repair_params)");
      to_repair_params(spec.repair_params());
      return;
    default:
      bad("kind", "unknown value " + std::to_string(int(spec.kind())));
  }
}

io::Format to_io_format(pb::MeshFormat format) {
  switch (format) {
    case pb::MESH_FORMAT_STL:
      return io::Format::Stl;
    case pb::MESH_FORMAT_OBJ:
      return io::Format::Obj;
    case pb::MESH_FORMAT_OFF:
      return io::Format::Off;
    case pb::MESH_FORMAT_PLY:
      return io::Format::Ply;
    case pb::MESH_FORMAT_VTP:
      return io::Format::Vtp;
    case pb::MESH_FORMAT_NASTRAN:
      return io::Format::Nastran;
    default:
      return io::Format::Unknown;
  }
}

pb::MeshFormat to_proto_format(io::Format format) {
  switch (format) {
    case io::Format::Stl:
      return pb::MESH_FORMAT_STL;
    case io::Format::Obj:
      return pb::MESH_FORMAT_OBJ;
    case io::Format::Off:
      return pb::MESH_FORMAT_OFF;
    case io::Format::Ply:
      return pb::MESH_FORMAT_PLY;
    case io::Format::Vtp:
      return pb::MESH_FORMAT_VTP;
    case io::Format::Nastran:
      return pb::MESH_FORMAT_NASTRAN;
    case io::Format::Unknown:
      break;
  }
  return pb::MESH_FORMAT_UNSPECIFIED;
}

std::string extension_of(pb::MeshFormat format) {
  switch (format) {
    case pb::MESH_FORMAT_STL:
      return "stl";
    case pb::MESH_FORMAT_OBJ:
      return "obj";
    case pb::MESH_FORMAT_OFF:
      return "off";
    case pb::MESH_FORMAT_PLY:
      return "ply";
    case pb::MESH_FORMAT_VTP:
      return "vtp";
    case pb::MESH_FORMAT_NASTRAN:
      return "nas";
    default:
      return "";
  }
}

pb::MeshFormat format_from_file_name(const std::string& file_name) {
  return to_proto_format(io::format_from_extension(file_name));
}

pb::ErrorKind to_proto(ErrorKind kind) {
  switch (kind) {
    case ErrorKind::Internal:
      return pb::ERROR_KIND_INTERNAL;
    case ErrorKind::InvalidArgument:
      return pb::ERROR_KIND_INVALID_ARGUMENT;
    case ErrorKind::InvalidInput:
      return pb::ERROR_KIND_INVALID_INPUT;
    case ErrorKind::WrapFailed:
      return pb::ERROR_KIND_WRAP_FAILED;
    case ErrorKind::OutputFailed:
      return pb::ERROR_KIND_OUTPUT_FAILED;
    case ErrorKind::Cancelled:
      return pb::ERROR_KIND_CANCELLED;
  }
  return pb::ERROR_KIND_INTERNAL;
}

ErrorKind to_error_kind(pb::ErrorKind kind) {
  switch (kind) {
    case pb::ERROR_KIND_INVALID_ARGUMENT:
      return ErrorKind::InvalidArgument;
    case pb::ERROR_KIND_INVALID_INPUT:
      return ErrorKind::InvalidInput;
    case pb::ERROR_KIND_WRAP_FAILED:
      return ErrorKind::WrapFailed;
    case pb::ERROR_KIND_OUTPUT_FAILED:
      return ErrorKind::OutputFailed;
    case pb::ERROR_KIND_CANCELLED:
      return ErrorKind::Cancelled;
    default:
      return ErrorKind::Internal;
  }
}

const char* state_name(pb::JobState state) {
  switch (state) {
    case pb::JOB_STATE_QUEUED:
      return "queued";
    case pb::JOB_STATE_RUNNING:
      return "running";
    case pb::JOB_STATE_SUCCEEDED:
      return "succeeded";
    case pb::JOB_STATE_FAILED:
      return "failed";
    case pb::JOB_STATE_CANCELLED:
      return "cancelled";
    default:
      return "unknown";
  }
}

bool is_final(pb::JobState state) {
  return state == pb::JOB_STATE_SUCCEEDED || state == pb::JOB_STATE_FAILED || state == pb::JOB_STATE_CANCELLED;
}

grpc::StatusCode status_code_for(ErrorKind kind) {
  switch (kind) {
    case ErrorKind::InvalidArgument:
    case ErrorKind::InvalidInput:
      return grpc::StatusCode::INVALID_ARGUMENT;
    case ErrorKind::Cancelled:
      return grpc::StatusCode::CANCELLED;
    default:
      return grpc::StatusCode::INTERNAL;
  }
}

}  // namespace vdbwrap::api
