// What a report says about the run's origin: the tool's version and the input (its file name
// and parts). The CLI and the server both fill reports with these, so that a job's report
// carries the same keys as `vdbwrap wrap --report`.
#pragma once
#include <string>

#include "vdbwrap/mesh.h"
#include "vdbwrap/report.h"  // WrapReport::Source

namespace vdbwrap {

// The project's version ("0.1.0").
const char* version();

// The version, the input's file name without its folder ('/' or '\\': a client's name may come
// from another system) and each part's name and triangle count. The library reads no file: the
// caller passes the name it read `mesh` from.
WrapReport::Source source_of(const std::string& input_name, const Mesh& mesh);

// report_json (a JSON object: the repair or check report) with the wrap report's
// "vdbwrap_version" and "source" keys added. Throws Error(Internal) for text that is not a
// JSON object.
std::string with_source(const std::string& report_json, const WrapReport::Source& source);

}  // namespace vdbwrap
