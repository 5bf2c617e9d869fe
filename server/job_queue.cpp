#include "job_queue.h"

#include <malloc.h>

#include <algorithm>
#include <cstdio>
#include <ctime>
#include <optional>

#include "io/mesh_io.h"
#include "params_mapping.h"
#include "vdbwrap/repair.h"
#include "vdbwrap/wrap.h"

namespace vdbwrap::server {

namespace {

constexpr size_t kMaxEventsPerJob = 20000;  // beyond this only state changes are kept

std::string short_name(const pb::JobStatus& r) {
  std::string name = r.spec().file_name();
  if (name.size() > 80) name = name.substr(0, 77) + "...";
  for (char& c : name)
    if (c == '\n' || c == '\r' || c == '"') c = '?';
  return name;
}

}  // namespace

void log_line(const std::string& text) {
  static std::mutex lock;
  auto now = std::chrono::system_clock::now();
  std::time_t t = std::chrono::system_clock::to_time_t(now);
  int ms = int(std::chrono::duration_cast<std::chrono::milliseconds>(now.time_since_epoch()).count() % 1000);
  std::tm tm{};
  gmtime_r(&t, &tm);
  char stamp[32];
  std::strftime(stamp, sizeof stamp, "%Y-%m-%dT%H:%M:%S", &tm);
  std::lock_guard<std::mutex> g(lock);
  std::fprintf(stderr, "%s.%03dZ %s\n", stamp, ms, text.c_str());
  std::fflush(stderr);
}

int64_t unix_ms_now() {
  return std::chrono::duration_cast<std::chrono::milliseconds>(std::chrono::system_clock::now().time_since_epoch())
      .count();
}

// The core's window on a job: progress goes to the job's events, cancelled() answers true
// once a client cancelled it, its time is up, or the server stops.
class JobQueue::Sink : public ProgressSink {
 public:
  Sink(JobQueue& queue, Job& job, double timeout_seconds) : queue_(queue), job_(job) {
    if (timeout_seconds > 0)
      deadline_ = job.started + std::chrono::duration_cast<std::chrono::steady_clock::duration>(
                                    std::chrono::duration<double>(timeout_seconds));
  }
  void progress(const std::string& stage, double fraction, const std::string& message) override {
    bool new_stage = false;
    {
      std::lock_guard<std::mutex> g(job_.lock);
      new_stage = stage != last_stage_;
      last_stage_ = stage;
      queue_.add_event_locked(job_, stage, fraction, message);
    }
    if (new_stage) log_line("job " + job_.record.job_id() + " stage \"" + stage + "\": " + message);
  }
  bool cancelled() override {
    if (job_.cancel_requested.load() || queue_.interrupt_.load()) return true;
    if (deadline_ && std::chrono::steady_clock::now() > *deadline_) {
      timed_out_ = true;
      return true;
    }
    return false;
  }
  bool timed_out() const { return timed_out_.load(); }

 private:
  JobQueue& queue_;
  Job& job_;
  std::optional<std::chrono::steady_clock::time_point> deadline_;
  std::atomic<bool> timed_out_{false};
  std::string last_stage_;
};

JobQueue::JobQueue(JobStore& store, Options options) : store_(store), options_(std::move(options)) {
  options_.workers = std::max(1, options_.workers);
}

JobQueue::~JobQueue() {
  if (!stopped_) shutdown(0);
}

void JobQueue::index_locked(const std::shared_ptr<Job>& job) {
  const std::string& id = job->record.job_id();
  jobs_[id] = job;
  order_.push_back(job);
  if (!job->record.spec().idempotency_key().empty()) by_key_[job->record.spec().idempotency_key()] = id;
}

void JobQueue::restore() {
  std::vector<pb::JobStatus> records = store_.load_all();
  size_t requeued = 0, ended = 0;
  for (auto& record : records) {
    auto job = std::make_shared<Job>();
    const bool unfinished = !api::is_final(record.state());
    if (unfinished) {
      std::error_code ec;
      if (!std::filesystem::exists(store_.input_path(record), ec)) {
        record.set_state(pb::JOB_STATE_FAILED);
        record.set_error_kind(pb::ERROR_KIND_INTERNAL);
        record.set_error_message("the job's input is missing from the spool");
        record.set_finished_unix_ms(unix_ms_now());
      } else {
        record.set_state(pb::JOB_STATE_QUEUED);
        record.set_started_unix_ms(0);
        record.set_stage("");
        record.set_fraction(0);
        record.set_message("queued again after a server restart");
      }
      try {
        store_.save(record);
      } catch (const std::exception& e) {
        log_line(std::string("warning: ") + e.what());
      }
    }
    job->record = record;
    {
      std::lock_guard<std::mutex> g(job->lock);
      add_event_locked(*job, record.stage(), record.fraction(), record.message());
      if (api::is_final(record.state())) {
        auto& ev = job->events.back();
        ev.set_error_kind(record.error_kind());
        ev.set_error_message(record.error_message());
      }
    }
    std::lock_guard<std::mutex> g(lock_);
    index_locked(job);
    if (record.state() == pb::JOB_STATE_QUEUED) {
      queue_.push_back(job);
      ++requeued;
      log_line("job " + record.job_id() + " re-queued after restart (\"" + short_name(record) + "\")");
    } else {
      ++ended;
    }
  }
  log_line("spool: " + std::to_string(requeued) + " job(s) queued again, " + std::to_string(ended) + " ended job(s) kept");
}

void JobQueue::start() {
  for (int i = 0; i < options_.workers; ++i) workers_.emplace_back([this] { worker(); });
}

bool JobQueue::try_reserve() {
  std::lock_guard<std::mutex> g(lock_);
  if (stop_ || queue_.size() + reserved_ >= options_.queue_limit) return false;
  ++reserved_;
  return true;
}

void JobQueue::release_reservation() {
  std::lock_guard<std::mutex> g(lock_);
  if (reserved_ > 0) --reserved_;
}

std::shared_ptr<Job> JobQueue::accept(JobStore::Upload& upload, pb::JobStatus record, bool& duplicate) {
  std::unique_lock<std::mutex> g(lock_);
  duplicate = false;
  const std::string& key = record.spec().idempotency_key();
  if (!key.empty()) {
    auto it = by_key_.find(key);
    if (it != by_key_.end()) {
      duplicate = true;
      if (reserved_ > 0) --reserved_;
      return jobs_.at(it->second);
    }
  }
  // Stored before anyone can learn the id. Holding the lock keeps idempotency keys unique.
  store_.commit(upload, record);
  auto job = std::make_shared<Job>();
  job->record = std::move(record);
  {
    std::lock_guard<std::mutex> jg(job->lock);
    add_event_locked(*job, "", 0, "queued");
  }
  index_locked(job);
  if (reserved_ > 0) --reserved_;
  queue_.push_back(job);
  work_.notify_one();
  return job;
}

std::shared_ptr<Job> JobQueue::find(const std::string& id) const {
  std::lock_guard<std::mutex> g(lock_);
  auto it = jobs_.find(id);
  return it == jobs_.end() ? nullptr : it->second;
}

std::shared_ptr<Job> JobQueue::find_by_key(const std::string& key) const {
  std::lock_guard<std::mutex> g(lock_);
  auto it = by_key_.find(key);
  return it == by_key_.end() ? nullptr : jobs_.at(it->second);
}

std::vector<std::shared_ptr<Job>> JobQueue::list() const {
  std::lock_guard<std::mutex> g(lock_);
  return order_;
}

JobQueue::CancelResult JobQueue::cancel(const std::shared_ptr<Job>& job) {
  {
    std::lock_guard<std::mutex> g(lock_);
    auto it = std::find(queue_.begin(), queue_.end(), job);
    if (it != queue_.end()) {
      queue_.erase(it);
      job->cancel_requested = true;
    }
  }
  pb::JobState state = job->snapshot().state();
  if (state == pb::JOB_STATE_CANCELLED) return CancelResult::AlreadyCancelled;
  if (api::is_final(state)) return CancelResult::AlreadyEnded;
  if (state == pb::JOB_STATE_QUEUED && job->cancel_requested) {
    set_state(*job, pb::JOB_STATE_CANCELLED, pb::ERROR_KIND_CANCELLED, "cancelled while queued");
    log_line("job " + job->record.job_id() + " cancelled while queued");
    return CancelResult::Cancelled;
  }
  job->cancel_requested = true;
  log_line("job " + job->record.job_id() + " cancel requested");
  return CancelResult::Requested;
}

bool JobQueue::remove(const std::shared_ptr<Job>& job) {
  std::lock_guard<std::mutex> g(lock_);
  pb::JobStatus r = job->snapshot();
  if (!api::is_final(r.state())) return false;
  store_.remove(r.job_id());
  jobs_.erase(r.job_id());
  order_.erase(std::remove(order_.begin(), order_.end(), job), order_.end());
  if (!r.spec().idempotency_key().empty()) by_key_.erase(r.spec().idempotency_key());
  log_line("job " + r.job_id() + " deleted");
  return true;
}

void JobQueue::shutdown(double grace_seconds) {
  {
    std::unique_lock<std::mutex> g(lock_);
    if (stopped_) return;
    stop_ = true;
    work_.notify_all();
    auto deadline = std::chrono::steady_clock::now() +
                    std::chrono::duration_cast<std::chrono::steady_clock::duration>(
                        std::chrono::duration<double>(std::max(0.0, grace_seconds)));
    if (running_ > 0) log_line("shutdown: waiting up to " + std::to_string(int(grace_seconds)) + " s for " +
                               std::to_string(running_) + " running job(s)");
    idle_.wait_until(g, deadline, [&] { return running_ == 0; });
    if (running_ > 0) {
      log_line("shutdown: interrupting " + std::to_string(running_) + " running job(s); they stay queued on disk");
      interrupt_ = true;
    }
  }
  for (auto& t : workers_)
    if (t.joinable()) t.join();
  workers_.clear();
  stopped_ = true;
  // Wake every watcher so that it notices the stop.
  for (auto& job : list()) job->changed.notify_all();
}

void JobQueue::add_event_locked(Job& job, const std::string& stage, double fraction, const std::string& message) {
  pb::JobStatus& r = job.record;
  r.set_stage(stage);
  r.set_fraction(fraction);
  r.set_message(message);
  const bool state_change = job.events.empty() || job.events.back().state() != r.state();
  if (job.events.size() >= kMaxEventsPerJob && !state_change && !api::is_final(r.state())) return;
  pb::ProgressEvent ev;
  ev.set_sequence(job.events.size() + 1);
  ev.set_state(r.state());
  ev.set_stage(stage);
  ev.set_fraction(fraction);
  ev.set_message(message);
  if (r.state() == pb::JOB_STATE_RUNNING || api::is_final(r.state()))
    ev.set_elapsed_seconds(job.started == std::chrono::steady_clock::time_point{}
                               ? 0.0
                               : std::chrono::duration<double>(std::chrono::steady_clock::now() - job.started).count());
  job.events.push_back(std::move(ev));
  job.changed.notify_all();
}

void JobQueue::set_state(Job& job, pb::JobState state, pb::ErrorKind kind, const std::string& error) {
  std::lock_guard<std::mutex> g(job.lock);
  pb::JobStatus& r = job.record;
  r.set_state(state);
  r.set_error_kind(kind);
  r.set_error_message(error);
  if (state == pb::JOB_STATE_RUNNING) r.set_started_unix_ms(unix_ms_now());
  if (api::is_final(state)) r.set_finished_unix_ms(unix_ms_now());
  if (state == pb::JOB_STATE_QUEUED) r.set_started_unix_ms(0);
  try {
    store_.save(r);
  } catch (const std::exception& e) {
    log_line("job " + r.job_id() + " warning: cannot save its record: " + e.what());
  }
  const char* msg = state == pb::JOB_STATE_RUNNING ? "started" : api::state_name(state);
  add_event_locked(job, state == pb::JOB_STATE_RUNNING ? "" : r.stage(), state == pb::JOB_STATE_RUNNING ? 0.0 : r.fraction(),
                   error.empty() ? std::string(msg) : error);
  if (api::is_final(state)) {
    job.events.back().set_error_kind(kind);
    job.events.back().set_error_message(error);
  }
}

void JobQueue::worker() {
  for (;;) {
    std::shared_ptr<Job> job;
    {
      std::unique_lock<std::mutex> g(lock_);
      work_.wait(g, [&] { return stop_ || !queue_.empty(); });
      if (stop_) return;
      job = queue_.front();
      queue_.pop_front();
      ++running_;
    }
    run(job);
    ::malloc_trim(0);  // give the job's memory back to the system
    {
      std::lock_guard<std::mutex> g(lock_);
      --running_;
    }
    idle_.notify_all();
  }
}

void JobQueue::run(const std::shared_ptr<Job>& job) {
  const pb::JobStatus spec_record = job->snapshot();
  const std::string id = spec_record.job_id();
  job->started = std::chrono::steady_clock::now();
  set_state(*job, pb::JOB_STATE_RUNNING);
  log_line("job " + id + " started (\"" + short_name(spec_record) + "\")");
  Sink sink(*this, *job, options_.job_timeout_seconds);
  auto fail = [&](pb::ErrorKind kind, const std::string& why) {
    set_state(*job, kind == pb::ERROR_KIND_CANCELLED ? pb::JOB_STATE_CANCELLED : pb::JOB_STATE_FAILED, kind, why);
    log_line("job " + id + (kind == pb::ERROR_KIND_CANCELLED ? " cancelled: " : " failed: ") + why);
  };
  try {
    const pb::JobSpec& spec = spec_record.spec();
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
    if (sink.cancelled()) throw Error(ErrorKind::Cancelled, "cancelled");
    Mesh input;
    {
      sink.progress("read", 0.0, "reading the upload");
      std::string bytes = JobStore::read_file(store_.input_path(spec_record));
      input = io::read_mesh_from_bytes(bytes, api::to_io_format(spec.input_format()),
                                       spec.file_name().empty() ? "upload" : spec.file_name());
      sink.progress("read", 1.0, std::to_string(input.triangles.size()) + " triangles");
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
      report = to_json(result.report);
      seconds = result.report.total_seconds;
      pairs_left = result.report.after.intersecting_pairs;
    } else {
      WrapResult result = wrap(input, params, &sink);
      surface = std::move(result.surface);
      report = to_json(result.report);
      seconds = result.report.total_seconds;
    }
    input = Mesh{};  // frees the input before writing
    sink.progress("write", 0.0, "writing the result");
    const pb::MeshFormat out_format = spec.output_format();
    std::string ply = io::write_mesh_to_bytes(surface, io::Format::Ply);
    store_.write_file_atomic(store_.result_path(id, pb::MESH_FORMAT_PLY), ply);
    uint64_t result_bytes = ply.size();
    ply = std::string();
    if (out_format != pb::MESH_FORMAT_PLY) {
      std::string bytes = io::write_mesh_to_bytes(surface, api::to_io_format(out_format));
      store_.write_file_atomic(store_.result_path(id, out_format), bytes);
      result_bytes = bytes.size();
    }
    store_.write_file_atomic(store_.report_path(id), report + "\n");
    {
      std::lock_guard<std::mutex> g(job->lock);
      job->record.set_result_bytes(result_bytes);
      job->record.set_output_triangles(surface.triangles.size());
      job->record.set_intersecting_pairs_left(pairs_left);
    }
    sink.progress("write", 1.0, std::to_string(result_bytes) + " bytes");
    set_state(*job, pb::JOB_STATE_SUCCEEDED);
    char line[256];
    std::snprintf(line, sizeof line, " finished: %zu triangles, %.2f s", surface.triangles.size(), seconds);
    std::string text = "job " + id + line;
    if (api::is_repair(spec)) text += ", " + std::to_string(pairs_left) + " intersecting pairs left";
    log_line(text);
  } catch (const WrapFailure& f) {
    // A leak or a failed validation: the report says where, so it is kept with the job.
    try {
      store_.write_file_atomic(store_.report_path(id), to_json(f.report()) + "\n");
    } catch (const std::exception&) {
    }
    fail(api::to_proto(f.kind()), f.what());
  } catch (const Error& e) {
    if (e.kind() == ErrorKind::Cancelled && interrupt_) {
      set_state(*job, pb::JOB_STATE_QUEUED, pb::ERROR_KIND_UNSPECIFIED, "");
      log_line("job " + id + " interrupted by the shutdown; it stays queued on disk");
    } else if (e.kind() == ErrorKind::Cancelled && sink.timed_out()) {
      char why[128];
      std::snprintf(why, sizeof why, "timed out: ran longer than the server's job timeout of %g s",
                    options_.job_timeout_seconds);
      fail(pb::ERROR_KIND_TIMED_OUT, why);
    } else if (e.kind() == ErrorKind::Cancelled) {
      fail(pb::ERROR_KIND_CANCELLED, "cancelled by a client");
    } else {
      fail(api::to_proto(e.kind()), e.what());
    }
  } catch (const std::bad_alloc&) {
    fail(pb::ERROR_KIND_INTERNAL, "out of memory");
  } catch (const std::exception& e) {
    fail(pb::ERROR_KIND_INTERNAL, std::string("internal error: ") + e.what());
  }
}

}  // namespace vdbwrap::server
