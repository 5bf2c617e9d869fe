// Fuzzes the parameter texts: byte 0 picks what the rest is: a --params file (JSON or YAML,
// proto/params_file.cpp, then the API mapping) or one of the command line's text forms
// (core/params_text.cpp, core/report.cpp). Bad text must be answered with
// Error(InvalidArgument); text that is accepted must survive a round trip.
#include <google/protobuf/util/json_util.h>
#include <google/protobuf/util/message_differencer.h>

#include <cmath>
#include <cstdint>
#include <string>

#include "fuzz_check.h"
#include "params_file.h"
#include "params_mapping.h"
#include "vdbwrap/wrap.h"

using namespace vdbwrap;

namespace {

bool close(double a, double b) { return std::fabs(a - b) <= 1e-5 * std::fabs(b); }

void same_length(const Length& a, const Length& b, const char* what) {
  FUZZ_CHECK(a.percent_of_diagonal == b.percent_of_diagonal && close(a.value, b.value),
             "%s: %s does not read back (%s)", what, b.to_string().c_str(), a.to_string().c_str());
}

void params_file(const std::string& text, bool yaml) {
  api::pb::WrapParameters msg;
  WrapParams p;
  try {
    msg = api::parse_params_text(text, yaml, "fuzz");
    p = api::to_wrap_params(msg);
  } catch (const Error& e) {
    FUZZ_CHECK(e.kind() == ErrorKind::InvalidArgument, "kind %d: %s", int(e.kind()), e.what());
    return;
  }
  // What the file said must read back from the API's own JSON (a client sending it).
  std::string json;
  FUZZ_CHECK(google::protobuf::util::MessageToJsonString(msg, &json).ok(), "message does not print as JSON");
  api::pb::WrapParameters again;
  try {
    again = api::parse_params_text(json, false, "round trip");
  } catch (const Error& e) {
    FUZZ_CHECK(false, "the message's JSON %s is refused: %s", json.c_str(), e.what());
  }
  FUZZ_CHECK(google::protobuf::util::MessageDifferencer::Equals(msg, again), "JSON round trip changed %s",
             json.c_str());
  // Accepted parameters map back to the API and are accepted again, unchanged.
  const api::pb::WrapParameters out = api::to_proto(p);
  WrapParams q;
  try {
    q = api::to_wrap_params(out);
  } catch (const Error& e) {
    FUZZ_CHECK(false, "mapped parameters refused: %s", e.what());
  }
  FUZZ_CHECK(google::protobuf::util::MessageDifferencer::Equals(api::to_proto(q), out), "mapping round trip");
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size < 1) return 0;
  const std::string text(reinterpret_cast<const char*>(data) + 1, size - 1);
  switch (data[0] % 7) {
    case 0:
      params_file(text, false);
      break;
    case 1:
      params_file(text, true);
      break;
    case 2: {
      ControlVolume cv;
      if (!accepted([&] { cv = ControlVolume::parse(text); })) break;
      ControlVolume back;
      FUZZ_CHECK(accepted([&] { back = ControlVolume::parse(cv.to_string()); }), "'%s' does not read back",
                 cv.to_string().c_str());
      FUZZ_CHECK(back.shape == cv.shape && back.a == cv.a && back.b == cv.b && back.radius == cv.radius &&
                     back.radius_b == cv.radius_b,
                 "'%s' reads back as another volume", cv.to_string().c_str());
      same_length(back.size, cv.size, "control volume size");
      break;
    }
    case 3: {
      VolumeChoice choice;
      std::vector<Vec3> seeds;
      if (!accepted([&] { parse_volume_choice(text, choice, seeds); })) break;
      VolumeChoice choice2;
      std::vector<Vec3> seeds2;
      const std::string s = volume_choice_to_string(choice, seeds);
      FUZZ_CHECK(accepted([&] { parse_volume_choice(s, choice2, seeds2); }), "'%s' does not read back", s.c_str());
      FUZZ_CHECK(choice2 == choice && seeds2 == seeds, "'%s' reads back differently", s.c_str());
      break;
    }
    case 4: {
      ContactRule rule;
      if (!accepted([&] { rule = ContactRule::parse(text); })) break;
      ContactRule back;
      const std::string s = rule.to_string();
      FUZZ_CHECK(accepted([&] { back = ContactRule::parse(s); }), "'%s' does not read back", s.c_str());
      FUZZ_CHECK(back.groups == rule.groups, "'%s' reads back differently", s.c_str());
      break;
    }
    case 5: {
      PartSize ps;
      if (!accepted([&] { ps = PartSize::parse(text); })) break;
      // The API refuses an empty part name (params_mapping.cpp); the text form must as well.
      FUZZ_CHECK(!ps.part.empty(), "'%s': empty part name accepted", text.c_str());
      FUZZ_CHECK(ps.size.value > 0 && std::isfinite(ps.size.value), "size %g accepted", ps.size.value);
      break;
    }
    case 6: {
      Length len;
      if (!accepted([&] { len = Length::parse(text); })) break;
      FUZZ_CHECK(len.value > 0 && std::isfinite(len.value), "length %g accepted", len.value);
      Length back;
      const std::string s = len.to_string();
      FUZZ_CHECK(accepted([&] { back = Length::parse(s); }), "'%s' does not read back", s.c_str());
      same_length(back, len, "length");
      break;
    }
  }
  return 0;
}
