// `vdbwrap wrap --html FILE`: the self-contained HTML report (core's html_report) written
// beside the other outputs. Everything it needs is checked before the wrap starts: the path,
// as for -o, and three.js, which the page embeds (exit code 2 when it is missing).
#pragma once
#include <CLI/CLI.hpp>

#include <cstdint>
#include <string>
#include <vector>

#include "vdbwrap/deviation.h"
#include "vdbwrap/mesh.h"

namespace vdbwrap::cli {

class HtmlOutput {
 public:
  void add_to(CLI::App* cmd);
  bool wanted() const { return !path_.empty(); }
  // Throws Error(InvalidArgument) for a path in a missing folder or when three.js is not found.
  void check();
  // wrap: null when the run stopped (the page then shows the leak of the report, if any);
  // else with its deviation from the input (measured once by the caller, who may write it to
  // a file too). Returns the line to print when not quiet ("page FILE (SIZE, TIME)").
  // Throws Error(OutputFailed) when the file cannot be written.
  std::string write(const Mesh& input, const Mesh* wrap, const std::string& report_json,
                    const DeviationField* deviation, const std::string& title) const;
  const std::string& path() const { return path_; }

 private:
  std::string path_, three_js_;
};

}  // namespace vdbwrap::cli
