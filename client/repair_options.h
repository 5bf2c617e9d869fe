// The repair parameters on the command line, shared by `vdbwrap repair` (in-process) and
// `vdbwrap submit --repair` (remote): one definition of every option, its help and its checks.
#pragma once
#include <CLI/CLI.hpp>

#include <string>
#include <vector>

#include "vdbwrap/repair.h"

namespace vdbwrap::cli {

class RepairOptions {
 public:
  // with_threads: false where the command has its own --threads (submit's wrap options).
  void add_to(CLI::App* cmd, bool with_threads);
  // After parsing: the defaults with every option given applied. Throws Error(InvalidArgument).
  RepairParams resolve() const;
  // The options given on the command line (their names), for commands where they need --repair.
  std::vector<std::string> given() const;

 private:
  RepairParams p_;
  std::string max_deviation_ = "0.5%";
  bool no_fair_ = false, keep_pieces_ = false, no_unite_ = false;
  std::vector<CLI::Option*> options_;
};

}  // namespace vdbwrap::cli
