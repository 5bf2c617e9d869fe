#include "params_file.h"

#include <google/protobuf/util/json_util.h>
#include <yaml-cpp/yaml.h>

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cctype>
#include <charconv>
#include <fstream>
#include <sstream>

#include "params_mapping.h"

namespace vdbwrap::api {
namespace {

using nlohmann::json;

[[noreturn]] void bad(const std::string& name, const std::string& what) {
  throw Error(ErrorKind::InvalidArgument, name + ": " + what);
}

// A WrapParameters message is a few levels deep. Deeper text is refused while it is read:
// printing a deeply nested JSON array overflowed the stack (issue 33).
constexpr int kMaxDepth = 32;

[[noreturn]] void too_deep(const std::string& name) {
  bad(name, "nested more than " + std::to_string(kMaxDepth) + " levels deep (not a WrapParameters message)");
}

// YAML aliases repeat a node wherever they appear: a few lines of nested aliases expand to
// billions of values (exhausting memory, issue 33). Far more values than any parameter file has
// are refused.
constexpr size_t kMaxYamlValues = 100000;

struct YamlBudget {
  const std::string& name;
  size_t values = 0;
};

// YAML scalars carry no type: numbers and booleans are recognised, the rest are strings.
json yaml_to_json(const YAML::Node& node, YamlBudget& budget, int depth = 0) {
  if (depth > kMaxDepth) too_deep(budget.name);
  if (++budget.values > kMaxYamlValues)
    bad(budget.name, "more than " + std::to_string(kMaxYamlValues) + " values once its aliases are expanded");
  switch (node.Type()) {
    case YAML::NodeType::Map: {
      json j = json::object();
      for (const auto& kv : node) j[kv.first.as<std::string>()] = yaml_to_json(kv.second, budget, depth + 1);
      return j;
    }
    case YAML::NodeType::Sequence: {
      json j = json::array();
      for (const auto& v : node) j.push_back(yaml_to_json(v, budget, depth + 1));
      return j;
    }
    case YAML::NodeType::Scalar: {
      const std::string s = node.Scalar();
      if (node.Tag() == "!") return s;  // quoted: a string
      if (s == "true" || s == "True") return true;
      if (s == "false" || s == "False") return false;
      double v = 0;
      auto [end, ec] = std::from_chars(s.data(), s.data() + s.size(), v);
      if (!s.empty() && ec == std::errc() && end == s.data() + s.size()) return v;
      return s;
    }
    default:
      return nullptr;
  }
}

std::string upper(std::string s) {
  std::transform(s.begin(), s.end(), s.begin(), [](unsigned char c) { return char(std::toupper(c)); });
  return s;
}

// The short enum spellings of the command line ("inside", "box") as the API's names.
void normalise_enums(json& j) {
  if (!j.is_object()) return;
  if (j.contains("volume") && j["volume"].is_string()) {
    std::string v = j["volume"];
    if (v.rfind("VOLUME_", 0) != 0) j["volume"] = "VOLUME_" + upper(v == "seed points" ? "seed_points" : v);
  }
  for (const char* key : {"control_volumes", "controlVolumes"})
    if (j.contains(key) && j[key].is_array())
      for (auto& cv : j[key])
        if (cv.is_object() && cv.contains("shape") && cv["shape"].is_string()) {
          std::string s = cv["shape"];
          if (s.rfind("SHAPE_", 0) != 0) cv["shape"] = "SHAPE_" + upper(s);
        }
}

}  // namespace

v1::WrapParameters parse_params_text(const std::string& text, bool yaml, const std::string& name) {
  json j;
  try {
    if (yaml) {
      YamlBudget budget{name};
      j = yaml_to_json(YAML::Load(text), budget);
    } else {
      // The parser itself does not recurse; its callback sees the depth of every value.
      j = json::parse(text, [&](int depth, json::parse_event_t, json&) {
        if (depth > kMaxDepth) too_deep(name);
        return true;
      });
    }
  } catch (const YAML::Exception& e) {
    bad(name, std::string("not valid YAML: ") + e.what());
  } catch (const json::exception& e) {
    bad(name, std::string("not valid JSON: ") + e.what());
  }
  if (j.is_null()) j = json::object();
  if (!j.is_object()) bad(name, "expected a mapping of parameter names to values (the WrapParameters message)");
  // A file may also nest the parameters under "params" (as in a JobSpec).
  if (j.size() == 1 && j.contains("params") && j["params"].is_object()) j = j["params"];
  normalise_enums(j);
  v1::WrapParameters msg;
  google::protobuf::util::JsonParseOptions options;
  options.ignore_unknown_fields = false;
  std::string text_json;
  try {
    text_json = j.dump();
  } catch (const json::exception& e) {
    // YAML takes any bytes; JSON (and so the message) only UTF-8: a Latin-1 byte threw here.
    bad(name, std::string("is not UTF-8 text: ") + e.what());
  }
  auto status = google::protobuf::util::JsonStringToMessage(text_json, &msg, options);
  if (!status.ok()) bad(name, "not a WrapParameters message: " + std::string(status.message()));
  return msg;
}

WrapParams read_params_file(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) bad(path, "cannot read the parameter file");
  std::stringstream buf;
  buf << in.rdbuf();
  const bool yaml =
      path.size() >= 5 && (path.substr(path.size() - 5) == ".yaml" || path.substr(path.size() - 4) == ".yml");
  v1::WrapParameters msg = parse_params_text(buf.str(), yaml, path);
  try {
    return to_wrap_params(msg);
  } catch (const Error& e) {
    bad(path, e.what());
  }
}

}  // namespace vdbwrap::api
