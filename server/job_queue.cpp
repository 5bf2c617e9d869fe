#include "job_queue.h"

#include <signal.h>
#include <sys/wait.h>

#include <algorithm>
#include <cstdio>
#include <ctime>
#include <optional>

#include "job_process.h"
#include "params_mapping.h"

namespace vdbwrap::server {

namespace {

constexpr size_t kMaxEventsPerJob = 20000;  // beyond this only state changes are kept
// A job process asked to stop (SIGTERM) gets this long to unwind before SIGKILL.
constexpr auto kStopGrace = std::chrono::seconds(2);
// How often a running job's process is looked at (cancel, timeout, shutdown).
constexpr auto kPollInterval = std::chrono::milliseconds(100);

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
      // Running on disk: the server (and with it the job's process) stopped while it ran.
      const bool was_running = record.state() == pb::JOB_STATE_RUNNING;
      const int attempts = store_.attempts(record.job_id());
      std::error_code ec;
      auto fail = [&](const std::string& why) {
        record.set_state(pb::JOB_STATE_FAILED);
        record.set_error_kind(pb::ERROR_KIND_INTERNAL);
        record.set_error_message(why);
        record.set_finished_unix_ms(unix_ms_now());
        log_line("job " + record.job_id() + " failed: " + why);
      };
      if (!std::filesystem::exists(store_.input_path(record), ec)) {
        fail("the job's input is missing from the spool");
      } else if (was_running && attempts >= options_.max_attempts) {
        fail("the server stopped " + std::to_string(attempts) + " times while this job ran (--max-attempts " +
             std::to_string(options_.max_attempts) + "); it is not run again");
      } else {
        record.set_state(pb::JOB_STATE_QUEUED);
        record.set_started_unix_ms(0);
        record.set_stage("");
        record.set_fraction(0);
        record.set_message(was_running ? "queued again: the server stopped while it ran (" + std::to_string(attempts) +
                                             " of " + std::to_string(options_.max_attempts) + " attempts used)"
                                       : std::string("queued again after a server restart"));
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
  log_line("spool: " + std::to_string(requeued) + " job(s) queued again, " + std::to_string(ended) +
           " ended job(s) kept");
  // Before the server listens, so that no client sees a job older than --retain.
  if (options_.retain_seconds > 0) {
    try {
      prune(unix_ms_now() - int64_t(options_.retain_seconds * 1000));
    } catch (const std::exception& e) {
      log_line(std::string("warning: pruning the spool: ") + e.what());
    }
  }
}

void JobQueue::start() {
  for (int i = 0; i < options_.workers; ++i) workers_.emplace_back([this] { worker(); });
  if (options_.retain_seconds > 0) janitor_ = std::thread([this] { janitor(); });
}

// Prunes every tenth of the retention (between a second and ten minutes); restore() did at start.
void JobQueue::janitor() {
  const double period = std::clamp(options_.retain_seconds / 10, 1.0, 600.0);
  std::unique_lock<std::mutex> g(lock_);
  for (;;) {
    if (janitor_wake_.wait_for(g, std::chrono::duration<double>(period), [&] { return stop_; })) return;
    g.unlock();
    try {
      prune(unix_ms_now() - int64_t(options_.retain_seconds * 1000));
    } catch (const std::exception& e) {
      log_line(std::string("warning: pruning the spool: ") + e.what());
    }
    g.lock();
  }
}

size_t JobQueue::prune(int64_t cutoff_unix_ms) {
  std::lock_guard<std::mutex> g(lock_);
  std::vector<std::shared_ptr<Job>> old;
  for (const auto& job : order_) {
    const pb::JobStatus r = job->snapshot();
    if (api::is_final(r.state()) && r.finished_unix_ms() > 0 && r.finished_unix_ms() < cutoff_unix_ms)
      old.push_back(job);
  }
  for (const auto& job : old) remove_locked(job, "pruned (ended longer ago than --retain)");
  return old.size();
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
  if (!api::is_final(job->snapshot().state())) return false;
  remove_locked(job, "deleted");
  return true;
}

void JobQueue::remove_locked(const std::shared_ptr<Job>& job, const std::string& why) {
  pb::JobStatus r = job->snapshot();
  store_.remove(r.job_id());
  jobs_.erase(r.job_id());
  order_.erase(std::remove(order_.begin(), order_.end(), job), order_.end());
  if (!r.spec().idempotency_key().empty()) by_key_.erase(r.spec().idempotency_key());
  log_line("job " + r.job_id() + " " + why);
}

void JobQueue::shutdown(double grace_seconds) {
  {
    std::unique_lock<std::mutex> g(lock_);
    if (stopped_) return;
    stop_ = true;
    work_.notify_all();
    janitor_wake_.notify_all();
    auto deadline = std::chrono::steady_clock::now() + std::chrono::duration_cast<std::chrono::steady_clock::duration>(
                                                           std::chrono::duration<double>(std::max(0.0, grace_seconds)));
    if (running_ > 0)
      log_line("shutdown: waiting up to " + std::to_string(int(grace_seconds)) + " s for " + std::to_string(running_) +
               " running job(s)");
    idle_.wait_until(g, deadline, [&] { return running_ == 0; });
    if (running_ > 0) {
      log_line("shutdown: interrupting " + std::to_string(running_) + " running job(s); they stay queued on disk");
      interrupt_ = true;
    }
  }
  for (auto& t : workers_)
    if (t.joinable()) t.join();
  workers_.clear();
  if (janitor_.joinable()) janitor_.join();
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
  add_event_locked(job, state == pb::JOB_STATE_RUNNING ? "" : r.stage(),
                   state == pb::JOB_STATE_RUNNING ? 0.0 : r.fraction(), error.empty() ? std::string(msg) : error);
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
    {
      std::lock_guard<std::mutex> g(lock_);
      --running_;
    }
    idle_.notify_all();
  }
}

// Runs one job in its own process and turns how that process ended into the job's state.
void JobQueue::run(const std::shared_ptr<Job>& job) {
  const pb::JobStatus spec_record = job->snapshot();
  const std::string id = spec_record.job_id();
  const char* process_name = api::is_repair(spec_record.spec()) ? "the repair process" : "the wrap process";
  auto fail = [&](pb::ErrorKind kind, const std::string& why) {
    set_state(*job, kind == pb::ERROR_KIND_CANCELLED ? pb::JOB_STATE_CANCELLED : pb::JOB_STATE_FAILED, kind, why);
    log_line("job " + id + (kind == pb::ERROR_KIND_CANCELLED ? " cancelled: " : " failed: ") + why);
  };
  // Counted before the start, durably: if the server dies while the job runs, the next start
  // knows (restore()).
  const int attempt = store_.attempts(id) + 1;
  try {
    store_.set_attempts(id, attempt);
  } catch (const std::exception& e) {
    log_line("job " + id + " warning: cannot record the attempt: " + e.what());
  }
  job->started = std::chrono::steady_clock::now();
  set_state(*job, pb::JOB_STATE_RUNNING);
  log_line("job " + id + " started (\"" + short_name(spec_record) + "\"" +
           (attempt > 1 ? ", attempt " + std::to_string(attempt) : std::string()) + ")");
  if (job->cancel_requested) {
    fail(pb::ERROR_KIND_CANCELLED, "cancelled by a client");
    return;
  }

  std::optional<std::chrono::steady_clock::time_point> deadline;
  if (options_.job_timeout_seconds > 0)
    deadline = job->started + std::chrono::duration_cast<std::chrono::steady_clock::duration>(
                                  std::chrono::duration<double>(options_.job_timeout_seconds));
  enum class Stop { None, Cancel, Timeout, Shutdown };
  Stop stop = Stop::None;
  std::chrono::steady_clock::time_point stop_asked{};
  bool killed = false;
  std::optional<pb::JobStatus> verdict;
  std::string last_stage, protocol_error;

  std::unique_ptr<JobProcess> process;
  try {
    process = std::make_unique<JobProcess>(
        std::vector<std::string>{options_.worker_command, "--worker", store_.job_dir(id).string()},
        options_.job_memory);
  } catch (const std::exception& e) {
    fail(pb::ERROR_KIND_INTERNAL, e.what());
    return;
  }
  auto on_frame = [&](const pb::JobStatus& frame) {
    if (frame.state() != pb::JOB_STATE_RUNNING) {
      verdict = frame;
      return;
    }
    const bool new_stage = frame.stage() != last_stage;
    last_stage = frame.stage();
    {
      std::lock_guard<std::mutex> g(job->lock);
      add_event_locked(*job, frame.stage(), frame.fraction(), frame.message());
    }
    if (new_stage) log_line("job " + id + " stage \"" + frame.stage() + "\": " + frame.message());
  };
  std::vector<pb::JobStatus> frames;
  while (!process->reap()) {
    frames.clear();
    try {
      if (process->pipe_open())
        process->read_frames(kPollInterval, frames);
      else
        std::this_thread::sleep_for(kPollInterval / 2);
    } catch (const std::exception& e) {
      if (protocol_error.empty()) protocol_error = e.what();
      process->signal(SIGKILL);
      killed = true;
    }
    for (const auto& f : frames) on_frame(f);
    const auto now = std::chrono::steady_clock::now();
    if (stop == Stop::None) {
      if (interrupt_)
        stop = Stop::Shutdown;
      else if (job->cancel_requested)
        stop = Stop::Cancel;
      else if (deadline && now > *deadline)
        stop = Stop::Timeout;
      if (stop != Stop::None) {
        process->signal(SIGTERM);
        stop_asked = now;
      }
    } else if (!killed && now - stop_asked > kStopGrace) {
      process->signal(SIGKILL);
      killed = true;
    }
  }
  // What the process wrote before it ended (the verdict among it).
  try {
    frames.clear();
    while (process->pipe_open() && process->read_frames(std::chrono::milliseconds(0), frames) > 0) {
    }
    for (const auto& f : frames) on_frame(f);
  } catch (const std::exception& e) {
    if (protocol_error.empty()) protocol_error = e.what();
  }
  const int status = process->wait_status();
  process.reset();

  const bool succeeded = verdict && verdict->state() == pb::JOB_STATE_SUCCEEDED && WIFEXITED(status) &&
                         WEXITSTATUS(status) == 0 && protocol_error.empty();
  if (!succeeded) {
    // A killed process may leave a half-written file behind.
    std::error_code ec;
    for (const auto& entry : fs::directory_iterator(store_.job_dir(id), ec))
      if (entry.path().extension() == ".tmp") fs::remove(entry.path(), ec);
  }
  if (succeeded) {
    {
      std::lock_guard<std::mutex> g(job->lock);
      job->record.set_result_bytes(verdict->result_bytes());
      job->record.set_output_triangles(verdict->output_triangles());
      job->record.set_intersecting_pairs_left(verdict->intersecting_pairs_left());
    }
    set_state(*job, pb::JOB_STATE_SUCCEEDED);
    log_line("job " + id + " finished: " + verdict->message());
    return;
  }
  const std::string where = last_stage.empty() ? " before it reported any progress" : " in stage " + last_stage;
  switch (stop) {
    case Stop::Shutdown:
      // Not counted as an attempt: the job did nothing wrong, the server was asked to stop.
      try {
        store_.set_attempts(id, attempt - 1);
      } catch (const std::exception&) {
      }
      set_state(*job, pb::JOB_STATE_QUEUED, pb::ERROR_KIND_UNSPECIFIED, "");
      log_line("job " + id + " interrupted by the shutdown; it stays queued on disk");
      return;
    case Stop::Cancel:
      fail(pb::ERROR_KIND_CANCELLED, "cancelled by a client");
      return;
    case Stop::Timeout: {
      char why[160];
      std::snprintf(why, sizeof why, "timed out: ran longer than the server's job timeout of %g s",
                    options_.job_timeout_seconds);
      fail(pb::ERROR_KIND_TIMED_OUT, why);
      return;
    }
    case Stop::None:
      break;
  }
  if (!protocol_error.empty()) {
    fail(pb::ERROR_KIND_INTERNAL,
         std::string(process_name) + " broke the worker protocol" + where + ": " + protocol_error);
    return;
  }
  const bool exited_cleanly = WIFEXITED(status) && WEXITSTATUS(status) == 0;
  if (verdict && exited_cleanly && verdict->state() == pb::JOB_STATE_FAILED) {
    // The pipeline's own verdict: bad input, a leak, out of memory under --job-memory...
    fail(verdict->error_kind() == pb::ERROR_KIND_UNSPECIFIED ? pb::ERROR_KIND_INTERNAL : verdict->error_kind(),
         verdict->error_message());
    return;
  }
  // A crash: failed at once, not retried (a deterministic crash would only repeat).
  std::string why;
  if (WIFSIGNALED(status)) {
    why = std::string(process_name) + " ended with " + describe_wait_status(status) + where;
    if (verdict && !verdict->error_message().empty()) why += ": " + verdict->error_message();
    if (WTERMSIG(status) == SIGKILL)
      why += " (killed from outside the server: the system may have run out of memory)";
    else if (WTERMSIG(status) == SIGTERM)
      why += " (stopped from outside the server)";
  } else if (WIFEXITED(status) && WEXITSTATUS(status) == 127 && last_stage.empty()) {
    why = std::string(process_name) + " could not be started (" + options_.worker_command + ")";
  } else {
    why = std::string(process_name) + " ended with " + describe_wait_status(status) + where + " without a result";
    if (verdict && !verdict->error_message().empty()) why += ": " + verdict->error_message();
  }
  fail(pb::ERROR_KIND_INTERNAL, why);
}

}  // namespace vdbwrap::server
