// Jobs in memory: the queue, the worker threads that each run one job at a time in a worker
// process (job_process.h, worker.h), cancellation (client cancel, --job-timeout, shutdown),
// progress events for watchers, attempts across restarts and the pruning of old jobs
// (--retain). Every state change is written to the JobStore before it is visible to clients.
#pragma once
#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <deque>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "job_store.h"

namespace vdbwrap::server {

// One line on stderr, with a UTC timestamp: "2026-11-21T10:00:00.123Z job <id> started ...".
void log_line(const std::string& text);
int64_t unix_ms_now();

struct Job {
  mutable std::mutex lock;
  std::condition_variable changed;        // notified on every new event
  pb::JobStatus record;                   // guarded by lock; report_json is never set here
  std::vector<pb::ProgressEvent> events;  // guarded by lock; sequence = index + 1
  std::atomic<bool> cancel_requested{false};
  std::chrono::steady_clock::time_point started{};

  pb::JobStatus snapshot() const {
    std::lock_guard<std::mutex> g(lock);
    return record;
  }
};

class JobQueue {
 public:
  struct Options {
    int workers = 1;
    size_t queue_limit = 16;         // most jobs waiting (not counting running ones)
    double job_timeout_seconds = 0;  // 0: none
    std::string advertise;           // copied into each job's record.server
    // The job process: worker_command --worker <job dir>, with RLIMIT_DATA job_memory (0: none).
    std::string worker_command;
    uint64_t job_memory = 0;
    // A job the server stopped (died) under this many times is failed instead of run again.
    int max_attempts = 2;
    double retain_seconds = 0;  // ended jobs older than this are deleted; 0: kept forever
  };
  JobQueue(JobStore& store, Options options);
  ~JobQueue();

  // Loads the spool: unfinished jobs (queued or running when the last server stopped) are
  // queued again, oldest first, unless the server already stopped max_attempts times while
  // one ran (then it fails); finished ones are served, or deleted when older than
  // retain_seconds. Call once, before start().
  void restore();
  // Starts the worker threads, and with retain_seconds the periodic pruning.
  void start();

  // A slot in the queue for an upload about to be received; false when the queue is full.
  bool try_reserve();
  void release_reservation();

  // Stores the upload as a new job (durably) and queues it, using up one reservation. When
  // the record's idempotency key is already known, nothing is stored and that job is
  // returned with duplicate = true. Throws std::runtime_error when the job cannot be stored.
  std::shared_ptr<Job> accept(JobStore::Upload& upload, pb::JobStatus record, bool& duplicate);

  std::shared_ptr<Job> find(const std::string& id) const;
  std::shared_ptr<Job> find_by_key(const std::string& key) const;
  std::vector<std::shared_ptr<Job>> list() const;  // oldest first

  enum class CancelResult { Cancelled, Requested, AlreadyCancelled, AlreadyEnded };
  // A queued job is cancelled at once; a running one is asked to stop (Requested).
  CancelResult cancel(const std::shared_ptr<Job>& job);
  // Deletes an ended job and its files; false (nothing done) for a queued or running job.
  bool remove(const std::shared_ptr<Job>& job);
  // Deletes the ended jobs that finished before cutoff_unix_ms; returns how many.
  size_t prune(int64_t cutoff_unix_ms);

  // Graceful stop: no new job starts; running jobs get grace_seconds to finish, then they are
  // interrupted and left queued on disk for the next start. Joins the workers.
  void shutdown(double grace_seconds);
  bool stopped() const { return stopped_.load(); }

  JobStore& store() { return store_; }
  const Options& options() const { return options_; }

 private:
  void worker();
  void janitor();
  void run(const std::shared_ptr<Job>& job);
  void remove_locked(const std::shared_ptr<Job>& job, const std::string& why);
  // Under job->lock: appends an event and notifies watchers.
  void add_event_locked(Job& job, const std::string& stage, double fraction, const std::string& message);
  // Sets a new state, persists the record, appends an event and notifies.
  void set_state(Job& job, pb::JobState state, pb::ErrorKind kind = pb::ERROR_KIND_UNSPECIFIED,
                 const std::string& error = "");
  void index_locked(const std::shared_ptr<Job>& job);

  JobStore& store_;
  Options options_;
  mutable std::mutex lock_;
  std::condition_variable work_;  // a job was queued, or stop
  std::condition_variable idle_;  // a job finished
  std::map<std::string, std::shared_ptr<Job>> jobs_;
  std::vector<std::shared_ptr<Job>> order_;    // oldest first
  std::map<std::string, std::string> by_key_;  // idempotency key -> job id
  std::deque<std::shared_ptr<Job>> queue_;
  size_t reserved_ = 0;
  size_t running_ = 0;
  bool stop_ = false;
  std::atomic<bool> interrupt_{false};
  std::atomic<bool> stopped_{false};
  std::vector<std::thread> workers_;
  std::thread janitor_;
  std::condition_variable janitor_wake_;  // stop
};

}  // namespace vdbwrap::server
