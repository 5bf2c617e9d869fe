#include "post/repair_wrap.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>

#include "check/intersections.h"

namespace vdbwrap::post {

WrapRepairOutcome repair_intersections(PostSurface& s, double max_deviation, bool float_coordinates,
                                       ProgressSink* progress) {
  WrapRepairOutcome out;
  out.intersecting_before = check::intersecting_triangles(s.points, s.triangles, check::SoupKind::kWrap).size();
  if (out.intersecting_before == 0) return out;
  out.ran = true;
  if (progress)
    progress->progress("repair", 0.0,
                       std::to_string(out.intersecting_before) + " intersecting triangles: intersection repair");
  RepairParams rp;
  rp.max_deviation = Length{max_deviation, false};
  rp.remove_small_pieces = false;
  rp.float_coordinates = float_coordinates;
  rp.compute_distances = false;
  Mesh mesh{s.points, s.triangles, {}, {}};
  RepairResult result = repair(mesh, rp, progress);

  // Per-point data by position: untouched points keep theirs.
  std::map<Vec3, uint32_t> old_index;
  for (uint32_t i = 0; i < s.points.size(); ++i) old_index.emplace(s.points[i], i);
  PostSurface next;
  next.points = result.mesh.points;
  next.triangles = result.mesh.triangles;
  next.cell_size.assign(next.points.size(), -1);
  next.locked.assign(next.points.size(), 0);
  for (uint32_t i = 0; i < next.points.size(); ++i) {
    auto it = old_index.find(next.points[i]);
    if (it != old_index.end()) next.cell_size[i] = s.cell_size[it->second], next.locked[i] = s.locked[it->second];
  }
  double smallest = INFINITY;
  for (double c : s.cell_size) smallest = std::min(smallest, c);
  std::vector<double> fill(next.points.size(), INFINITY);
  for (const Tri& t : next.triangles)
    for (uint32_t v : t)
      for (uint32_t w : t)
        if (next.cell_size[w] > 0) fill[v] = std::min(fill[v], next.cell_size[w]);
  for (uint32_t i = 0; i < next.points.size(); ++i)
    if (next.cell_size[i] < 0) next.cell_size[i] = std::isfinite(fill[i]) ? fill[i] : smallest;
  // Feature edges whose two ends kept their places (and are still an edge: checked where used).
  std::map<Vec3, uint32_t> new_index;
  for (uint32_t i = 0; i < next.points.size(); ++i) new_index.emplace(next.points[i], i);
  for (const auto& [a, b] : s.feature_edges) {
    auto ia = new_index.find(s.points[a]), ib = new_index.find(s.points[b]);
    if (ia != new_index.end() && ib != new_index.end()) next.feature_edges.push_back({ia->second, ib->second});
  }
  s = std::move(next);

  const RepairReport& r = result.report;
  out.intersecting_after = check::intersecting_triangles(s.points, s.triangles, check::SoupKind::kWrap).size();
  char text[256];
  std::snprintf(text, sizeof text, "%zu regions: %zu fixed by local operations, %zu by refill, %zu left",
                r.regions_found, r.fixed_by_local, r.fixed_by_refill, r.left_unfixed);
  out.summary = text;
  for (size_t i = 0; i < r.unfixed.size() && i < 5; ++i) {
    std::snprintf(text, sizeof text, "; unfixed region around (%.6g, %.6g, %.6g)", r.unfixed[i].center[0],
                  r.unfixed[i].center[1], r.unfixed[i].center[2]);
    out.summary += text;
  }
  return out;
}

}  // namespace vdbwrap::post
