// The report's "source" object (file name, parts, reading notes), one writer for the wrap
// report's to_json and for with_source (repair and check reports).
// Defined in report.cpp.
#pragma once
#include <nlohmann/json.hpp>

#include "vdbwrap/report.h"

namespace vdbwrap {

nlohmann::json source_json(const WrapReport::Source& src);

}  // namespace vdbwrap
