// The report's account of a two-sided wrap: how much of the input is wrapped from both sides,
// the input's openings the volume may have come in through, and the gap closure that would
// keep it out (a line for the progress log).
#pragma once
#include <cmath>
#include <cstdio>
#include <string>

#include "fit/two_sided.h"
#include "prep/openings.h"
#include "vdbwrap/report.h"

namespace vdbwrap::fit {

// Below this share of the area the progress log says nothing: closed models show up to 4 %
// (nodes around sharp edges and in thin slots judged on the wrong side; corpus at 1 %).
constexpr double kTwoSidedWorthSaying = 0.05;
// An opening wider than this share of the diagonal is the rim of a sheet, not a hole a gap
// closure should bridge.
constexpr double kWidestClosableOpening = 0.25;

// Fills `r`; returns the progress line (empty when little is two-sided).
inline std::string describe_two_sided(const TwoSidedStats& s, const prep::PreparedInput& in, TwoSidedReport& r) {
  r.area_fraction = two_sided_area_fraction(s, in.mesh.points, in.mesh.triangles);
  r.nodes = s.nodes;
  r.nodes_raised = s.nodes_raised;
  const std::vector<prep::Opening> openings = prep::find_openings(in);
  r.openings = openings.size();
  const prep::Opening* widest = nullptr;
  for (const prep::Opening& o : openings)
    if (!widest || o.width > widest->width) widest = &o;
  if (widest) {
    r.largest_opening_centre = widest->centre + in.origin;
    r.largest_opening_width = widest->width;
    // Gap closure sets aside free cells nearer the input than half its value: an opening
    // closes when it is wider than the opening; a tenth more for the cells' positions.
    if (widest->width < kWidestClosableOpening * in.diagonal) r.suggested_gap_closure = 1.1 * widest->width;
  }
  if (r.area_fraction < kTwoSidedWorthSaying) return {};
  char text[400];
  int n =
      std::snprintf(text, sizeof text, "%.1f %% of the input's area is wrapped from both sides", 100 * r.area_fraction);
  if (!widest) {
    std::snprintf(text + n, sizeof text - n, " (the input has no openings: its pieces overlap or are inside out)");
    return text;
  }
  const Vec3& c = r.largest_opening_centre;
  n += std::snprintf(text + n, sizeof text - n,
                     "; the input has %zu opening%s, the widest %.4g wide at (%.6g, %.6g, %.6g)", openings.size(),
                     openings.size() == 1 ? "" : "s", widest->width, c[0], c[1], c[2]);
  if (r.suggested_gap_closure > 0) {
    // Rounded up to two significant digits, in percent of the diagonal.
    double pct = 100 * r.suggested_gap_closure / in.diagonal;
    const double step = std::pow(10.0, std::floor(std::log10(pct)) - 1);
    pct = std::ceil(pct / step) * step;
    // Only a promise about the openings: two-sided places elsewhere (pieces overlapping, a
    // sheet inside the material) stay as they are.
    std::snprintf(text + n, sizeof text - n, ": --gap-closure %.2g%% closes them", pct);
  } else {
    std::snprintf(text + n, sizeof text - n, ": an open sheet, which no gap closure closes");
  }
  return text;
}

}  // namespace vdbwrap::fit
