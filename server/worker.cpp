#include "worker.h"

#include <signal.h>
#include <sys/resource.h>
#include <unistd.h>

#include <atomic>
#include <cstdio>
#include <exception>
#include <fstream>
#include <mutex>
#include <new>

#include "vdbwrap/io.h"
#include "job_store.h"
#include "params_mapping.h"
#include "vdbwrap/repair.h"
#include "vdbwrap/source.h"
#include "vdbwrap/wrap.h"
#include "worker_protocol.h"

namespace vdbwrap::server {

namespace {

std::atomic<bool> g_terminate{false};
std::atomic<bool> g_verdict_sent{false};

void on_sigterm(int) { g_terminate.store(true); }

// "8 GiB", "300 MiB": the per-job memory limit as the server's operator wrote it, roughly.
std::string human_bytes(unsigned long long n) {
  char text[64];
  if (n >= (1ull << 30))
    std::snprintf(text, sizeof text, "%.3g GiB", double(n) / double(1ull << 30));
  else
    std::snprintf(text, sizeof text, "%.3g MiB", double(n) / double(1ull << 20));
  return text;
}

// The last stage the pipeline reported, for messages about where it ran out of memory.
std::mutex g_stage_lock;
std::string g_stage;

std::string out_of_memory_message() {
  std::string where;
  {
    std::lock_guard<std::mutex> g(g_stage_lock);
    if (!g_stage.empty()) where = " in stage " + g_stage;
  }
  rlimit limit{};
  if (::getrlimit(RLIMIT_DATA, &limit) == 0 && limit.rlim_cur != RLIM_INFINITY)
    return "out of memory" + where + ": the job needs more than the server's per-job memory limit (--job-memory) of " +
           human_bytes(limit.rlim_cur);
  return "out of memory" + where;
}

bool send_verdict(pb::JobState state, pb::ErrorKind kind, const std::string& error, const pb::JobStatus& extra = {}) {
  pb::JobStatus frame = extra;
  frame.set_state(state);
  frame.set_error_kind(kind);
  frame.set_error_message(error);
  g_verdict_sent = true;
  return write_frame(kWorkerEventsFd, frame);
}

// An exception that escapes a thread ends the process; its reason goes to the server first,
// which then reports it with the signal.
void on_terminate() {
  if (!g_verdict_sent.exchange(true)) {
    std::string why = "an exception escaped";
    try {
      if (auto e = std::current_exception()) std::rethrow_exception(e);
    } catch (const std::bad_alloc&) {
      why = out_of_memory_message();
    } catch (const std::exception& e) {
      why = std::string("internal error: ") + e.what();
    } catch (...) {
    }
    pb::JobStatus frame;
    frame.set_state(pb::JOB_STATE_FAILED);
    frame.set_error_kind(pb::ERROR_KIND_INTERNAL);
    frame.set_error_message(why);
    write_frame(kWorkerEventsFd, frame);
  }
  std::abort();
}

// The core's window on the job: progress becomes frames; cancelled() answers SIGTERM (a
// client cancel, the job timeout or the server's shutdown). When the server is gone (the
// pipe is closed), the job stops too.
class FrameSink : public ProgressSink {
 public:
  void progress(const std::string& stage, double fraction, const std::string& message) override {
    pb::JobStatus frame;
    frame.set_state(pb::JOB_STATE_RUNNING);
    frame.set_stage(stage);
    frame.set_fraction(fraction);
    frame.set_message(message);
    {
      std::lock_guard<std::mutex> g(g_stage_lock);
      if (g_stage != stage) g_stage = stage;
    }
    if (!write_frame(kWorkerEventsFd, frame)) server_gone_ = true;
  }
  bool cancelled() override { return g_terminate.load() || server_gone_.load(); }

 private:
  std::atomic<bool> server_gone_{false};
};

}  // namespace

int run_worker(const std::string& job_dir_text) {
  struct sigaction sa {};
  sa.sa_handler = on_sigterm;
  sigemptyset(&sa.sa_mask);
  ::sigaction(SIGTERM, &sa, nullptr);
  std::set_terminate(on_terminate);
  // When the machine runs out of memory, the kernel should end a job, not the server.
  if (std::ofstream adj{"/proc/self/oom_score_adj"}) adj << 500 << std::flush;

  const fs::path dir = job_dir_text;
  FrameSink sink;
  WrapReport::Source source;  // the reports' vdbwrap_version and source, as the CLI's
  try {
    const pb::JobStatus record = JobStore::read_record(dir);
    const pb::JobSpec& spec = record.spec();
    // Binary STL stores floats: validate (or repair) what will be written.
    const bool float_coordinates = spec.output_format() == pb::MESH_FORMAT_STL;
    WrapParams params;
    RepairParams repair_params;
    if (api::is_repair(spec)) {
      repair_params = api::to_repair_params(spec.repair_params());
      repair_params.float_coordinates = float_coordinates;
    } else {
      params = api::to_wrap_params(spec.params());
      params.float_coordinates = float_coordinates;
    }
    Mesh input;
    {
      sink.progress("read", 0.0, "reading the upload");
      std::string bytes = JobStore::read_file(dir / JobStore::input_file_name(record));
      input = io::read_mesh_from_bytes(bytes, api::to_io_format(spec.input_format()),
                                       spec.file_name().empty() ? "upload" : spec.file_name());
      sink.progress("read", 1.0, std::to_string(input.triangles.size()) + " triangles");
      source = source_of(spec.file_name().empty() ? "upload" : spec.file_name(), input);
    }
    // The job's work: a wrap, or a repair (whose result is written even with intersections
    // left, as `vdbwrap repair` does; the status says how many).
    Mesh surface;
    std::string report;
    double seconds = 0;
    uint64_t pairs_left = 0;
    if (api::is_repair(spec)) {
      RepairResult result = repair(input, repair_params, &sink);
      surface = std::move(result.mesh);
      report = with_source(to_json(result.report), source);
      seconds = result.report.total_seconds;
      pairs_left = result.report.after.intersecting_pairs;
    } else {
      WrapResult result = wrap(input, params, &sink);
      surface = std::move(result.surface);
      result.report.source = source;
      report = to_json(result.report);
      seconds = result.report.total_seconds;
    }
    input = Mesh{};  // frees the input before writing
    sink.progress("write", 0.0, "writing the result");
    const pb::MeshFormat out_format = spec.output_format();
    std::string ply = io::write_mesh_to_bytes(surface, io::Format::Ply);
    JobStore::write_file_atomic(dir / JobStore::result_file_name(pb::MESH_FORMAT_PLY), ply);
    uint64_t result_bytes = ply.size();
    ply = std::string();
    if (out_format != pb::MESH_FORMAT_PLY) {
      std::string bytes = io::write_mesh_to_bytes(surface, api::to_io_format(out_format));
      JobStore::write_file_atomic(dir / JobStore::result_file_name(out_format), bytes);
      result_bytes = bytes.size();
    }
    JobStore::write_file_atomic(dir / JobStore::kReportFile, report + "\n");
    sink.progress("write", 1.0, std::to_string(result_bytes) + " bytes");
    pb::JobStatus outcome;
    outcome.set_result_bytes(result_bytes);
    outcome.set_output_triangles(surface.triangles.size());
    outcome.set_intersecting_pairs_left(pairs_left);
    char line[256];
    std::snprintf(line, sizeof line, "%zu triangles, %.2f s", surface.triangles.size(), seconds);
    std::string summary = line;
    if (api::is_repair(spec)) summary += ", " + std::to_string(pairs_left) + " intersecting pairs left";
    outcome.set_message(summary);
    return send_verdict(pb::JOB_STATE_SUCCEEDED, pb::ERROR_KIND_UNSPECIFIED, "", outcome) ? 0 : 1;
  } catch (const WrapFailure& f) {
    // A leak or a failed validation: the report says where, so it is kept with the job.
    try {
      WrapReport report = f.report();
      report.source = source;
      JobStore::write_file_atomic(dir / JobStore::kReportFile, to_json(report) + "\n");
    } catch (const std::exception&) {
    }
    return send_verdict(pb::JOB_STATE_FAILED, api::to_proto(f.kind()), f.what()) ? 0 : 1;
  } catch (const Error& e) {
    // A cancel (SIGTERM) is named by the server, which knows why it asked.
    if (e.kind() == ErrorKind::Cancelled)
      return send_verdict(pb::JOB_STATE_CANCELLED, pb::ERROR_KIND_CANCELLED, "cancelled") ? 0 : 1;
    return send_verdict(pb::JOB_STATE_FAILED, api::to_proto(e.kind()), e.what()) ? 0 : 1;
  } catch (const std::bad_alloc&) {
    return send_verdict(pb::JOB_STATE_FAILED, pb::ERROR_KIND_INTERNAL, out_of_memory_message()) ? 0 : 1;
  } catch (const std::exception& e) {
    return send_verdict(pb::JOB_STATE_FAILED, pb::ERROR_KIND_INTERNAL, std::string("internal error: ") + e.what()) ? 0
                                                                                                                   : 1;
  }
}

}  // namespace vdbwrap::server
