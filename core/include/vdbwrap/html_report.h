// The HTML report: one self-contained page (no network at view time) with the input and the
// wrap in a 3-D viewer and the report's numbers beside it. Plain data in, HTML text out; the
// viewer library (three.js) is read from where Debian installs it and embedded in the page.
#pragma once
#include <cstddef>
#include <string>

#include "vdbwrap/deviation.h"
#include "vdbwrap/errors.h"
#include "vdbwrap/mesh.h"

namespace vdbwrap {

struct HtmlReportData {
  const Mesh* input = nullptr;                // required
  const Mesh* wrap = nullptr;                 // none when the wrap failed (a leak): the page shows the leak
  std::string report_json;                    // to_json(WrapReport): the numbers and the leak come from it
  const DeviationField* deviation = nullptr;  // of the wrap against the input: colours and legend
  std::string title;                          // e.g. the input's file name
  // Meshes with more triangles are clustered to about this many for display only (the page says so).
  size_t display_triangles = 300000;
  // The input's self-intersecting triangles (for the defect colouring) are searched up to this size.
  size_t intersection_search_limit = 2000000;
};

// The three.min.js to embed: the file named by the environment variable VDBWRAP_THREE_JS when
// set, else the path configured at build time (CMake VDBWRAP_THREE_JS), else Debian's libjs-three
// paths. Throws Error(InvalidArgument) naming the places tried when there is none.
std::string find_three_js();

// The page. three_js: the text of three.min.js. Throws Error(InvalidArgument) without an
// input mesh or with report text that is not a JSON object.
std::string html_report(const HtmlReportData& data, const std::string& three_js);

// Reads the file find_three_js() names; Error(InvalidArgument) when it is unreadable.
std::string read_three_js(const std::string& path);

}  // namespace vdbwrap
