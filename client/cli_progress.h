// Progress on stderr for the CLI. On a terminal: one line redrawn in place with one overall
// figure computed from stage weights ("[ 42%] project: projecting 80000 nodes"). Otherwise
// (a log, a pipe): one line per stage message with the elapsed time, so a log keeps every step.
#pragma once
#include <chrono>
#include <mutex>
#include <string>
#include <utility>
#include <vector>

#include "vdbwrap/wrap.h"

namespace vdbwrap::cli {

// A command's stages in the order they run, each with its share of a typical run's time.
using StageWeights = std::vector<std::pair<std::string, double>>;
StageWeights wrap_stage_weights();
StageWeights repair_stage_weights();

// The overall fraction (0..1) when `stage` is `fraction` done: the weights of the stages
// before it plus its share. A stage not in the list (an optional one, e.g. the wrap's
// intersection repair) gives -1: the caller keeps the figure it had.
double overall_fraction(const StageWeights& weights, const std::string& stage, double fraction);

class StderrProgress : public ProgressSink {
 public:
  explicit StderrProgress(bool quiet, StageWeights weights = {});
  ~StderrProgress() override { finish(); }
  void progress(const std::string& stage, double fraction, const std::string& message) override;
  // Ends the redrawn line on a terminal, so that what follows starts on a line of its own.
  void finish();
  // The run succeeded: on a terminal, "[100%] message" ends the line (a log needs no extra line).
  void complete(const std::string& message);

 private:
  bool quiet_, tty_;
  StageWeights weights_;
  double overall_ = 0;
  bool drawn_ = false;
  std::string last_stage_;
  std::chrono::steady_clock::time_point start_, last_draw_{};
  std::mutex lock_;

  void draw(const std::string& stage, const std::string& message);  // lock_ held
};

}  // namespace vdbwrap::cli
