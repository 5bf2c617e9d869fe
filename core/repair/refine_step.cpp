// Part 2 again, for the regions the plain refill left. On CAD tessellations a triangle spans a
// whole face, so the band a refill removes (the intersecting triangles and a ring) reaches far
// beyond the bound. Bisecting the long edges near the intersections (the surface stays the
// same) makes that band narrow: a pin pushed into a plate then comes out as a band cut from
// both bodies, each loop of its contour filled on its own.
#include <algorithm>
#include <cstdio>
#include <set>
#include <unordered_set>
#include <utility>

#include "common/float_round.h"
#include "common/vec.h"
#include "mesh/surface_index.h"
#include "repair/steps.h"

namespace vdbwrap::local_repair {
namespace {

// Bisects the longest edge of every triangle within a ring of input region `r`'s
// intersecting triangles while it is longer than `h`, at most `budget` new triangles.
// Returns false when it gave up: the intersecting triangles multiplied as if the crossing were
// an area, not a curve (coplanar overlaps, a triangle soup), which no narrow band fixes.
bool refine_around(Work& w, int32_t r, double h, size_t budget, bool float_coordinates, size_t& added) {
  std::vector<std::vector<uint32_t>> vf(w.points.size());
  for (uint32_t t = 0; t < w.tris.size(); ++t)
    if (!is_dead(w.tris[t]))
      for (uint32_t v : w.tris[t]) vf[v].push_back(t);
  const size_t start = w.tris.size();
  size_t first = 0;
  auto longest = [&](const Tri& t, uint32_t& u, uint32_t& v) {
    double best = -1;
    for (int k = 0; k < 3; ++k) {
      double len = norm(w.points[t[(k + 1) % 3]] - w.points[t[k]]);
      if (len > best) best = len, u = t[k], v = t[(k + 1) % 3];
    }
    return best;
  };
  for (int round = 0; round < 64 && w.tris.size() - start < budget; ++round) {
    // The intersecting triangles first: while they are long, their ring is far-reaching (a
    // fan's hub) and needs no cutting; then the ring around them.
    std::vector<std::pair<double, uint32_t>> todo;
    const std::vector<uint32_t> cut = triangles_of(pairs_of_region(w, r));
    if (round == 0) first = cut.size();
    if (cut.size() > 32 * first) {
      added = w.tris.size() - start;
      return false;
    }
    for (int pass = 0; pass < 2 && todo.empty(); ++pass) {
      std::set<uint32_t> ring(cut.begin(), cut.end());
      if (pass == 1)
        for (uint32_t t : cut)
          for (uint32_t v : w.tris[t]) ring.insert(vf[v].begin(), vf[v].end());
      for (uint32_t t : ring) {
        uint32_t u = 0, v = 0;
        double len = longest(w.tris[t], u, v);
        if (len > h) todo.push_back({-len, t});
      }
    }
    if (todo.empty()) break;
    std::sort(todo.begin(), todo.end());  // longest first
    std::vector<uint32_t> changed;
    std::unordered_set<uint32_t> split;
    for (const auto& [neg, t] : todo) {
      if (split.count(t)) continue;  // already cut this round
      uint32_t u = 0, v = 0;
      if (longest(w.tris[t], u, v) <= h) continue;
      Vec3 mid = (w.points[u] + w.points[v]) * 0.5;
      if (float_coordinates) mid = round_to_float(mid);
      if (mid == w.points[u] || mid == w.points[v]) continue;
      const uint32_t m = uint32_t(w.points.size());
      w.points.push_back(mid);
      w.origin.push_back(mid);
      const size_t before = changed.size();
      split_edge(w, vf, u, v, m, changed);
      split.insert(changed.begin() + long(before), changed.end());
      if (w.tris.size() - start >= budget) break;
    }
    std::sort(changed.begin(), changed.end());
    changed.erase(std::unique(changed.begin(), changed.end()), changed.end());
    auto found = check::find_intersecting_pairs_with(w.points, w.tris, changed);
    w.update_pairs(std::unordered_set<uint32_t>(changed.begin(), changed.end()), found);
  }
  added = w.tris.size() - start;
  return added < budget;
}

}  // namespace

// Part 2 again, region by region, for the regions the plain refill left: refine around the
// region, refill it (smooth fill first, then flat); kept only when the region comes out free
// of intersections, else the mesh goes back as it was (no refinement left behind).
void run_refine_and_refill(Work& w, const RepairParams& params, double max_dev, const mesh::SurfaceIndex& original,
                           size_t regions_found, RepairReport& report, ProgressSink* progress) {
  auto has_pairs = [&](int32_t r) { return !pairs_of_region(w, r).empty(); };
  const size_t budget = std::max<size_t>(20000, 2 * w.tris.size());
  for (int32_t r = 0; r < int32_t(regions_found); ++r) {
    if (!has_pairs(r)) continue;
    check_cancel(progress);
    Work unrefined = w;
    size_t added = 0;
    if (debug_enabled())
      std::fprintf(stderr, "[repair] region %d: refine and refill, %zu pairs\n", r, pairs_of_region(w, r).size());
    if (!refine_around(w, r, max_dev / 3, budget, params.float_coordinates, added)) {
      if (debug_enabled())
        std::fprintf(stderr, "[repair] region %d: area crossing, not refined (%zu added)\n", r, added);
      w = std::move(unrefined);
      ++report.refusals["refine and refill: intersections cover an area, not a curve (not refined)"];
      continue;
    }
    bool fixed = false;
    const Work refined = w;
    for (bool fair : {true, false}) {
      if (fair && !params.fair) continue;
      const auto refills = report.refills;
      run_refill(w, params, max_dev, original, report, progress, r, fair);
      if (debug_enabled())
        std::fprintf(stderr, "[repair] region %d: after refill (fair %d): %zu pairs left\n", r, int(fair),
                     pairs_of_region(w, r).size());
      if (!has_pairs(r)) {
        fixed = true;
        ++report.regions_refined;
        report.refined_triangles_added += added;
        break;
      }
      w = refined;
      report.refills = refills;
    }
    if (!fixed) {
      w = std::move(unrefined);
      ++report.refusals["refine and refill: region still intersecting (refinement undone)"];
    }
  }
}

}  // namespace vdbwrap::local_repair
