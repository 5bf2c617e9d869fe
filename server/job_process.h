// One job's worker process as the server sees it: started with fork+exec, its progress and
// verdict frames read from a pipe, signalled, and reaped. Between fork and exec the child
// only makes system calls (no locks, no allocation): it gets the per-job memory limit
// (RLIMIT_DATA), dies with the server (PR_SET_PDEATHSIG), leaves the server's process group
// (a Ctrl-C meant for the server does not reach it), and keeps only fds 0-3 open.
#pragma once
#include <sys/types.h>

#include <chrono>
#include <cstdint>
#include <string>
#include <vector>

#include "worker_protocol.h"

namespace vdbwrap::server {

class JobProcess {
 public:
  // Starts `argv[0]` with `argv`: stdin /dev/null, stdout and stderr the server's, the frames
  // pipe on fd 3. memory_limit 0: none. Throws std::runtime_error when it cannot start.
  JobProcess(const std::vector<std::string>& argv, uint64_t memory_limit);
  // Kills (SIGKILL) and reaps a process still running: no zombie is left behind.
  ~JobProcess();
  JobProcess(const JobProcess&) = delete;
  JobProcess& operator=(const JobProcess&) = delete;

  // Waits up to `timeout` for bytes on the pipe and appends the complete frames to `out`;
  // returns how many bytes came (0: none, or the pipe closed: pipe_open() says which).
  // Throws std::runtime_error for bytes that are not frames.
  size_t read_frames(std::chrono::milliseconds timeout, std::vector<pb::JobStatus>& out);
  bool pipe_open() const { return pipe_fd_ >= 0; }

  // Signals the process and anything it started (its process group); nothing once reaped.
  void signal(int sig);
  // Reaps the process if it ended (without waiting); true once it has.
  bool reap();
  bool ended() const { return reaped_; }
  int wait_status() const { return status_; }  // waitpid's status, once ended()
  pid_t pid() const { return pid_; }

 private:
  pid_t pid_ = -1;
  int pipe_fd_ = -1;
  bool reaped_ = false;
  int status_ = 0;
  FrameReader reader_;
};

// "signal 11 (SIGSEGV)" or "exit code 3", from a waitpid status.
std::string describe_wait_status(int status);

}  // namespace vdbwrap::server
