#include "job_process.h"

#include <errno.h>
#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <string.h>
#include <sys/prctl.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <stdexcept>

namespace vdbwrap::server {

namespace {

[[noreturn]] void child_fail() { ::_exit(127); }

// The child between fork and exec: async-signal-safe calls only.
[[noreturn]] void exec_child(char* const* argv, pid_t parent, int events_fd, int null_fd, const rlimit* limit,
                             int max_fd) {
  if (::prctl(PR_SET_PDEATHSIG, SIGKILL) != 0 || ::getppid() != parent) child_fail();
  if (limit && ::setrlimit(RLIMIT_DATA, limit) != 0) child_fail();
  ::setpgid(0, 0);
  // The server blocks SIGTERM/SIGINT for its sigwait and ignores SIGPIPE; the job starts clean.
  sigset_t none;
  sigemptyset(&none);
  ::sigprocmask(SIG_SETMASK, &none, nullptr);
  struct sigaction dfl {};
  dfl.sa_handler = SIG_DFL;
  for (int sig : {SIGPIPE, SIGTERM, SIGINT, SIGCHLD}) ::sigaction(sig, &dfl, nullptr);
  if (::dup2(null_fd, 0) < 0) child_fail();
  if (events_fd == kWorkerEventsFd) {
    if (::fcntl(events_fd, F_SETFD, 0) != 0) child_fail();  // dup2 onto itself keeps O_CLOEXEC
  } else if (::dup2(events_fd, kWorkerEventsFd) < 0) {
    child_fail();
  }
  // Whatever else is open (a file an upload writes to, without O_CLOEXEC) stays with the server.
  if (::close_range(kWorkerEventsFd + 1, ~0u, 0) != 0)  // kernels before 5.9
    for (int fd = kWorkerEventsFd + 1; fd < max_fd; ++fd) ::close(fd);
  ::execv(argv[0], argv);
  child_fail();
}

}  // namespace

JobProcess::JobProcess(const std::vector<std::string>& args, uint64_t memory_limit) {
  if (args.empty()) throw std::runtime_error("no worker command");
  // Everything the child needs is prepared before fork: it must not allocate.
  std::vector<std::string> copy = args;
  std::vector<char*> argv;
  for (auto& a : copy) argv.push_back(a.data());
  argv.push_back(nullptr);
  rlimit limit{rlim_t(memory_limit), rlim_t(memory_limit)};
  int fds[2];
  if (::pipe2(fds, O_CLOEXEC) != 0) throw std::runtime_error(std::string("cannot create a pipe: ") + strerror(errno));
  int null_fd = ::open("/dev/null", O_RDONLY | O_CLOEXEC);
  if (null_fd < 0) {
    ::close(fds[0]);
    ::close(fds[1]);
    throw std::runtime_error("cannot open /dev/null");
  }
  rlimit files{};
  const int max_fd =
      ::getrlimit(RLIMIT_NOFILE, &files) == 0 && files.rlim_cur != RLIM_INFINITY && files.rlim_cur < (1u << 20)
          ? int(files.rlim_cur)
          : 1 << 20;
  const pid_t parent = ::getpid();
  pid_t pid = ::fork();
  if (pid == 0) exec_child(argv.data(), parent, fds[1], null_fd, memory_limit > 0 ? &limit : nullptr, max_fd);
  const int fork_errno = errno;
  ::close(fds[1]);
  ::close(null_fd);
  if (pid < 0) {
    ::close(fds[0]);
    throw std::runtime_error(std::string("cannot start a job process: ") + strerror(fork_errno));
  }
  ::setpgid(pid, pid);  // also here, so that signal() reaches the group from the start
  pid_ = pid;
  pipe_fd_ = fds[0];
}

JobProcess::~JobProcess() {
  if (!reaped_ && pid_ > 0) {
    signal(SIGKILL);
    while (::waitpid(pid_, &status_, 0) < 0 && errno == EINTR) {
    }
    reaped_ = true;
  }
  if (pipe_fd_ >= 0) ::close(pipe_fd_);
}

size_t JobProcess::read_frames(std::chrono::milliseconds timeout, std::vector<pb::JobStatus>& out) {
  if (pipe_fd_ < 0) return 0;
  pollfd p{pipe_fd_, POLLIN, 0};
  if (::poll(&p, 1, int(timeout.count())) <= 0) return 0;
  char buffer[1 << 16];
  ssize_t got = ::read(pipe_fd_, buffer, sizeof buffer);
  if (got < 0 && (errno == EINTR || errno == EAGAIN)) return 0;
  if (got <= 0) {
    ::close(pipe_fd_);
    pipe_fd_ = -1;
    return 0;
  }
  reader_.feed(buffer, size_t(got));
  pb::JobStatus frame;
  while (reader_.next(frame)) out.push_back(frame);
  return size_t(got);
}

void JobProcess::signal(int sig) {
  if (reaped_ || pid_ <= 0) return;  // a reaped pid may belong to someone else by now
  if (::kill(-pid_, sig) != 0) ::kill(pid_, sig);
}

bool JobProcess::reap() {
  if (reaped_) return true;
  pid_t r = ::waitpid(pid_, &status_, WNOHANG);
  if (r == pid_) reaped_ = true;
  return reaped_;
}

std::string describe_wait_status(int status) {
  if (WIFSIGNALED(status)) {
    const int sig = WTERMSIG(status);
    const char* abbrev = ::sigabbrev_np(sig);
    return "signal " + std::to_string(sig) + (abbrev ? " (SIG" + std::string(abbrev) + ")" : std::string());
  }
  if (WIFEXITED(status)) return "exit code " + std::to_string(WEXITSTATUS(status));
  return "status " + std::to_string(status);
}

}  // namespace vdbwrap::server
