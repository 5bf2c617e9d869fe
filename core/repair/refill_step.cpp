// Part 2 of the repair: the regions still intersecting, grown by a ring, are removed and
// refilled (refill.cpp builds each fill), all at once, each kept or undone by judge().
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cstdio>
#include <map>
#include <string>
#include <unordered_map>
#include <unordered_set>

#include "mesh/surface_index.h"
#include "repair/judge.h"
#include "repair/refill.h"
#include "repair/steps.h"

namespace vdbwrap::local_repair {

void run_refill(Work& w, const RepairParams& params, double max_dev, const mesh::SurfaceIndex& original,
                RepairReport& report, ProgressSink* progress, int32_t only, bool fair) {
  std::vector<uint32_t> T = triangles_of(pairs_of_region(w, only));
  RefillParams rp;
  rp.area_ratio = params.refill_area_ratio;
  rp.max_deviation = max_dev;
  rp.fair = params.fair && fair;
  rp.float_coordinates = params.float_coordinates;
  for (int j = 0; j < params.refill_iterations && !w.pairs.empty(); ++j) {
    start_round(progress, "repair: remove and refill", j, params.refill_iterations, w.pairs.size());
    report.refill_iterations_run = size_t(j + 1);
    VertexFaces faces = vertex_faces(w.points.size(), w.tris);
    T.erase(std::remove_if(T.begin(), T.end(), [&](uint32_t t) { return is_dead(w.tris[t]); }), T.end());
    T = grow_ring(w.tris, faces, T);
    auto regions = group_regions(w.tris, T, {});
    // Only regions that still hold an intersecting triangle are refilled.
    std::unordered_set<uint32_t> intersecting;
    for (const auto& p : pairs_of_region(w, only)) intersecting.insert(p.a), intersecting.insert(p.b);
    regions.erase(std::remove_if(regions.begin(), regions.end(),
                                 [&](const std::vector<uint32_t>& r) {
                                   return std::none_of(r.begin(), r.end(),
                                                       [&](uint32_t t) { return intersecting.count(t) > 0; });
                                 }),
                  regions.end());
    // Where a region's border pinches (refined meshes: vertices of high valence), its contour
    // is no simple loop: the region takes the triangles around the pinch.
    for (auto& r : regions) r = close_pinches(w.tris, faces, std::move(r));
    // The regions' vertices: a refill may delete a piece beyond its region only where no other
    // region is (the other's patch would border on nothing); grown regions that now overlap
    // are refused below.
    std::unordered_map<uint32_t, size_t> owner;
    for (size_t i = 0; i < regions.size(); ++i)
      for (uint32_t v : vertices_of(w.tris, regions[i])) owner.emplace(v, i);
    std::vector<Refill> fills(regions.size());
    tbb::parallel_for(size_t(0), regions.size(),
                      [&](size_t i) { fills[i] = refill_region(w.points, w.tris, faces, regions[i], rp, &original); });

    // Apply every refill that was built; judge them together.
    const uint32_t seen = uint32_t(w.points.size());  // refills number new points from here
    std::vector<Trial> trials;
    std::vector<size_t> who;
    std::vector<std::vector<Tri>> removed;
    for (size_t i = 0; i < regions.size(); ++i) {
      if (fills[i].ok) {
        std::vector<uint32_t> reach = regions[i];
        reach.insert(reach.end(), fills[i].also_removed.begin(), fills[i].also_removed.end());
        for (uint32_t t : reach) {
          for (uint32_t v : w.tris[t]) {
            auto [it, added] = owner.emplace(v, i);
            if (!added && it->second != i) fills[i].ok = false;
          }
          if (!fills[i].ok) {
            fills[i].why = "would reach a region another refill changes";
            break;
          }
        }
      }
      if (!fills[i].ok) {
        if (debug_enabled())
          std::fprintf(stderr, "[repair] region %d refill of %zu triangles refused: %s\n", only, regions[i].size(),
                       fills[i].why.c_str());
        ++report.refill_failures;
        ++report.refusals["refill: " + fills[i].why];
        continue;
      }
      const Refill& f = fills[i];
      std::vector<uint32_t> gone = regions[i];
      gone.insert(gone.end(), f.also_removed.begin(), f.also_removed.end());
      // The new triangles belong to the input region most of the removed ones came from.
      int32_t tag = -1;
      {
        std::map<int32_t, size_t> votes;
        for (uint32_t t : regions[i])
          if (w.region_of[t] >= 0) ++votes[w.region_of[t]];
        size_t most = 0;
        for (const auto& [r, n] : votes)
          if (n > most) most = n, tag = r;
      }
      Trial trial;
      trial.refill = true;
      std::unordered_set<uint32_t> region_set(gone.begin(), gone.end());
      for (const auto& p : w.pairs) {
        bool a_in = region_set.count(p.a) > 0, b_in = region_set.count(p.b) > 0;
        if (a_in != b_in) trial.partners_allowed.insert(a_in ? p.b : p.a);
      }
      const uint32_t point_base = uint32_t(w.points.size());
      w.points.insert(w.points.end(), f.new_points.begin(), f.new_points.end());
      w.origin.insert(w.origin.end(), f.new_points.begin(), f.new_points.end());
      removed.emplace_back();
      for (uint32_t t : gone) {
        removed.back().push_back(w.tris[t]);
        w.tris[t] = dead_triangle();
      }
      for (size_t k = 0; k < f.triangles.size(); ++k) {
        Tri t = f.triangles[k];
        for (uint32_t& v : t)
          if (v >= seen) v = point_base + (v - seen);
        uint32_t id = uint32_t(w.tris.size());
        w.tris.push_back(t);
        w.part.push_back(w.part[f.replaces[k]]);
        w.region_of.push_back(tag);
        w.touched.push_back(1);
        trial.changed.push_back(id);
      }
      trial.gone = gone;
      trial.watched = gone;
      trial.watched.insert(trial.watched.end(), trial.changed.begin(), trial.changed.end());
      trials.push_back(std::move(trial));
      who.push_back(i);
    }
    if (trials.empty()) continue;
    auto found = judge(w, trials, {}, [&](size_t k) {
      // Put the region back; its new triangles die (their points stay unused until compaction).
      for (uint32_t t : trials[k].changed) w.tris[t] = dead_triangle();
      const auto& gone = trials[k].gone;
      for (size_t q = 0; q < gone.size(); ++q) w.tris[gone[q]] = removed[k][q];
    });
    std::unordered_set<uint32_t> changed;
    for (size_t k = 0; k < trials.size(); ++k) {
      const auto& region = trials[k].gone;
      if (trials[k].accepted) {
        ++report.refills;
        changed.insert(region.begin(), region.end());
        changed.insert(trials[k].changed.begin(), trials[k].changed.end());
      } else {
        if (debug_enabled())
          std::fprintf(stderr, "[repair] region %d refill judged: intersections not fewer, or new ones\n", only);
        ++report.refill_failures;
        ++report.refusals["refill: intersections not fewer, or new ones"];
      }
    }
    w.update_pairs(changed, found);
  }
}

}  // namespace vdbwrap::local_repair
