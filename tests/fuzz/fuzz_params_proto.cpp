// Fuzzes the gRPC parameter mapping (proto/params_mapping.cpp): byte 0 picks the message
// (WrapParameters, RepairParameters or a whole JobSpec), the rest is its wire encoding, as a
// client could send it. Values out of range must be refused with Error(InvalidArgument);
// accepted values must map back to the API and be accepted again, unchanged.
#include <google/protobuf/util/message_differencer.h>

#include <cmath>
#include <cstdint>

#include "fuzz_check.h"
#include "params_mapping.h"

using namespace vdbwrap;
using google::protobuf::util::MessageDifferencer;

namespace {

bool finite(const Vec3& v) { return std::isfinite(v[0]) && std::isfinite(v[1]) && std::isfinite(v[2]); }

// The ranges wrap() itself checks: what the mapping accepts must not be refused later.
void check_wrap_ranges(const WrapParams& p) {
  FUZZ_CHECK(p.base_size.value > 0 && std::isfinite(p.base_size.value), "base size %g", p.base_size.value);
  FUZZ_CHECK(p.levels >= 0 && p.levels <= 6, "levels %d", p.levels);
  FUZZ_CHECK(p.threads >= 0, "threads %d", p.threads);
  for (const Vec3& s : p.seed_points) FUZZ_CHECK(finite(s), "non-finite seed point");
  FUZZ_CHECK((p.volume == VolumeChoice::SeedPoints) == !p.seed_points.empty(), "seed points and volume disagree");
  for (const ControlVolume& cv : p.control_volumes) {
    FUZZ_CHECK(finite(cv.a) && finite(cv.b), "non-finite control volume");
    FUZZ_CHECK(cv.radius >= 0 && cv.radius_b >= 0, "negative radius");
    FUZZ_CHECK(cv.size.value > 0 && std::isfinite(cv.size.value), "control volume size %g", cv.size.value);
  }
  for (const PartSize& ps : p.part_sizes) FUZZ_CHECK(!ps.part.empty() && ps.size.value > 0, "part size");
  if (p.gap_closure) FUZZ_CHECK(p.gap_closure->value > 0 && std::isfinite(p.gap_closure->value), "gap closure");
  if (p.contact_floor) FUZZ_CHECK(p.contact_floor->value > 0 && std::isfinite(p.contact_floor->value), "floor");
}

void wrap_parameters(const api::pb::WrapParameters& msg) {
  WrapParams p;
  if (!accepted([&] { p = api::to_wrap_params(msg); })) return;
  check_wrap_ranges(p);
  const api::pb::WrapParameters out = api::to_proto(p);
  WrapParams q;
  FUZZ_CHECK(accepted([&] { q = api::to_wrap_params(out); }), "mapped wrap parameters refused");
  FUZZ_CHECK(MessageDifferencer::Equals(api::to_proto(q), out), "wrap mapping round trip changed %s",
             out.ShortDebugString().c_str());
}

void repair_parameters(const api::pb::RepairParameters& msg) {
  RepairParams p;
  if (!accepted([&] { p = api::to_repair_params(msg); })) return;
  const api::pb::RepairParameters out = api::to_proto(p);
  RepairParams q;
  FUZZ_CHECK(accepted([&] { q = api::to_repair_params(out); }), "mapped repair parameters refused");
  FUZZ_CHECK(MessageDifferencer::Equals(api::to_proto(q), out), "repair mapping round trip changed %s",
             out.ShortDebugString().c_str());
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size < 1) return 0;
  const void* wire = data + 1;
  const int n = int(size - 1);
  switch (data[0] % 3) {
    case 0: {
      api::pb::WrapParameters msg;
      if (msg.ParseFromArray(wire, n)) wrap_parameters(msg);
      break;
    }
    case 1: {
      api::pb::RepairParameters msg;
      if (msg.ParseFromArray(wire, n)) repair_parameters(msg);
      break;
    }
    case 2: {
      api::pb::JobSpec spec;
      if (!spec.ParseFromArray(wire, n)) break;
      if (!accepted([&] { api::check_job_parameters(spec); })) break;
      if (api::is_repair(spec))
        repair_parameters(spec.repair_params());
      else
        wrap_parameters(spec.params());
      // Formats and names the server derives from a spec.
      (void)api::to_io_format(spec.input_format());
      (void)api::extension_of(spec.output_format());
      (void)api::format_from_file_name(spec.file_name());
      break;
    }
  }
  return 0;
}
