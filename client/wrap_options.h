// The wrap parameters on the command line, shared by `vdbwrap wrap` (in-process) and
// `vdbwrap submit` (remote): one definition of every option, its help and its checks.
// A parameter file (--params FILE, JSON or YAML in the form of the API's WrapParameters
// message) gives the starting values; options given on the command line override it.
#pragma once
#include <CLI/CLI.hpp>

#include <functional>
#include <string>
#include <vector>

#include "vdbwrap/wrap.h"

namespace vdbwrap::cli {

class WrapOptions {
 public:
  // threads_help differs: local cores or the server's.
  void add_to(CLI::App* cmd, const std::string& threads_help);
  // After parsing: the parameter file (if any), then every option given. Throws
  // Error(InvalidArgument) naming the option or the file.
  WrapParams resolve() const;
  // The options given on the command line (their names, --params included).
  std::vector<std::string> given() const;

 private:
  struct Binding {
    CLI::Option* option;
    std::function<void(WrapParams&)> apply;
  };
  template <typename T>
  CLI::Option* bind(CLI::App* cmd, const std::string& name, T& value, const std::string& help,
                    std::function<void(WrapParams&)> apply);

  std::vector<Binding> bindings_;
  WrapParams cli_;
  std::string base_size_ = "1%", volume_ = "outside", gap_closure_, contact_floor_, params_file_;
  std::vector<std::string> control_volumes_, part_sizes_, contact_rules_;
  bool no_features_ = false, no_distances_ = false, no_remesh_ = false;
  bool sliver_removal_ = false;
  bool proximity_refinement_ = false;
  bool two_sided_sheets_ = false;
  bool refine_far_cells_ = false;
  bool refine_where_far_ = true;
};

}  // namespace vdbwrap::cli
