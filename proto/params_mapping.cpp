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

}  // namespace

WrapParams to_wrap_params(const pb::WrapParameters& in) {
  WrapParams p;  // the CLI's defaults
  switch (in.base_size_case()) {
    case pb::WrapParameters::kBaseSizePercent:
      p.base_size = Length{finite("base_size_percent", in.base_size_percent()), true};
      if (!(p.base_size.value > 0)) bad("base_size_percent", "must be positive");
      break;
    case pb::WrapParameters::kBaseSizeModelUnits:
      p.base_size = Length{finite("base_size_model_units", in.base_size_model_units()), false};
      if (!(p.base_size.value > 0)) bad("base_size_model_units", "must be positive");
      break;
    case pb::WrapParameters::BASE_SIZE_NOT_SET:
      break;
  }
  if (in.has_levels()) {
    if (in.levels() < 0 || in.levels() > 6) bad("levels", "must be between 0 and 6");
    p.levels = in.levels();
  }
  if (in.has_feature_angle_deg()) {
    double a = finite("feature_angle_deg", in.feature_angle_deg());
    if (!(a > 0 && a < 180)) bad("feature_angle_deg", "must be strictly between 0 and 180 degrees");
    p.feature_angle_deg = a;
  }
  switch (in.volume()) {
    case pb::VOLUME_UNSPECIFIED:
    case pb::VOLUME_OUTSIDE: p.volume = VolumeChoice::Outside; break;
    case pb::VOLUME_INSIDE: p.volume = VolumeChoice::Inside; break;
    default: bad("volume", "unknown value " + std::to_string(int(in.volume())));
  }
  if (in.has_threads()) {
    if (in.threads() < 0) bad("threads", "must be 0 (all cores) or more");
    p.threads = in.threads();
  }
  if (in.has_refine_max_triangles()) {
    if (in.refine_max_triangles() < 1) bad("refine_max_triangles", "must be at least 1");
    p.refine_max_triangles = in.refine_max_triangles();
  }
  if (in.has_refine_normal_spread_deg()) {
    double a = finite("refine_normal_spread_deg", in.refine_normal_spread_deg());
    if (!(a >= 0 && a <= 180)) bad("refine_normal_spread_deg", "must be between 0 and 180 degrees");
    p.refine_normal_spread_deg = a;
  }
  if (in.has_presmooth_iterations()) {
    if (in.presmooth_iterations() < 0 || in.presmooth_iterations() > 100) bad("presmooth_iterations", "must be between 0 and 100");
    p.presmooth_iterations = in.presmooth_iterations();
  }
  if (in.has_snap_features()) p.snap_features = in.snap_features();
  if (in.has_corner_angle_deg()) {
    double a = finite("corner_angle_deg", in.corner_angle_deg());
    if (!(a > 0 && a < 180)) bad("corner_angle_deg", "must be strictly between 0 and 180 degrees");
    p.corner_angle_deg = a;
  }
  if (in.has_refine_at_features()) p.refine_at_features = in.refine_at_features();
  if (in.has_weld_tolerance()) {
    double w = finite("weld_tolerance", in.weld_tolerance());
    if (!(w >= 0 && w < 0.01)) bad("weld_tolerance", "must be in [0, 0.01) of the diagonal");
    p.weld_tolerance = w;
  }
  if (in.has_surface_offset()) {
    double s = finite("surface_offset", in.surface_offset());
    if (!(s >= 0 && s < 0.5)) bad("surface_offset", "must be in [0, 0.5) of the finest cell");
    p.surface_offset = s;
  }
  if (in.has_compute_distances()) p.compute_distances = in.compute_distances();
  return p;
}

pb::WrapParameters to_proto(const WrapParams& in) {
  pb::WrapParameters out;
  if (in.base_size.percent_of_diagonal)
    out.set_base_size_percent(in.base_size.value);
  else
    out.set_base_size_model_units(in.base_size.value);
  out.set_levels(in.levels);
  out.set_feature_angle_deg(in.feature_angle_deg);
  out.set_volume(in.volume == VolumeChoice::Inside ? pb::VOLUME_INSIDE : pb::VOLUME_OUTSIDE);
  out.set_threads(in.threads);
  out.set_refine_max_triangles(in.refine_max_triangles);
  out.set_refine_normal_spread_deg(in.refine_normal_spread_deg);
  out.set_presmooth_iterations(in.presmooth_iterations);
  out.set_snap_features(in.snap_features);
  out.set_corner_angle_deg(in.corner_angle_deg);
  out.set_refine_at_features(in.refine_at_features);
  out.set_weld_tolerance(in.weld_tolerance);
  out.set_surface_offset(in.surface_offset);
  out.set_compute_distances(in.compute_distances);
  return out;
}

io::Format to_io_format(pb::MeshFormat format) {
  switch (format) {
    case pb::MESH_FORMAT_STL: return io::Format::Stl;
    case pb::MESH_FORMAT_OBJ: return io::Format::Obj;
    case pb::MESH_FORMAT_OFF: return io::Format::Off;
    case pb::MESH_FORMAT_PLY: return io::Format::Ply;
    default: return io::Format::Unknown;
  }
}

pb::MeshFormat to_proto_format(io::Format format) {
  switch (format) {
    case io::Format::Stl: return pb::MESH_FORMAT_STL;
    case io::Format::Obj: return pb::MESH_FORMAT_OBJ;
    case io::Format::Off: return pb::MESH_FORMAT_OFF;
    case io::Format::Ply: return pb::MESH_FORMAT_PLY;
    case io::Format::Unknown: break;
  }
  return pb::MESH_FORMAT_UNSPECIFIED;
}

std::string extension_of(pb::MeshFormat format) {
  switch (format) {
    case pb::MESH_FORMAT_STL: return "stl";
    case pb::MESH_FORMAT_OBJ: return "obj";
    case pb::MESH_FORMAT_OFF: return "off";
    case pb::MESH_FORMAT_PLY: return "ply";
    default: return "";
  }
}

pb::MeshFormat format_from_file_name(const std::string& file_name) {
  return to_proto_format(io::format_from_extension(file_name));
}

pb::ErrorKind to_proto(ErrorKind kind) {
  switch (kind) {
    case ErrorKind::Internal: return pb::ERROR_KIND_INTERNAL;
    case ErrorKind::InvalidArgument: return pb::ERROR_KIND_INVALID_ARGUMENT;
    case ErrorKind::InvalidInput: return pb::ERROR_KIND_INVALID_INPUT;
    case ErrorKind::WrapFailed: return pb::ERROR_KIND_WRAP_FAILED;
    case ErrorKind::OutputFailed: return pb::ERROR_KIND_OUTPUT_FAILED;
    case ErrorKind::Cancelled: return pb::ERROR_KIND_CANCELLED;
  }
  return pb::ERROR_KIND_INTERNAL;
}

ErrorKind to_error_kind(pb::ErrorKind kind) {
  switch (kind) {
    case pb::ERROR_KIND_INVALID_ARGUMENT: return ErrorKind::InvalidArgument;
    case pb::ERROR_KIND_INVALID_INPUT: return ErrorKind::InvalidInput;
    case pb::ERROR_KIND_WRAP_FAILED: return ErrorKind::WrapFailed;
    case pb::ERROR_KIND_OUTPUT_FAILED: return ErrorKind::OutputFailed;
    case pb::ERROR_KIND_CANCELLED: return ErrorKind::Cancelled;
    default: return ErrorKind::Internal;
  }
}

const char* state_name(pb::JobState state) {
  switch (state) {
    case pb::JOB_STATE_QUEUED: return "queued";
    case pb::JOB_STATE_RUNNING: return "running";
    case pb::JOB_STATE_SUCCEEDED: return "succeeded";
    case pb::JOB_STATE_FAILED: return "failed";
    case pb::JOB_STATE_CANCELLED: return "cancelled";
    default: return "unknown";
  }
}

bool is_final(pb::JobState state) {
  return state == pb::JOB_STATE_SUCCEEDED || state == pb::JOB_STATE_FAILED || state == pb::JOB_STATE_CANCELLED;
}

grpc::StatusCode status_code_for(ErrorKind kind) {
  switch (kind) {
    case ErrorKind::InvalidArgument:
    case ErrorKind::InvalidInput: return grpc::StatusCode::INVALID_ARGUMENT;
    case ErrorKind::Cancelled: return grpc::StatusCode::CANCELLED;
    default: return grpc::StatusCode::INTERNAL;
  }
}

}  // namespace vdbwrap::api
