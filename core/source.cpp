#include "vdbwrap/source.h"

#include <nlohmann/json.hpp>

#include <algorithm>

#include "source_json.h"
#include "vdbwrap/errors.h"

namespace vdbwrap {
namespace {

// JSON holds UTF-8 only, and a client's file name or a part name may be Latin-1: such bytes
// become U+FFFD (as the JSON writer's own replacement does) instead of failing the report.
std::string as_utf8(const std::string& s) {
  using nlohmann::json;
  return json::parse(json(s).dump(-1, ' ', false, json::error_handler_t::replace)).get<std::string>();
}

}  // namespace

const char* version() { return VDBWRAP_VERSION; }

WrapReport::Source source_of(const std::string& input_name, const Mesh& mesh) {
  WrapReport::Source src;
  src.tool_version = version();
  const size_t slash = input_name.find_last_of("/\\");
  src.file_name = as_utf8(slash == std::string::npos ? input_name : input_name.substr(slash + 1));
  std::vector<size_t> counts(std::max<size_t>(mesh.part_names.size(), 1), 0);
  for (size_t t = 0; t < mesh.triangles.size(); ++t) {
    const int32_t p = mesh.part_of(t);
    if (p < 0) continue;
    if (size_t(p) >= counts.size()) counts.resize(size_t(p) + 1, 0);
    ++counts[size_t(p)];
  }
  for (size_t p = 0; p < counts.size(); ++p)
    src.parts.emplace_back(p < mesh.part_names.size() ? as_utf8(mesh.part_names[p]) : std::string(), counts[p]);
  for (const std::string& note : mesh.notes) src.notes.push_back(as_utf8(note));
  return src;
}

std::string with_source(const std::string& report_json, const WrapReport::Source& src) {
  nlohmann::json j = nlohmann::json::parse(report_json, nullptr, false);
  if (!j.is_object()) throw Error(ErrorKind::Internal, "with_source: the report is not a JSON object");
  j["vdbwrap_version"] = src.tool_version;
  j["source"] = source_json(src);
  return j.dump(2);
}

}  // namespace vdbwrap
