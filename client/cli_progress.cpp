#include "cli_progress.h"

#include <sys/ioctl.h>
#include <unistd.h>

#include <algorithm>
#include <cstdio>

namespace vdbwrap::cli {

// Shares of a typical run (the report's stage timings on the test corpus, rounded); they only
// need to keep the figure moving evenly, not to predict the time left.
StageWeights wrap_stage_weights() {
  return {{"read", 3},     {"diagnose input", 6}, {"prepare", 8}, {"refine", 8},   {"flood fill", 6}, {"extract", 10},
          {"project", 30}, {"coarsen", 5},        {"remesh", 8},  {"validate", 6}, {"distances", 8},  {"write", 2}};
}

StageWeights repair_stage_weights() {
  return {{"read", 5},
          {"repair: diagnose input", 10},
          {"repair: local operations", 35},
          {"repair: remove and refill", 35},
          {"repair: diagnose output", 10},
          {"write", 5}};
}

double overall_fraction(const StageWeights& weights, const std::string& stage, double fraction) {
  double total = 0, before = 0, share = -1;
  for (const auto& [name, w] : weights) {
    if (name == stage) {
      before = total;
      share = w;
    }
    total += w;
  }
  if (share < 0 || total <= 0) return -1;
  return (before + share * std::clamp(fraction, 0.0, 1.0)) / total;
}

StderrProgress::StderrProgress(bool quiet, StageWeights weights)
    : quiet_(quiet), tty_(::isatty(2) == 1), weights_(std::move(weights)), start_(std::chrono::steady_clock::now()) {}

void StderrProgress::progress(const std::string& stage, double fraction, const std::string& message) {
  if (quiet_) return;
  std::lock_guard<std::mutex> g(lock_);
  const auto now = std::chrono::steady_clock::now();
  if (!tty_ || weights_.empty()) {
    const double t = std::chrono::duration<double>(now - start_).count();
    std::fprintf(stderr, "[%7.2fs] %-15s %3.0f%%  %s\n", t, stage.c_str(), 100.0 * fraction, message.c_str());
    std::fflush(stderr);
    return;
  }
  // The figure never goes back: a stage may report a lower fraction than the last one.
  const double f = overall_fraction(weights_, stage, fraction);
  if (f >= 0) overall_ = std::max(overall_, f);
  // Redraw on a new stage at once, otherwise at most ten times a second.
  if (stage == last_stage_ && now - last_draw_ < std::chrono::milliseconds(100)) return;
  last_stage_ = stage;
  last_draw_ = now;
  draw(stage, message);
}

void StderrProgress::draw(const std::string& stage, const std::string& message) {
  char head[16];
  std::snprintf(head, sizeof head, "[%3.0f%%] ", 100.0 * overall_);
  std::string line = head + stage + (message.empty() ? "" : ": " + message);
  struct winsize ws {};
  const size_t cols = (::ioctl(2, TIOCGWINSZ, &ws) == 0 && ws.ws_col > 10) ? ws.ws_col : 100;
  if (line.size() >= cols) line = line.substr(0, cols - 1);
  std::fprintf(stderr, "\r\033[K%s", line.c_str());
  std::fflush(stderr);
  drawn_ = true;
}

void StderrProgress::complete(const std::string& message) {
  {
    std::lock_guard<std::mutex> g(lock_);
    if (quiet_ || !tty_ || weights_.empty()) return;
    overall_ = 1.0;
    draw("done", message);
  }
  finish();
}

void StderrProgress::finish() {
  std::lock_guard<std::mutex> g(lock_);
  if (drawn_) {
    std::fputs("\n", stderr);
    std::fflush(stderr);
  }
  drawn_ = false;
}

}  // namespace vdbwrap::cli
