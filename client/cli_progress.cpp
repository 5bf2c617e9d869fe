#include "cli_progress.h"

#include <cstdio>

namespace vdbwrap::cli {

void StderrProgress::progress(const std::string& stage, double fraction, const std::string& message) {
  if (quiet_) return;
  std::lock_guard<std::mutex> g(lock_);
  double t = std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
  std::fprintf(stderr, "[%7.2fs] %-15s %3.0f%%  %s\n", t, stage.c_str(), 100.0 * fraction, message.c_str());
  std::fflush(stderr);
}

}  // namespace vdbwrap::cli
