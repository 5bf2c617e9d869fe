// Progress lines on stderr for the CLI: one line per stage message, with elapsed time.
#pragma once
#include <chrono>
#include <mutex>
#include <string>

#include "vdbwrap/wrap.h"

namespace vdbwrap::cli {

class StderrProgress : public ProgressSink {
 public:
  explicit StderrProgress(bool quiet) : quiet_(quiet), start_(std::chrono::steady_clock::now()) {}
  void progress(const std::string& stage, double fraction, const std::string& message) override;

 private:
  bool quiet_;
  std::chrono::steady_clock::time_point start_;
  std::mutex lock_;
};

}  // namespace vdbwrap::cli
