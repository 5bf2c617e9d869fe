// A stand-in for the server's worker process, for the crash-isolation tests only (started
// with vdbwrap-server's hidden --worker-command; no client can reach it). When the job's file
// name holds a marker it misbehaves after reporting a stage, as a broken pipeline would:
//   "crash-segv"  reports "read" and "extract", then raise(SIGSEGV)
//   "hang"        reports "read", then sleeps forever and ignores SIGTERM (the server must
//                 SIGKILL it)
//   "exit-early"  reports "read", then exits with code 3 without a verdict
//   "garbage"     reports "read", then writes bytes that are not a frame, then sleeps
// and for an upload's check (--check-upload FILE FORMAT NAME):
//   "crash-read"  raise(SIGSEGV), as a mesh reader crashing on a hostile file would
// Anything else runs the real worker (VDBWRAP_SERVER with the same arguments).
#include <signal.h>
#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <string>

#include "worker_protocol.h"

#ifndef VDBWRAP_SERVER
#define VDBWRAP_SERVER "vdbwrap-server"
#endif

namespace {

void report_stage(const char* stage) {
  vdbwrap::v1::JobStatus frame;
  frame.set_state(vdbwrap::v1::JOB_STATE_RUNNING);
  frame.set_stage(stage);
  frame.set_message("test worker");
  vdbwrap::server::write_frame(vdbwrap::server::kWorkerEventsFd, frame);
}

}  // namespace

[[noreturn]] void run_the_real_worker(char** argv) {
  argv[0] = const_cast<char*>(VDBWRAP_SERVER);
  ::execv(argv[0], argv);
  std::perror("execv " VDBWRAP_SERVER);
  std::_Exit(127);
}

int main(int argc, char** argv) {
  if (argc == 5 && std::string(argv[1]) == "--check-upload") {
    if (std::string(argv[4]).find("crash-read") != std::string::npos) ::raise(SIGSEGV);
    run_the_real_worker(argv);
  }
  if (argc != 3 || std::string(argv[1]) != "--worker") {
    std::fprintf(stderr, "usage: %s --worker JOB_DIR\n", argv[0]);
    return 2;
  }
  std::ifstream in(std::string(argv[2]) + "/job.json");
  std::stringstream record;
  record << in.rdbuf();
  // The marker is looked for in the file name only ("file_name": "...").
  const std::string text = record.str();
  const size_t at = text.find("\"file_name\"");
  const std::string name = at == std::string::npos ? "" : text.substr(at, text.find('\n', at) - at);
  in.close();  // the process keeps only what the server gave it (fds 0-3)
  if (name.find("crash-segv") != std::string::npos) {
    report_stage("read");
    report_stage("extract");
    ::raise(SIGSEGV);
  }
  if (name.find("hang") != std::string::npos) {
    report_stage("read");
    ::signal(SIGTERM, SIG_IGN);
    for (;;) ::pause();
  }
  if (name.find("exit-early") != std::string::npos) {
    report_stage("read");
    return 3;
  }
  if (name.find("garbage") != std::string::npos) {
    report_stage("read");
    const char junk[] = "\xff\xff\xff\x7fnot a frame";
    if (::write(vdbwrap::server::kWorkerEventsFd, junk, sizeof junk) < 0) return 1;
    for (;;) ::pause();
  }
  run_the_real_worker(argv);
}
