#include "html_output.h"

#include <chrono>
#include <cstdio>
#include <fstream>

#include "output_paths.h"
#include "vdbwrap/html_report.h"

namespace vdbwrap::cli {

void HtmlOutput::add_to(CLI::App* cmd) {
  cmd->add_option("--html", path_,
                  "Write a self-contained HTML report: the input and the wrap in a 3-D viewer (deviation, parts, "
                  "defects, feature curves, the leak path) beside the report's numbers")
      ->group("Output");
}

void HtmlOutput::check() {
  if (path_.empty()) return;
  check_output_path("--html", path_);
  three_js_ = find_three_js();
}

std::string HtmlOutput::write(const Mesh& input, const Mesh* wrap, const std::string& report_json,
                              const DeviationField* deviation, const std::string& title) const {
  const auto start = std::chrono::steady_clock::now();
  HtmlReportData data;
  data.input = &input;
  data.wrap = wrap;
  data.report_json = report_json;
  data.deviation = wrap ? deviation : nullptr;
  data.title = title;
  const std::string page = html_report(data, read_three_js(three_js_));
  const std::string tmp = path_ + ".tmp";
  {
    std::ofstream out(tmp, std::ios::binary);
    out << page;
    if (!out) throw Error(ErrorKind::OutputFailed, path_ + ": cannot write the HTML report");
  }
  if (std::rename(tmp.c_str(), path_.c_str()) != 0)
    throw Error(ErrorKind::OutputFailed, path_ + ": cannot write the HTML report");
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  char line[256];
  std::snprintf(line, sizeof line, "page %s (%.1f MB, %.2fs)", path_.c_str(), double(page.size()) / 1e6, seconds);
  return line;
}

}  // namespace vdbwrap::cli
