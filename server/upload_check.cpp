#include "upload_check.h"

#include <signal.h>
#include <sys/wait.h>

#include <fstream>
#include <new>
#include <optional>
#include <thread>

#include "vdbwrap/io.h"
#include "job_process.h"
#include "job_store.h"
#include "params_mapping.h"
#include "worker_protocol.h"

namespace vdbwrap::server {

namespace {

pb::JobStatus failed(pb::ErrorKind kind, const std::string& why) {
  pb::JobStatus v;
  v.set_state(kind == pb::ERROR_KIND_CANCELLED ? pb::JOB_STATE_CANCELLED : pb::JOB_STATE_FAILED);
  v.set_error_kind(kind);
  v.set_error_message(why);
  return v;
}

}  // namespace

pb::JobStatus check_upload(const std::string& worker_command, uint64_t memory_limit, const std::string& file,
                           pb::MeshFormat format, const std::string& name, const std::function<bool()>& abandon) {
  std::optional<pb::JobStatus> verdict;
  int status = 0;
  try {
    JobProcess process({worker_command, "--check-upload", file, std::to_string(int(format)), name}, memory_limit);
    std::vector<pb::JobStatus> frames;
    while (!process.reap()) {
      if (process.pipe_open())
        process.read_frames(std::chrono::milliseconds(50), frames);
      else
        std::this_thread::sleep_for(std::chrono::milliseconds(10));
      if (abandon()) return failed(pb::ERROR_KIND_CANCELLED, "abandoned");  // the destructor kills and reaps
    }
    while (process.pipe_open() && process.read_frames(std::chrono::milliseconds(0), frames) > 0) {
    }
    for (auto& f : frames)
      if (f.state() != pb::JOB_STATE_RUNNING) verdict = f;
    status = process.wait_status();
  } catch (const std::exception& e) {
    return failed(pb::ERROR_KIND_INTERNAL, std::string("cannot check the upload: ") + e.what());
  }
  if (verdict && WIFEXITED(status) && WEXITSTATUS(status) == 0) return *verdict;
  return failed(pb::ERROR_KIND_INTERNAL,
                name + ": the mesh reader's process ended with " + describe_wait_status(status) + " on this file");
}

int run_upload_check(const std::string& file, const std::string& format_number, const std::string& name) {
  // As a job's process: when the machine runs out of memory, the kernel should end this, not the server.
  if (std::ofstream adj{"/proc/self/oom_score_adj"}) adj << 500 << std::flush;
  pb::JobStatus v;
  try {
    const auto format = pb::MeshFormat(std::stoi(format_number));
    if (!pb::MeshFormat_IsValid(format)) throw std::invalid_argument("format");
    const std::string bytes = JobStore::read_file(file);
    const Mesh mesh = io::read_mesh_from_bytes(bytes, api::to_io_format(format), name);
    v.set_state(pb::JOB_STATE_SUCCEEDED);
    v.set_output_triangles(mesh.triangles.size());
  } catch (const Error& e) {
    v = failed(api::to_proto(e.kind()), e.what());
  } catch (const std::bad_alloc&) {
    v = failed(pb::ERROR_KIND_INTERNAL, "out of memory");
  } catch (const std::exception& e) {
    v = failed(pb::ERROR_KIND_INTERNAL, std::string("cannot read the upload back: ") + e.what());
  }
  return write_frame(kWorkerEventsFd, v) ? 0 : 1;
}

}  // namespace vdbwrap::server
