// Wall time and peak resident memory of a pipeline stage (Linux /proc; zero elsewhere).
#pragma once
#include <chrono>
#include <string>

#include "vdbwrap/report.h"

namespace vdbwrap {

double current_peak_memory_mb();  // VmHWM
void reset_peak_memory();         // so the next reading is this stage's own peak

class StageTimer {
 public:
  StageTimer(std::string name, std::vector<StageStats>& out) : name_(std::move(name)), out_(out) {
    reset_peak_memory();
    start_ = std::chrono::steady_clock::now();
  }
  ~StageTimer() {
    StageStats s;
    s.name = name_;
    s.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
    s.peak_memory_mb = current_peak_memory_mb();
    out_.push_back(s);
  }

 private:
  std::string name_;
  std::vector<StageStats>& out_;
  std::chrono::steady_clock::time_point start_;
};

}  // namespace vdbwrap
