// The one mapping between the vdbwrap.v1 API messages and the core API
// (core/include/vdbwrap/wrap.h), used by the server and by the remote CLI.
#pragma once
#include <grpcpp/support/status.h>

#include <string>

#include "vdbwrap/io.h"
#include "vdbwrap/errors.h"
#include "vdbwrap/repair.h"
#include "vdbwrap/v1/jobs.pb.h"
#include "vdbwrap/wrap.h"

namespace vdbwrap::api {

namespace pb = ::vdbwrap::v1;

// Trailing metadata key of a failed call: the ErrorKind number ("2", "3") when the call
// failed because of the parameters or the input.
inline constexpr const char* kErrorKindMetadata = "vdbwrap-error-kind";

// API parameters -> core parameters. Unset fields take WrapParams' defaults (the CLI's).
// Throws Error(InvalidArgument) naming the field for a value out of range (the same ranges
// as the command line).
WrapParams to_wrap_params(const pb::WrapParameters& in);

// Core parameters -> API parameters, every field set.
pb::WrapParameters to_proto(const WrapParams& in);

// The same for the repair: unset fields take RepairParams' defaults (`vdbwrap repair`'s);
// Error(InvalidArgument) naming the field for a value out of range.
RepairParams to_repair_params(const pb::RepairParameters& in);
pb::RepairParameters to_proto(const RepairParams& in);

// Checks that a job's spec names its kind's parameters only (Error(InvalidArgument)) and
// that they are in range.
void check_job_parameters(const pb::JobSpec& spec);
bool is_repair(const pb::JobSpec& spec);

io::Format to_io_format(pb::MeshFormat format);
pb::MeshFormat to_proto_format(io::Format format);
// "stl", "obj", "off", "ply"; empty for unspecified.
std::string extension_of(pb::MeshFormat format);
// From a file name's extension (case-insensitive); UNSPECIFIED when none matches.
pb::MeshFormat format_from_file_name(const std::string& file_name);

pb::ErrorKind to_proto(ErrorKind kind);
// The CLI exit code of a job error (TIMED_OUT counts as an internal/resource error: 1).
ErrorKind to_error_kind(pb::ErrorKind kind);

const char* state_name(pb::JobState state);  // "queued", "running", ...
bool is_final(pb::JobState state);

// The gRPC status of a call that failed with a core error: InvalidArgument/InvalidInput ->
// INVALID_ARGUMENT, Cancelled -> CANCELLED, others -> INTERNAL.
grpc::StatusCode status_code_for(ErrorKind kind);

}  // namespace vdbwrap::api
