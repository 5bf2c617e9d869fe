// Crash isolation: each job runs in its own process, so a crashing, runaway or killed job
// fails alone while the server serves on and keeps every accepted job.
#include "service_harness.h"

using namespace server_test;

namespace {

// --- crash isolation: each job in its own process ----------------------------------------
// The misbehaving jobs run under tests/server_worker_hook.cpp (--worker-command), which
// crashes or hangs when the job's file name says so and runs the real worker otherwise.

// The processes whose parent is `parent`, with their state letter (R, S, Z...).
std::map<pid_t, char> children_of(pid_t parent) {
  std::map<pid_t, char> out;
  std::error_code ec;
  for (const auto& entry : fs::directory_iterator("/proc", ec)) {
    const std::string name = entry.path().filename().string();
    if (name.empty() || !std::all_of(name.begin(), name.end(), ::isdigit)) continue;
    const std::string stat = read_file(entry.path() / "stat");
    const size_t close = stat.rfind(')');
    if (close == std::string::npos) continue;
    std::istringstream rest(stat.substr(close + 1));
    char state = 0;
    pid_t ppid = 0;
    if (rest >> state >> ppid && ppid == parent) out[pid_t(std::stoi(name))] = state;
  }
  return out;
}

bool process_gone(pid_t pid, std::chrono::seconds limit) {
  const auto deadline = Clock::now() + limit;
  for (;;) {
    const std::string stat = read_file("/proc/" + std::to_string(pid) + "/stat");
    const size_t close = stat.rfind(')');
    if (stat.empty() || (close != std::string::npos && close + 2 < stat.size() && stat[close + 2] == 'Z')) return true;
    if (Clock::now() > deadline) return false;
    std::this_thread::sleep_for(20ms);
  }
}

// Asks the health service every 100 ms on its own channel until stopped; counts the answers
// that were not SERVING.
class HealthWatch {
 public:
  explicit HealthWatch(const std::string& address)
      : channel_(grpc::CreateChannel(address, grpc::InsecureChannelCredentials())), thread_([this] { loop(); }) {}
  ~HealthWatch() { stop(); }
  void stop() {
    done_ = true;
    if (thread_.joinable()) thread_.join();
  }
  int asked() const { return asked_; }
  int failed() const { return failed_; }

 private:
  void loop() {
    while (!done_) {
      ++asked_;
      if (health(channel_, "vdbwrap.v1.Jobs") != 1) ++failed_;
      std::this_thread::sleep_for(100ms);
    }
  }
  std::shared_ptr<grpc::Channel> channel_;
  std::atomic<bool> done_{false};
  std::atomic<int> asked_{0}, failed_{0};
  std::thread thread_;
};

TEST_F(Service, CrashingJobFailsAloneWhileTheServerServesOn) {
  ServerProcess& s = server({"--workers", "2", "--worker-command", VDBWRAP_WORKER_HOOK});
  HealthWatch health_watch(s.address());
  Client c(s.address());
  std::vector<std::string> good = {c.submit_ok("two_objects_mixed_case_names.stl"), c.submit_ok("fuze.obj")};
  SubmitOutcome crash = c.submit(data("fuze.obj"), "crash-segv.obj", coarse());
  ASSERT_TRUE(crash.status.ok()) << crash.status.error_message();
  good.push_back(c.submit_ok("unit_sphere.STL"));
  SubmitOutcome early = c.submit(data("fuze.obj"), "exit-early.obj", coarse());
  SubmitOutcome garbage = c.submit(data("fuze.obj"), "garbage.obj", coarse());
  ASSERT_TRUE(early.status.ok() && garbage.status.ok());
  // An upload whose check crashes the mesh reader is refused, and no job is created.
  SubmitOutcome unreadable = c.submit(data("fuze.obj"), "crash-read.obj", coarse());
  EXPECT_EQ(unreadable.status.error_code(), grpc::StatusCode::INTERNAL);
  EXPECT_NE(unreadable.status.error_message().find(
                "crash-read.obj: the mesh reader's process ended with signal 11 (SIGSEGV)"),
            std::string::npos)
      << unreadable.status.error_message();
  EXPECT_EQ(s.jobs_on_disk(), 6u);

  pb::JobStatus crashed = c.wait_done(crash.job_id, 60s);
  EXPECT_EQ(crashed.state(), pb::JOB_STATE_FAILED);
  EXPECT_EQ(crashed.error_kind(), pb::ERROR_KIND_INTERNAL);
  EXPECT_NE(crashed.error_message().find("the wrap process ended with signal 11 (SIGSEGV) in stage extract"),
            std::string::npos)
      << crashed.error_message();
  for (const auto& id : good) {
    pb::JobStatus st = c.wait_done(id, 120s);
    ASSERT_EQ(st.state(), pb::JOB_STATE_SUCCEEDED) << st.spec().file_name() << ": " << st.error_message();
    std::string bytes;
    ASSERT_TRUE(c.download(id, bytes).ok());
    expect_valid_result(bytes, vdbwrap::io::format_from_extension(st.spec().file_name()), st.spec().file_name());
  }
  // A process that exits without a verdict, or writes what is not a frame, fails its job alone.
  pb::JobStatus ended = c.wait_done(early.job_id, 60s);
  EXPECT_EQ(ended.state(), pb::JOB_STATE_FAILED);
  EXPECT_NE(ended.error_message().find("the wrap process ended with exit code 3 in stage read without a result"),
            std::string::npos)
      << ended.error_message();
  pb::JobStatus broken = c.wait_done(garbage.job_id, 60s);
  EXPECT_EQ(broken.state(), pb::JOB_STATE_FAILED);
  EXPECT_NE(broken.error_message().find("broke the worker protocol"), std::string::npos) << broken.error_message();
  // The watchers saw the crash as the job's last event, with the reason.
  grpc::Status st;
  std::vector<pb::ProgressEvent> events = c.watch(crash.job_id, st, 10s);
  ASSERT_TRUE(st.ok()) << st.error_message();
  ASSERT_FALSE(events.empty());
  EXPECT_EQ(events.back().state(), pb::JOB_STATE_FAILED);
  EXPECT_NE(events.back().error_message().find("SIGSEGV"), std::string::npos);
  // The failure is final: no attempt to run it again.
  std::this_thread::sleep_for(500ms);
  EXPECT_EQ(c.status(crash.job_id).state(), pb::JOB_STATE_FAILED);
  health_watch.stop();
  EXPECT_GT(health_watch.asked(), 5);
  EXPECT_EQ(health_watch.failed(), 0) << "the health service did not answer SERVING throughout";
  // Every job process was reaped: no children left, zombies or not.
  EXPECT_TRUE(children_of(s.pid()).empty());
  EXPECT_NE(s.log().find("failed: the wrap process ended with signal 11 (SIGSEGV) in stage extract"), std::string::npos)
      << s.log();
  EXPECT_EQ(s.kill(SIGTERM), 0);
}

TEST_F(Service, JobOverTheMemoryLimitFailsAlone) {
  // On one thread, a coarse wrap of fuze.obj fits in about 100 MiB; at 0.3 % it needs over 200.
  auto one_thread = [](double percent) {
    pb::WrapParameters p = coarse(percent);
    p.set_threads(1);
    return p;
  };
  ServerProcess& s = server({"--workers", "2", "--job-memory", "150M"});
  HealthWatch health_watch(s.address());
  Client c(s.address());
  std::string big = c.submit_ok("fuze.obj", one_thread(0.3));
  std::string small = c.submit_ok("fuze.obj", one_thread(3));
  pb::JobStatus over = c.wait_done(big, 120s);
  EXPECT_EQ(over.state(), pb::JOB_STATE_FAILED);
  EXPECT_EQ(over.error_kind(), pb::ERROR_KIND_INTERNAL);
  EXPECT_NE(over.error_message().find("out of memory"), std::string::npos) << over.error_message();
  EXPECT_NE(over.error_message().find("--job-memory"), std::string::npos) << over.error_message();
  EXPECT_EQ(c.wait_done(small, 120s).state(), pb::JOB_STATE_SUCCEEDED);
  health_watch.stop();
  EXPECT_EQ(health_watch.failed(), 0);
  // The limit is what failed it: the same job succeeds on a server without one.
  ServerProcess& unlimited = server({}, "b");
  Client u(unlimited.address());
  EXPECT_EQ(u.wait_done(u.submit_ok("fuze.obj", one_thread(0.3)), 120s).state(), pb::JOB_STATE_SUCCEEDED);
}

TEST_F(Service, CancelAndTimeoutKillAJobProcessThatIgnoresThem) {
  ServerProcess& s = server({"--workers", "2", "--job-timeout", "2", "--worker-command", VDBWRAP_WORKER_HOOK});
  Client c(s.address());
  SubmitOutcome timed = c.submit(data("fuze.obj"), "hang-timeout.obj", coarse());
  SubmitOutcome cancelled = c.submit(data("fuze.obj"), "hang-cancel.obj", coarse());
  ASSERT_TRUE(timed.status.ok() && cancelled.status.ok());
  c.poll(
      cancelled.job_id, [](const pb::JobStatus& st) { return st.stage() == "read"; }, 30s);
  const auto t0 = Clock::now();
  ASSERT_TRUE(c.cancel(cancelled.job_id).ok());
  // The stand-in ignores SIGTERM: it ends by the SIGKILL that follows a grace period.
  pb::JobStatus st = c.wait_done(cancelled.job_id, 30s);
  EXPECT_EQ(st.state(), pb::JOB_STATE_CANCELLED);
  EXPECT_LT(Clock::now() - t0, 6s);
  pb::JobStatus late = c.wait_done(timed.job_id, 30s);
  EXPECT_EQ(late.state(), pb::JOB_STATE_FAILED);
  EXPECT_EQ(late.error_kind(), pb::ERROR_KIND_TIMED_OUT);
  EXPECT_TRUE(children_of(s.pid()).empty());
}

TEST_F(Service, ServerKilledWhileAJobRunsGivesUpAfterMaxAttempts) {
  ServerProcess& s =
      server({"--workers", "1", "--max-attempts", "2", "--job-memory", "3G", "--worker-command", VDBWRAP_WORKER_HOOK});
  std::string id;
  {
    Client c(s.address());
    SubmitOutcome o = c.submit(data("fuze.obj"), "hang.obj", coarse());
    ASSERT_TRUE(o.status.ok());
    id = o.job_id;
  }
  for (int run = 1; run <= 2; ++run) {
    Client c(s.address());
    c.poll(
        id, [](const pb::JobStatus& st) { return st.state() == pb::JOB_STATE_RUNNING && st.stage() == "read"; }, 30s);
    std::map<pid_t, char> workers = children_of(s.pid());
    ASSERT_EQ(workers.size(), 1u) << "run " << run;
    if (run == 1) {
      // How the server started it: fds 0-3 only, its own process group, the memory limit.
      const fs::path proc = "/proc/" + std::to_string(workers.begin()->first);
      std::set<std::string> fds;
      for (const auto& e : fs::directory_iterator(proc / "fd")) fds.insert(e.path().filename().string());
      EXPECT_EQ(fds, (std::set<std::string>{"0", "1", "2", "3"}));
      const std::string stat = read_file(proc / "stat");
      std::istringstream rest(stat.substr(stat.rfind(')') + 1));
      char state = 0;
      pid_t ppid = 0, pgrp = 0;
      rest >> state >> ppid >> pgrp;
      EXPECT_EQ(pgrp, workers.begin()->first);
      EXPECT_TRUE(std::regex_search(read_file(proc / "limits"), std::regex("Max data size +3221225472 +3221225472 ")))
          << read_file(proc / "limits");
    }
    EXPECT_EQ(s.kill(SIGKILL), 128 + SIGKILL);
    // The job's process does not outlive the server.
    EXPECT_TRUE(process_gone(workers.begin()->first, 10s)) << "run " << run;
    s.start();
  }
  Client c(s.address());
  pb::JobStatus st = c.wait_done(id, 30s);
  EXPECT_EQ(st.state(), pb::JOB_STATE_FAILED);
  EXPECT_NE(st.error_message().find("the server stopped 2 times while this job ran"), std::string::npos)
      << st.error_message();
  EXPECT_TRUE(children_of(s.pid()).empty());
  // Once failed, it stays failed: a further restart queues nothing.
  EXPECT_EQ(s.kill(SIGKILL), 128 + SIGKILL);
  s.start();
  Client again(s.address());
  EXPECT_EQ(again.status(id).state(), pb::JOB_STATE_FAILED);
  const std::string log = s.log();
  EXPECT_NE(log.rfind("0 job(s) queued again, 1 ended job(s) kept"), std::string::npos) << log;
  EXPECT_EQ(read_file(s.spool() / "jobs" / id / "attempts"), "2\n");
}

TEST_F(Service, RetainPrunesOldEndedJobs) {
  ServerProcess& s = server();
  std::string old_id, new_id;
  {
    Client c(s.address());
    old_id = c.submit_ok("two_objects_mixed_case_names.stl");
    new_id = c.submit_ok("unit_sphere.STL");
    ASSERT_EQ(c.wait_done(old_id).state(), pb::JOB_STATE_SUCCEEDED);
    ASSERT_EQ(c.wait_done(new_id).state(), pb::JOB_STATE_SUCCEEDED);
  }
  EXPECT_EQ(s.kill(SIGTERM), 0);
  // One job ended eight days ago.
  const fs::path record = s.spool() / "jobs" / old_id / "job.json";
  const int64_t eight_days_ago =
      std::chrono::duration_cast<std::chrono::milliseconds>(std::chrono::system_clock::now().time_since_epoch())
          .count() -
      8 * 86400 * 1000LL;
  const std::string json = std::regex_replace(read_file(record), std::regex("\"finished_unix_ms\": \"[0-9]+\""),
                                              "\"finished_unix_ms\": \"" + std::to_string(eight_days_ago) + "\"");
  ASSERT_NE(json, read_file(record));
  write_file(record, json);

  // The same spool, with a retention of seven days.
  servers_.push_back(std::make_unique<ServerProcess>(s.spool(), dir_ / "server_retain.log",
                                                     std::vector<std::string>{"--retain", "7d"}));
  ServerProcess& kept = *servers_.back();
  kept.start();
  Client c(kept.address());
  pb::JobStatus gone;
  EXPECT_EQ(c.status(old_id, gone).error_code(), grpc::StatusCode::NOT_FOUND);
  EXPECT_FALSE(fs::exists(s.spool() / "jobs" / old_id));
  std::string bytes;
  EXPECT_TRUE(c.download(new_id, bytes).ok());
  EXPECT_EQ(kept.jobs_on_disk(), 1u);
  EXPECT_EQ(kept.kill(SIGTERM), 0);

  // Periodically too, and never a job that has not ended.
  ServerProcess& quick = server({"--retain", "2s", "--workers", "2", "--worker-command", VDBWRAP_WORKER_HOOK}, "b");
  Client q(quick.address());
  SubmitOutcome hanging = q.submit(data("fuze.obj"), "hang.obj", coarse());
  ASSERT_TRUE(hanging.status.ok());
  std::string done = q.submit_ok("two_objects_mixed_case_names.stl");
  ASSERT_EQ(q.wait_done(done).state(), pb::JOB_STATE_SUCCEEDED);
  EXPECT_TRUE(q.status(done, gone).ok()) << "pruned at once";
  const auto deadline = Clock::now() + 15s;
  while (Clock::now() < deadline && q.status(done, gone).error_code() != grpc::StatusCode::NOT_FOUND)
    std::this_thread::sleep_for(100ms);
  EXPECT_EQ(q.status(done, gone).error_code(), grpc::StatusCode::NOT_FOUND);
  EXPECT_EQ(q.status(hanging.job_id).state(), pb::JOB_STATE_RUNNING);
  EXPECT_EQ(quick.jobs_on_disk(), 1u);
  EXPECT_NE(quick.log().find("pruned"), std::string::npos);

  // A duration that is not one is refused at start.
  std::string cmd = std::string(VDBWRAP_SERVER) + " --listen 127.0.0.1:0 --spool " + (dir_ / "spool_c").string() +
                    " --retain 5x 2> " + (dir_ / "c.log").string();
  int status = std::system(cmd.c_str());
  EXPECT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 2);
  EXPECT_NE(read_file(dir_ / "c.log").find("--retain 5x"), std::string::npos);
}

}  // namespace
