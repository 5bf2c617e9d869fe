// The check of an upload on arrival (is it a mesh `vdbwrap wrap` can read?), run in a process of
// its own like the jobs: `WORKER_COMMAND --check-upload FILE FORMAT NAME`. A reader that crashes
// or runs out of memory on a hostile file ends that process, not the server.
#pragma once
#include <cstdint>
#include <functional>
#include <string>

#include "vdbwrap/v1/jobs.pb.h"

namespace vdbwrap::server {

namespace pb = ::vdbwrap::v1;

// The verdict as a JobStatus: SUCCEEDED with output_triangles (the mesh's triangles), or
// FAILED with an error kind and message (the reader's error; "out of memory..."; or how the
// process ended). `abandon` is polled while waiting: true kills the check (FAILED, CANCELLED).
pb::JobStatus check_upload(const std::string& worker_command, uint64_t memory_limit, const std::string& file,
                           pb::MeshFormat format, const std::string& name, const std::function<bool()>& abandon);

// The worker side (`--check-upload`): reads the file and sends the verdict on fd 3. Returns the
// process exit code.
int run_upload_check(const std::string& file, const std::string& format_number, const std::string& name);

}  // namespace vdbwrap::server
