// Parameter files: JSON or YAML in the form of the API's WrapParameters message, so one file
// serves the CLI (--params) and any gRPC client. Field names as in jobs.proto (snake_case;
// lowerCamelCase also works); enums by name ("VOLUME_INSIDE", or the short "inside"; shapes
// "SHAPE_BOX" or "box").
#pragma once
#include <string>

#include "vdbwrap/v1/jobs.pb.h"
#include "vdbwrap/wrap.h"

namespace vdbwrap::api {

// Parses text (YAML when yaml is true, else JSON) into the message. Throws
// Error(InvalidArgument) naming `display_name` and what is wrong.
v1::WrapParameters parse_params_text(const std::string& text, bool yaml, const std::string& display_name);

// Reads PATH (.yaml / .yml: YAML, else JSON) and maps it to the core parameters (with the
// same range checks as the API). Throws Error(InvalidArgument).
WrapParams read_params_file(const std::string& path);

}  // namespace vdbwrap::api
