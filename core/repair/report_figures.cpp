// Report figures read off the finished repair (see report_figures.h).
#include "repair/report_figures.h"

#include <algorithm>
#include <unordered_set>

#include "check/distance_stats.h"
#include "common/vec.h"
#include "vdbwrap/check.h"

namespace vdbwrap::local_repair {

void count_fixed_regions(const Work& w, const std::vector<uint8_t>& by_union,
                         const std::vector<uint8_t>& clean_after_local, RepairReport& report) {
  const auto clean_at_end = clean_regions(w, report.regions_found);
  for (size_t r = 0; r < report.regions_found; ++r) {
    if (by_union[r])
      ++report.fixed_by_union;
    else if (clean_after_local[r])
      ++report.fixed_by_local;
    else if (clean_at_end[r])
      ++report.fixed_by_refill;
    else
      ++report.left_unfixed;
  }
}

std::vector<RepairRegion> describe_regions(const Work& w) {
  std::vector<RepairRegion> out;
  for (const auto& region : group_regions(w.tris, triangles_of(w.pairs), w.pairs)) {
    RepairRegion r;
    r.triangles = region.size();
    std::unordered_set<uint32_t> in(region.begin(), region.end());
    for (const auto& p : w.pairs) r.pairs += in.count(p.a) ? 1 : 0;
    Box3 box;
    for (uint32_t t : region)
      for (uint32_t v : w.tris[t]) box.add(w.points[v]);
    r.bbox_min = box.lo;
    r.bbox_max = box.hi;
    r.center = box.center();
    out.push_back(r);
  }
  return out;
}

void measure_deviation(const Work& w, const std::vector<Tri>& input_tris,
                       const std::vector<std::unique_ptr<SolidTest>>& solids, RepairReport& report) {
  // Metro-style, from the surface the repair changed (elsewhere input and output are the
  // same surface, at distance 0) to the whole other surface, both ways.
  Mesh before{w.origin, input_tris, {}, {}}, after{w.points, {}, {}, {}};
  Mesh changed_before{w.origin, {}, {}, {}}, changed_after{w.points, {}, {}, {}};
  for (size_t t = 0; t < w.tris.size(); ++t) {
    const bool dead = is_dead(w.tris[t]);
    if (!dead) after.triangles.push_back(w.tris[t]);
    if (t < input_tris.size() && (dead || w.touched[t])) changed_before.triangles.push_back(input_tris[t]);
    if (!dead && w.touched[t]) changed_after.triangles.push_back(w.tris[t]);
  }
  // Every vertex is a sample (the largest moves are at vertices), area samples every 1/400
  // of the diagonal in between.
  report.output_to_input = sampled_distance(changed_after, before, 400);
  // Input surface buried inside a united solid is gone with nothing to be near: not measured.
  report.input_to_output = check::sampled_distance_skipping(changed_before, after, 400, [&](const Vec3& q) {
    for (const auto& s : solids)
      if (s->inside(q)) return true;
    return false;
  });
  report.output_to_input.diagonal = report.input_to_output.diagonal = report.diagonal;
  if (report.diagonal > 0)
    report.deviation = std::max(report.output_to_input.max, report.input_to_output.max) / report.diagonal;
}

}  // namespace vdbwrap::local_repair
