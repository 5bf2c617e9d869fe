// The repair pipeline (spec: "Intersection repair"): find the intersecting pairs, group them
// into regions, part 1 (vertex and triangle shifts), part 2 (remove and refill), removal of
// small leftovers, then the report. Every change is kept only where the region's
// intersection count drops and no new intersecting pair appears.
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <functional>
#include <memory>
#include <cmath>
#include <map>
#include <numeric>
#include <set>
#include <unordered_map>
#include <unordered_set>

#include "prep/check_input.h"
#include "check/distance_stats.h"
#include "check/intersections.h"
#include "common/debug_switch.h"
#include "common/edge_key.h"
#include "common/float_round.h"
#include "common/stage_timer.h"
#include "common/vec.h"
#include "fit/surface_index.h"
#include "repair/local_operations.h"
#include "repair/refill.h"
#include "repair/regions.h"
#include "repair/stitch.h"
#include "repair/unite.h"
#include "vdbwrap/repair.h"

namespace vdbwrap {
namespace {

using check::TrianglePair;
using local_repair::Move;
using local_repair::VertexFaces;

void check_cancel(ProgressSink* progress) {
  if (progress && progress->cancelled()) throw Error(ErrorKind::Cancelled, "cancelled");
}

void validate(const RepairParams& p) {
  auto bad = [](const std::string& what) { throw Error(ErrorKind::InvalidArgument, "repair: " + what); };
  if (p.local_iterations < 0 || p.local_iterations > 1000) bad("local iterations must be 0..1000");
  if (p.refill_iterations < 0 || p.refill_iterations > 100) bad("refill iterations must be 0..100");
  if (!(p.alpha > 0 && p.alpha < 1)) bad("alpha must be in (0, 1)");
  if (!(p.beta > 0)) bad("beta must be positive");
  if (!(p.delta > 0)) bad("delta must be positive");
  if (!(p.gamma > 0)) bad("gamma must be positive");
  if (!(p.area_ratio > 0 && p.area_ratio <= 1)) bad("area ratio (eps_S) must be in (0, 1]");
  if (!(p.refill_area_ratio > 0 && p.refill_area_ratio <= 1)) bad("refill area ratio must be in (0, 1]");
  if (!(p.accuracy >= 0) || !std::isfinite(p.accuracy)) bad("accuracy must be 0 (automatic) or positive");
  if (!(p.max_deviation.value > 0) || !std::isfinite(p.max_deviation.value)) bad("max deviation must be positive");
  if (p.small_piece_triangles < 0) bad("small piece triangles must not be negative");
  if (!(p.small_piece_area >= 0 && p.small_piece_area <= 1)) bad("small piece area must be in [0, 1]");
}


bool debug_enabled() {
  static const bool on = debug::setting("VDBWRAP_REPAIR_DEBUG") != nullptr;
  return on;
}

bool touches(const TrianglePair& p, const std::unordered_set<uint32_t>& set) { return set.count(p.a) || set.count(p.b); }

// The mesh being repaired. Deleted triangles keep their slot (local_repair::dead_triangle).
struct Work {
  std::vector<Vec3> points, origin;  // origin: where each vertex started (new ones: where made)
  std::vector<Tri> tris;
  std::vector<int32_t> part;         // per triangle
  std::vector<int32_t> region_of;    // per triangle: the input region it belongs to, or -1
  std::vector<uint8_t> touched;      // per triangle: changed by the repair
  std::vector<TrianglePair> pairs;   // current intersecting pairs (a < b), sorted

  void set_pairs(std::vector<TrianglePair> p) {
    p.erase(std::remove_if(p.begin(), p.end(), [](const TrianglePair& x) { return x.a == x.b; }), p.end());
    std::sort(p.begin(), p.end(), [](const TrianglePair& u, const TrianglePair& v) { return u.a != v.a ? u.a < v.a : u.b < v.b; });
    pairs = std::move(p);
  }
  // Replaces the pairs touching `changed` by `found` (the pairs found again around them).
  void update_pairs(const std::unordered_set<uint32_t>& changed, const std::vector<TrianglePair>& found) {
    std::vector<TrianglePair> p;
    for (const auto& x : pairs)
      if (!touches(x, changed)) p.push_back(x);
    p.insert(p.end(), found.begin(), found.end());
    set_pairs(std::move(p));
  }
};

// Exact weld (bit-identical points merge), parts per triangle.
Work make_work(const Mesh& input, bool float_coordinates) {
  Work w;
  std::map<Vec3, uint32_t> index;
  std::vector<uint32_t> remap(input.points.size());
  for (size_t i = 0; i < input.points.size(); ++i) {
    Vec3 p = input.points[i];  // finite: repair() checked the input (prep::check_input_mesh)
    if (float_coordinates) p = round_to_float(p);
    auto [it, added] = index.emplace(p, uint32_t(w.points.size()));
    if (added) w.points.push_back(p);
    remap[i] = it->second;
  }
  for (size_t t = 0; t < input.triangles.size(); ++t) {
    Tri tri = input.triangles[t];
    for (uint32_t& v : tri) {
      if (v >= remap.size())
        throw Error(ErrorKind::InvalidInput, "repair: triangle " + std::to_string(t) + " has a vertex index out of range");
      v = remap[v];
    }
    if (local_repair::is_dead(tri)) continue;  // all three corners equal: nothing there
    w.tris.push_back(tri);
    w.part.push_back(input.part_of(t));
  }
  if (w.tris.empty()) throw Error(ErrorKind::InvalidInput, "repair: the mesh has no triangles");
  w.origin = w.points;
  w.region_of.assign(w.tris.size(), -1);
  w.touched.assign(w.tris.size(), 0);
  return w;
}

double shortest_edge(const Work& w) {
  double lo = INFINITY;
  for (const Tri& t : w.tris)
    for (int k = 0; k < 3; ++k) {
      double len = norm(w.points[t[(k + 1) % 3]] - w.points[t[k]]);
      if (len > 0) lo = std::min(lo, len);
    }
  return std::isfinite(lo) ? lo : 0;
}

// ---------------------------------------------------------------------------------------
// Part 1: local operations.

struct RegionPlan {
  std::vector<uint32_t> triangles;
  size_t too_far = 0, area_refused = 0;  // candidates dropped by --max-deviation and eps_S
  std::vector<Move> queue;  // passing the area criterion and the deviation bound, by volume change
};

RegionPlan plan_region(const Work& w, const VertexFaces& faces, std::vector<uint32_t> region,
                       const local_repair::LocalParams& lp, const RepairParams& params, double max_dev) {
  RegionPlan plan;
  plan.triangles = std::move(region);
  std::unordered_set<uint32_t> in(plan.triangles.begin(), plan.triangles.end());
  std::vector<TrianglePair> pairs;
  for (const auto& p : w.pairs)
    if (in.count(p.a) || in.count(p.b)) pairs.push_back(p);
  auto crossings = local_repair::edge_crossings(w.points, w.tris, pairs);
  std::vector<Move> moves = local_repair::plan_vertex_shifts(w.points, w.tris, plan.triangles, crossings, lp, 8);
  for (Move& m : local_repair::plan_triangle_shifts(w.points, w.tris, plan.triangles, pairs, crossings, lp)) moves.push_back(std::move(m));
  // A move reaching beyond --max-deviation (from where its vertices started) is also tried
  // cut short at the bound, after the others: it often still clears the crossing.
  const size_t planned = moves.size();
  for (size_t i = 0; i < planned; ++i) {
    bool far = false;
    for (const auto& [v, pos] : moves[i].positions) far |= norm(pos - w.origin[v]) > max_dev;
    if (!far) continue;
    Move cut = moves[i];
    cut.primary = false;
    for (auto& [v, pos] : cut.positions) {
      const Vec3 d = pos - w.origin[v];
      const double len = norm(d);
      if (len > 0.98 * max_dev) pos = w.origin[v] + d * (0.98 * max_dev / len);
    }
    moves.push_back(std::move(cut));
  }
  for (Move& m : moves) {
    bool ok = true;
    for (auto& [v, pos] : m.positions) {
      if (params.float_coordinates) pos = round_to_float(pos);
      ok &= std::isfinite(pos[0]) && std::isfinite(pos[1]) && std::isfinite(pos[2]);
      ok &= norm(pos - w.origin[v]) <= max_dev;  // --max-deviation, from where the vertex started
    }
    bool moves_something = false;
    for (const auto& [v, pos] : m.positions) moves_something |= pos != w.points[v];
    if (!moves_something) continue;
    if (!ok) {
      ++plan.too_far;
      continue;
    }
    local_repair::measure_move(w.points, w.tris, faces, m);
    if (m.area_ratio >= params.area_ratio) plan.queue.push_back(std::move(m));
    else ++plan.area_refused;
  }
  // The paper's operations by increasing volume change, then the other vertices' shifts and
  // the moves cut short.
  std::stable_sort(plan.queue.begin(), plan.queue.end(), [](const Move& a, const Move& b) {
    return a.primary != b.primary ? a.primary : a.volume_change < b.volume_change;
  });
  return plan;
}

// One trial: a change per region applied at once, judged per region.
struct Trial {
  std::vector<uint32_t> watched;  // triangles whose pairs decide (region + changed)
  std::vector<uint32_t> changed;  // triangles the change made or moved
  std::vector<uint32_t> gone;     // triangles it deleted (their old pairs go with them)
  std::unordered_set<uint32_t> partners_allowed;  // refill: the outside triangles it may still meet
  bool refill = false;
  bool accepted = true;
};

// Judges every trial: the intersecting pairs around its triangles must drop in number, none
// may be new (refills: new triangles may only meet what the region met before), and no
// triangle may become degenerate. Returns the pairs found around the accepted trials'
// changed triangles. `undo(i)` takes trial i back; rejected trials are undone here.
template <typename Undo>
std::vector<TrianglePair> judge(Work& w, std::vector<Trial>& trials, const std::unordered_set<uint32_t>& degenerate_before,
                                Undo undo) {
  std::set<std::pair<uint32_t, uint32_t>> before;
  for (const auto& p : w.pairs) before.insert({p.a, p.b});
  std::vector<TrianglePair> found;
  for (int round = 0;; ++round) {
    std::vector<uint32_t> changed;
    for (const Trial& t : trials)
      if (t.accepted) changed.insert(changed.end(), t.changed.begin(), t.changed.end());
    std::sort(changed.begin(), changed.end());
    changed.erase(std::unique(changed.begin(), changed.end()), changed.end());
    found = check::find_intersecting_pairs_with(w.points, w.tris, changed);
    std::unordered_set<uint32_t> changed_set(changed.begin(), changed.end());
    for (const Trial& t : trials)
      if (t.accepted) changed_set.insert(t.gone.begin(), t.gone.end());
    // Degenerate triangles come back as (t, t): new ones fail their trial.
    std::unordered_set<uint32_t> new_degenerate;
    std::vector<TrianglePair> real;
    for (const auto& p : found) {
      if (p.a == p.b) {
        if (!degenerate_before.count(p.a)) new_degenerate.insert(p.a);
      } else {
        real.push_back(p);
      }
    }
    // The pairs after the trials: the old ones away from the change, plus those found.
    std::unordered_map<uint32_t, std::vector<uint32_t>> after;  // triangle -> partners
    for (const auto& p : w.pairs)
      if (!touches(p, changed_set)) after[p.a].push_back(p.b), after[p.b].push_back(p.a);
    for (const auto& p : real) after[p.a].push_back(p.b), after[p.b].push_back(p.a);
    std::unordered_map<uint32_t, std::vector<uint32_t>> prior;
    for (const auto& p : w.pairs) prior[p.a].push_back(p.b), prior[p.b].push_back(p.a);

    bool any_rejected = false;
    for (size_t i = 0; i < trials.size(); ++i) {
      Trial& t = trials[i];
      if (!t.accepted) continue;
      std::unordered_set<uint32_t> watched(t.watched.begin(), t.watched.end());
      std::set<std::pair<uint32_t, uint32_t>> pb, pa;
      for (uint32_t x : t.watched) {
        if (auto it = prior.find(x); it != prior.end())
          for (uint32_t y : it->second) pb.insert({std::min(x, y), std::max(x, y)});
        if (auto it = after.find(x); it != after.end())
          for (uint32_t y : it->second) pa.insert({std::min(x, y), std::max(x, y)});
      }
      bool ok = pa.size() < pb.size();
      for (uint32_t x : t.changed) ok &= !new_degenerate.count(x);
      for (const auto& pr : pa) {
        if (!ok) break;
        if (t.refill) {
          // New triangles only meet triangles outside that the region met before.
          bool a_in = watched.count(pr.first) > 0, b_in = watched.count(pr.second) > 0;
          if (a_in && b_in) ok = false;
          else ok = t.partners_allowed.count(a_in ? pr.second : pr.first) > 0;
        } else {
          ok = before.count(pr) > 0;
        }
      }
      if (!ok) {
        t.accepted = false;
        undo(i);
        any_rejected = true;
      }
    }
    if (!any_rejected) break;  // undone trials may have met accepted ones: check again
  }
  std::vector<TrianglePair> out;
  for (const auto& p : found)
    if (p.a != p.b) out.push_back(p);
  return out;
}

std::unordered_set<uint32_t> degenerate_among(const Work& w, const std::vector<uint32_t>& tris) {
  std::unordered_set<uint32_t> out;
  for (uint32_t t : tris)
    if (!local_repair::is_dead(w.tris[t]) && check::triangle_is_degenerate(w.points, w.tris[t])) out.insert(t);
  return out;
}

void run_local(Work& w, const RepairParams& params, const local_repair::LocalParams& lp, double max_dev, RepairReport& report,
               ProgressSink* progress) {
  for (int iter = 0; iter < params.local_iterations && !w.pairs.empty(); ++iter) {
    check_cancel(progress);
    if (progress)
      progress->progress("repair: local operations", double(iter) / params.local_iterations,
                         std::to_string(w.pairs.size()) + " intersecting pairs");
    report.local_iterations_run = size_t(iter + 1);
    const VertexFaces faces = local_repair::vertex_faces(w.points.size(), w.tris);
    auto regions = local_repair::group_regions(w.tris, local_repair::triangles_of(w.pairs), w.pairs);
    std::vector<RegionPlan> plans(regions.size());
    tbb::parallel_for(size_t(0), regions.size(),
                      [&](size_t i) { plans[i] = plan_region(w, faces, std::move(regions[i]), lp, params, max_dev); });
    for (const auto& p : plans) {
      if (p.too_far) report.refusals["local operation: would move a vertex beyond --max-deviation"] += p.too_far;
      if (p.area_refused) report.refusals["local operation: area criterion (eps_S)"] += p.area_refused;
    }
    std::vector<uint8_t> done(plans.size(), 0);
    size_t accepted_this_iteration = 0;
    size_t longest = 0;
    for (const auto& p : plans) longest = std::max(longest, p.queue.size());
    // Round k applies each unresolved region's k-th operation, all regions at once.
    for (size_t k = 0; k < longest; ++k) {
      check_cancel(progress);
      std::vector<size_t> who;
      std::vector<Trial> trials;
      std::vector<std::vector<std::pair<uint32_t, Vec3>>> saved;
      for (size_t i = 0; i < plans.size(); ++i) {
        if (done[i] || k >= plans[i].queue.size()) continue;
        const Move& m = plans[i].queue[k];
        Trial t;
        t.changed = local_repair::triangles_moved(faces, m);
        t.watched = t.changed;
        t.watched.insert(t.watched.end(), plans[i].triangles.begin(), plans[i].triangles.end());
        who.push_back(i);
        trials.push_back(std::move(t));
        saved.emplace_back();
      }
      if (trials.empty()) break;
      std::vector<uint32_t> all_changed;
      for (const auto& t : trials) all_changed.insert(all_changed.end(), t.changed.begin(), t.changed.end());
      const auto degenerate_before = degenerate_among(w, all_changed);
      for (size_t j = 0; j < who.size(); ++j)
        for (const auto& [v, pos] : plans[who[j]].queue[k].positions) {
          saved[j].push_back({v, w.points[v]});
          w.points[v] = pos;
        }
      auto found = judge(w, trials, degenerate_before, [&](size_t j) {
        for (const auto& [v, pos] : saved[j]) w.points[v] = pos;
      });
      std::unordered_set<uint32_t> changed;
      for (size_t j = 0; j < who.size(); ++j) {
        if (!trials[j].accepted) {
          ++report.refusals["local operation: intersections not fewer, or new ones"];
          continue;
        }
        changed.insert(trials[j].changed.begin(), trials[j].changed.end());
        for (uint32_t t : trials[j].changed) w.touched[t] = 1;
        done[who[j]] = 1;
        ++accepted_this_iteration;
        if (plans[who[j]].queue[k].kind == Move::Kind::VertexShift) ++report.vertex_shifts;
        else ++report.triangle_shifts;
      }
      w.update_pairs(changed, found);
    }
    if (accepted_this_iteration == 0) break;  // nothing moved: the next iteration would be the same
  }
}

// ---------------------------------------------------------------------------------------
// Part 2: remove and refill.

// The pairs with a triangle of input region `only` (all pairs when it is negative).
std::vector<TrianglePair> pairs_of_region(const Work& w, int32_t only) {
  if (only < 0) return w.pairs;
  std::vector<TrianglePair> out;
  for (const auto& p : w.pairs)
    if (w.region_of[p.a] == only || w.region_of[p.b] == only) out.push_back(p);
  return out;
}

void run_refill(Work& w, const RepairParams& params, double max_dev, const fit::SurfaceIndex& original,
                RepairReport& report, ProgressSink* progress, int32_t only = -1, bool fair = true) {
  std::vector<uint32_t> T = local_repair::triangles_of(pairs_of_region(w, only));
  local_repair::RefillParams rp;
  rp.area_ratio = params.refill_area_ratio;
  rp.max_deviation = max_dev;
  rp.fair = params.fair && fair;
  rp.float_coordinates = params.float_coordinates;
  for (int j = 0; j < params.refill_iterations && !w.pairs.empty(); ++j) {
    check_cancel(progress);
    if (progress)
      progress->progress("repair: remove and refill", double(j) / params.refill_iterations,
                         std::to_string(w.pairs.size()) + " intersecting pairs");
    report.refill_iterations_run = size_t(j + 1);
    VertexFaces faces = local_repair::vertex_faces(w.points.size(), w.tris);
    T.erase(std::remove_if(T.begin(), T.end(), [&](uint32_t t) { return local_repair::is_dead(w.tris[t]); }), T.end());
    T = local_repair::grow_ring(w.tris, faces, T);
    auto regions = local_repair::group_regions(w.tris, T, {});
    // Only regions that still hold an intersecting triangle are refilled.
    std::unordered_set<uint32_t> intersecting;
    for (const auto& p : pairs_of_region(w, only)) intersecting.insert(p.a), intersecting.insert(p.b);
    regions.erase(std::remove_if(regions.begin(), regions.end(),
                                 [&](const std::vector<uint32_t>& r) {
                                   return std::none_of(r.begin(), r.end(), [&](uint32_t t) { return intersecting.count(t) > 0; });
                                 }),
                  regions.end());
    // Where a region's border pinches (refined meshes: vertices of high valence), its contour
    // is no simple loop: the region takes the triangles around the pinch.
    for (auto& r : regions) r = local_repair::close_pinches(w.tris, faces, std::move(r));
    // The regions' vertices: a refill may delete a piece beyond its region only where no other
    // region is (the other's patch would border on nothing); grown regions that now overlap
    // are refused below.
    std::unordered_map<uint32_t, size_t> owner;
    for (size_t i = 0; i < regions.size(); ++i)
      for (uint32_t v : local_repair::vertices_of(w.tris, regions[i])) owner.emplace(v, i);
    std::vector<local_repair::Refill> fills(regions.size());
    tbb::parallel_for(size_t(0), regions.size(), [&](size_t i) {
      fills[i] = local_repair::refill_region(w.points, w.tris, faces, regions[i], rp, &original);
    });

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
          std::fprintf(stderr, "[repair] region %d refill of %zu triangles refused: %s\n", only, regions[i].size(), fills[i].why.c_str());
        ++report.refill_failures;
        ++report.refusals["refill: " + fills[i].why];
        continue;
      }
      const local_repair::Refill& f = fills[i];
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
        w.tris[t] = local_repair::dead_triangle();
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
      for (uint32_t t : trials[k].changed) w.tris[t] = local_repair::dead_triangle();
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
        if (debug_enabled()) std::fprintf(stderr, "[repair] region %d refill judged: intersections not fewer, or new ones\n", only);
        ++report.refill_failures;
        ++report.refusals["refill: intersections not fewer, or new ones"];
      }
    }
    w.update_pairs(changed, found);
  }
}

// ---------------------------------------------------------------------------------------
// Refinement before a second refill: on CAD tessellations a triangle spans a whole face, so
// the band a refill removes (the intersecting triangles and a ring) reaches far beyond the
// bound. Bisecting the long edges near the intersections (the surface stays the same) makes
// that band narrow: a pin pushed into a plate then comes out as a band cut from both bodies,
// each loop of its contour filled on its own.

// Splits edge (u, v) at new point m in every live triangle on it: each keeps its slot as the
// half at u and appends the half at v (same orientation, part and region). `vf` follows.
void split_edge(Work& w, std::vector<std::vector<uint32_t>>& vf, uint32_t u, uint32_t v, uint32_t m,
                std::vector<uint32_t>& changed) {
  std::vector<uint32_t> on;
  for (uint32_t f : vf[u]) {
    const Tri& t = w.tris[f];
    if (t[0] == v || t[1] == v || t[2] == v) on.push_back(f);
  }
  vf.resize(std::max<size_t>(vf.size(), m + 1));
  for (uint32_t f : on) {
    Tri t = w.tris[f];
    int k = 0;
    while (!((t[k] == u && t[(k + 1) % 3] == v) || (t[k] == v && t[(k + 1) % 3] == u))) ++k;
    const uint32_t a = t[k], b = t[(k + 1) % 3], c = t[(k + 2) % 3];
    const uint32_t keep_end = a == u ? b : a;  // the corner (u or v) that leaves slot f
    w.tris[f] = a == u ? Tri{a, m, c} : Tri{m, b, c};
    const Tri other = a == u ? Tri{m, b, c} : Tri{a, m, c};
    const uint32_t id = uint32_t(w.tris.size());
    w.tris.push_back(other);
    w.part.push_back(w.part[f]);
    w.region_of.push_back(w.region_of[f]);
    w.touched.push_back(1);
    w.touched[f] = 1;
    auto& row = vf[keep_end];
    row.erase(std::find(row.begin(), row.end(), f));
    vf[m].push_back(f);
    for (uint32_t x : other) vf[x].push_back(id);
    changed.push_back(f);
    changed.push_back(id);
  }
}

// Bisects the longest edge of every triangle within a ring of input region `r`'s
// intersecting triangles while it is longer than `h`, at most `budget` new triangles.
// Returns false when it gave up: the intersecting triangles multiplied as if the crossing were
// an area, not a curve (coplanar overlaps, a triangle soup), which no narrow band fixes.
bool refine_around(Work& w, int32_t r, double h, size_t budget, bool float_coordinates, size_t& added) {
  std::vector<std::vector<uint32_t>> vf(w.points.size());
  for (uint32_t t = 0; t < w.tris.size(); ++t)
    if (!local_repair::is_dead(w.tris[t]))
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
    const std::vector<uint32_t> cut = local_repair::triangles_of(pairs_of_region(w, r));
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

// Stage 0, before part 1: cracks (faces that share no vertices and touch along their seams)
// are stitched: corners within `tol` of each other welded, border edges split at the corners
// within `tol` of them. Nothing moves by more than `tol`. A round is kept only when the
// intersecting pairs drop, each pair found is one the triangles' originals had, no triangle
// becomes degenerate and no edge ends up on three triangles or on two that run the same way
// (a vertex that would do that is left alone in the next try).
void run_stitch(Work& w, double tol, RepairReport& report) {
  std::unordered_set<uint32_t> forbidden;
  std::set<std::pair<uint32_t, uint32_t>> input_pairs;
  for (const auto& p : w.pairs) input_pairs.insert({p.a, p.b});
  std::vector<uint32_t> original_of(w.tris.size());  // triangle -> the input triangle it is part of
  std::iota(original_of.begin(), original_of.end(), 0);
  for (int round = 0, tries = 0; round < 8 && tries < 16 && !w.pairs.empty(); ++tries) {
    const VertexFaces faces = local_repair::vertex_faces(w.points.size(), w.tris);
    const auto st = local_repair::find_stitches(w.points, w.tris, faces, w.pairs, tol, forbidden);
    if (st.welds.empty() && st.splits.empty()) break;
    Work saved = w;
    const auto saved_original = original_of;
    std::vector<uint32_t> changed;
    std::unordered_set<uint32_t> placed;  // the vertices welded or inserted
    for (const auto& [from, to] : st.welds) {
      for (const uint32_t* f = faces.begin(from); f != faces.end(from); ++f) {
        for (uint32_t& v : w.tris[*f])
          if (v == from) v = to;
        w.touched[*f] = 1;
        changed.push_back(*f);
      }
      placed.insert(from);
      placed.insert(to);
    }
    if (st.welds.empty()) {
      std::vector<std::vector<uint32_t>> vf(w.points.size());
      for (uint32_t t = 0; t < w.tris.size(); ++t)
        if (!local_repair::is_dead(w.tris[t]))
          for (uint32_t v : w.tris[t]) vf[v].push_back(t);
      for (const auto& s : st.splits) {
        uint32_t from = s.u;
        for (uint32_t m : s.at) {
          std::vector<uint32_t> split;
          split_edge(w, vf, from, s.w, m, split);
          // split_edge lists each triangle it cut, then the half it appended.
          original_of.resize(w.tris.size());
          for (size_t i = 0; i + 1 < split.size(); i += 2) original_of[split[i + 1]] = original_of[split[i]];
          changed.insert(changed.end(), split.begin(), split.end());
          placed.insert(m);
          from = m;
        }
      }
    }
    std::sort(changed.begin(), changed.end());
    changed.erase(std::unique(changed.begin(), changed.end()), changed.end());
    const VertexFaces after = local_repair::vertex_faces(w.points.size(), w.tris);
    bool refused = false;
    for (const auto& [u, v] : local_repair::bad_edges(w.tris, changed, after)) {
      refused = true;
      for (uint32_t x : {u, v})
        if (placed.count(x)) forbidden.insert(x);
    }
    for (uint32_t t : changed) {
      const Tri& x = w.tris[t];
      if (x[0] == x[1] || x[1] == x[2] || x[0] == x[2]) {
        refused = true;
        for (uint32_t v : x)
          if (placed.count(v)) forbidden.insert(v);
      }
    }
    auto found = refused ? std::vector<TrianglePair>{} : check::find_intersecting_pairs_with(w.points, w.tris, changed);
    for (const auto& p : found) {
      const uint32_t a = original_of[p.a], b = original_of[p.b];
      if (p.a == p.b || !input_pairs.count({std::min(a, b), std::max(a, b)})) refused = true;  // degenerate or new
    }
    if (!refused) {
      const std::unordered_set<uint32_t> changed_set(changed.begin(), changed.end());
      size_t left = found.size();
      for (const auto& p : w.pairs) left += touches(p, changed_set) ? 0 : 1;
      if (left >= w.pairs.size()) {
        w = std::move(saved);
        original_of = saved_original;
        ++report.refusals["stitch: intersections not fewer"];
        break;
      }
      w.update_pairs(changed_set, found);
      report.cracks_stitched += st.welds.size() + placed.size() * (st.welds.empty() ? 1 : 0);
      ++round;
      continue;
    }
    const size_t forbidden_before = forbidden.size();
    w = std::move(saved);
    original_of = saved_original;
    ++report.refusals["stitch: would make a degenerate triangle, a new intersection, or a non-manifold or misoriented edge"];
    if (forbidden.size() == forbidden_before) forbidden.insert(placed.begin(), placed.end());  // no culprit found: leave them
  }
}

// Part 2 again, region by region, for the regions the plain refill left: refine around the
// region, refill it (smooth fill first, then flat); kept only when the region comes out free
// of intersections, else the mesh goes back as it was (no refinement left behind).
void run_refine_and_refill(Work& w, const RepairParams& params, double max_dev, const fit::SurfaceIndex& original,
                           size_t regions_found, RepairReport& report, ProgressSink* progress) {
  auto has_pairs = [&](int32_t r) { return !pairs_of_region(w, r).empty(); };
  const size_t budget = std::max<size_t>(20000, 2 * w.tris.size());
  for (int32_t r = 0; r < int32_t(regions_found); ++r) {
    if (!has_pairs(r)) continue;
    check_cancel(progress);
    Work unrefined = w;
    size_t added = 0;
    if (debug_enabled()) std::fprintf(stderr, "[repair] region %d: refine and refill, %zu pairs\n", r, pairs_of_region(w, r).size());
    if (!refine_around(w, r, max_dev / 3, budget, params.float_coordinates, added)) {
      if (debug_enabled()) std::fprintf(stderr, "[repair] region %d: area crossing, not refined (%zu added)\n", r, added);
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
        std::fprintf(stderr, "[repair] region %d: after refill (fair %d): %zu pairs left\n", r, int(fair), pairs_of_region(w, r).size());
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

// ---------------------------------------------------------------------------------------
// Last: closed bodies still crossing each other are united. An assembly exported as one mesh
// (walls of a box overlapping at every edge, faces lying flat on each other) crosses over
// areas no band refill can cut; the exact union keeps every face where it is and drops only
// what is buried inside another body or lies on another body's face. Kept only when every
// body keeps some of its surface (no part buried whole), the union lies on the input, every
// input point it drops is within --max-deviation of it or inside it, and the united surface
// meets nothing and has no degenerate triangle.

// Returns how many groups of closed bodies it tried to unite.
size_t run_unite(Work& w, const RepairParams& params, double max_dev, const fit::SurfaceIndex& original,
                 std::vector<std::unique_ptr<local_repair::SolidTest>>& solids, RepairReport& report,
                 const std::set<int32_t>* regions = nullptr) {
  size_t tried = 0;
  // Bodies: the live triangles connected through shared edges (two bodies touching at a
  // corner, welded there, stay two; a vertex shared that way is copied into each).
  std::vector<uint32_t> parent(w.tris.size());
  std::iota(parent.begin(), parent.end(), 0);
  std::function<uint32_t(uint32_t)> find = [&](uint32_t x) {
    while (parent[x] != x) x = parent[x] = parent[parent[x]];
    return x;
  };
  {
    std::unordered_map<uint64_t, uint32_t> first_on_edge;
    for (uint32_t t = 0; t < w.tris.size(); ++t) {
      const Tri& tri = w.tris[t];
      if (local_repair::is_dead(tri)) continue;
      for (int k = 0; k < 3; ++k) {
        const uint32_t u = tri[k], v = tri[(k + 1) % 3];
        auto [it, added] = first_on_edge.emplace(edge_key(u, v), t);
        if (!added) parent[find(t)] = find(it->second);
      }
    }
  }
  std::map<uint32_t, std::vector<uint32_t>> members;  // root -> triangles, by root (deterministic)
  for (uint32_t t = 0; t < w.tris.size(); ++t)
    if (!local_repair::is_dead(w.tris[t])) members[find(t)].push_back(t);
  // Groups of components linked by intersecting pairs; a component that cuts itself spoils its group.
  std::map<uint32_t, uint32_t> group;  // component root -> group root
  std::function<uint32_t(uint32_t)> gfind = [&](uint32_t c) {
    auto it = group.emplace(c, c).first;
    return it->second == c ? c : (it->second = gfind(it->second));
  };
  std::set<uint32_t> spoiled, wanted;  // wanted: components holding a triangle of `regions`
  for (const auto& p : w.pairs) {
    const uint32_t a = find(p.a), b = find(p.b);
    if (a == b) spoiled.insert(a);
    else group[gfind(a)] = gfind(b);
  }
  if (regions)
    for (const auto& [c, tris] : members)
      for (uint32_t t : tris)
        if (regions->count(w.region_of[t])) {
          wanted.insert(c);
          break;
        }
  std::map<uint32_t, std::vector<uint32_t>> groups;  // group root -> component roots
  for (const auto& [c, g] : group) groups[gfind(c)].push_back(c);
  for (auto& [g, comps] : groups) {
    if (debug_enabled()) std::fprintf(stderr, "[repair] unite: group of %zu bodies\n", comps.size());
    if (comps.size() < 2) continue;
    if (regions && std::none_of(comps.begin(), comps.end(), [&](uint32_t c) { return wanted.count(c) > 0; })) continue;
    if (std::any_of(comps.begin(), comps.end(), [&](uint32_t c) { return spoiled.count(c) > 0; })) {
      ++report.refusals["unite: a body cuts itself"];
      continue;
    }
    std::vector<std::vector<Tri>> bodies;
    std::vector<uint32_t> gone;
    for (uint32_t c : comps) {
      bodies.emplace_back();
      for (uint32_t t : members[c]) bodies.back().push_back(w.tris[t]), gone.push_back(t);
    }
    std::sort(gone.begin(), gone.end());
    // Closed: every edge of a body on two of its triangles, running opposite ways.
    bool closed = true;
    for (const auto& body : bodies) {
      std::map<std::pair<uint32_t, uint32_t>, int> directed;
      for (const Tri& t : body)
        for (int k = 0; k < 3; ++k) ++directed[{t[k], t[(k + 1) % 3]}];
      for (const auto& [e, n] : directed) closed &= n == 1 && directed.count({e.second, e.first}) && directed[{e.second, e.first}] == 1;
      if (!closed) break;
    }
    if (!closed) {
      ++report.refusals["unite: a body is not closed"];
      continue;
    }
    ++tried;
    local_repair::Union u = local_repair::unite_bodies(w.points, bodies, params.float_coordinates);
    if (!u.ok) {
      ++report.refusals["unite: " + u.why];
      continue;
    }
    for (const Tri& t : u.triangles)
      if (check::triangle_is_degenerate(u.points, t)) u.ok = false;
    if (!u.ok) {
      ++report.refusals["unite: the union has a degenerate triangle"];
      continue;
    }
    auto solid = std::make_unique<local_repair::SolidTest>(u.points, u.triangles);
    fit::SurfaceIndex united(u.points, u.triangles);
    // Every body keeps some of its surface: a triangle outside every other body (not on one).
    // A body inside the others, even one resting on their faces, is a part the union would lose.
    std::vector<std::unique_ptr<local_repair::SolidTest>> each;
    for (const auto& body : bodies) each.push_back(std::make_unique<local_repair::SolidTest>(w.points, body));
    bool whole = true;
    for (size_t i = 0; i < bodies.size() && whole; ++i) {
      bool shows = false;
      for (const Tri& t : bodies[i]) {
        const Vec3 c = (w.points[t[0]] + w.points[t[1]] + w.points[t[2]]) * (1.0 / 3);
        bool out = true;
        for (size_t j = 0; j < bodies.size() && out; ++j)
          if (j != i) out = each[j]->outside(c);
        if (out) {
          shows = true;
          break;
        }
      }
      whole &= shows;
    }
    if (!whole) {
      ++report.refusals["unite: would delete a body buried in another"];
      continue;
    }
    // The union lies on the input; what it drops is near it or buried inside it.
    bool near = true;
    for (const Tri& t : u.triangles) {
      const Vec3 c = (u.points[t[0]] + u.points[t[1]] + u.points[t[2]]) * (1.0 / 3);
      for (const Vec3& q : {u.points[t[0]], u.points[t[1]], u.points[t[2]], c})
        near &= original.squared_distance(q) <= max_dev * max_dev;
      if (!near) break;
    }
    if (!near) {
      ++report.refusals["unite: the union leaves the input surface"];
      continue;
    }
    for (uint32_t t : gone) {
      const Tri& x = w.tris[t];
      const Vec3 c = (w.origin[x[0]] + w.origin[x[1]] + w.origin[x[2]]) * (1.0 / 3);
      for (const Vec3& q : {w.origin[x[0]], w.origin[x[1]], w.origin[x[2]], c})
        if (!solid->inside(q) && united.squared_distance(q) > max_dev * max_dev) near = false;
      if (!near) break;
    }
    if (!near) {
      ++report.refusals["unite: would drop surface that is neither buried nor near the union"];
      continue;
    }
    // Apply: the bodies die, the union comes in (parts and regions from the nearest old triangle).
    std::vector<Tri> old_tris;
    std::vector<uint32_t> old_of;
    for (uint32_t t : gone) old_tris.push_back(w.tris[t]), old_of.push_back(t);
    fit::SurfaceIndex old_index(w.points, old_tris);
    const Work saved = w;
    const uint32_t base = uint32_t(w.points.size());
    w.points.insert(w.points.end(), u.points.begin(), u.points.end());
    w.origin.insert(w.origin.end(), u.points.begin(), u.points.end());
    std::vector<uint32_t> changed;
    for (const Tri& t : u.triangles) {
      const Vec3 c = (u.points[t[0]] + u.points[t[1]] + u.points[t[2]]) * (1.0 / 3);
      const uint32_t from = old_of[old_index.closest(c).triangle];  // ties: the same on every run
      changed.push_back(uint32_t(w.tris.size()));
      w.tris.push_back({base + t[0], base + t[1], base + t[2]});
      w.part.push_back(w.part[from]);
      w.region_of.push_back(w.region_of[from]);
      w.touched.push_back(1);
    }
    for (uint32_t t : gone) w.tris[t] = local_repair::dead_triangle();
    auto found = check::find_intersecting_pairs_with(w.points, w.tris, changed);
    if (!found.empty()) {
      w = saved;
      ++report.refusals["unite: the union meets other triangles (after rounding)"];
      continue;
    }
    std::unordered_set<uint32_t> changed_set(gone.begin(), gone.end());
    w.update_pairs(changed_set, found);
    report.bodies_united += comps.size();
    solids.push_back(std::move(solid));
  }
  return tried;
}

// ---------------------------------------------------------------------------------------
// Small pieces the repair left behind.

void remove_small_pieces(Work& w, const RepairParams& params, double max_dev, RepairReport& report) {
  const size_t n = w.points.size();
  std::vector<uint32_t> parent(n);
  std::iota(parent.begin(), parent.end(), 0);
  auto find = [&](uint32_t x) {
    while (parent[x] != x) x = parent[x] = parent[parent[x]];
    return x;
  };
  double total_area = 0;
  for (const Tri& t : w.tris) {
    if (local_repair::is_dead(t)) continue;
    parent[find(t[0])] = find(t[1]);
    parent[find(t[1])] = find(t[2]);
    total_area += 0.5 * norm(area_vector(w.points[t[0]], w.points[t[1]], w.points[t[2]]));
  }
  struct Piece {
    std::vector<uint32_t> tris;
    double area = 0;
    bool touched = false;
  };
  std::unordered_map<uint32_t, Piece> pieces;
  std::unordered_set<uint32_t> intersecting;
  for (const auto& p : w.pairs) intersecting.insert(p.a), intersecting.insert(p.b);
  for (uint32_t t = 0; t < w.tris.size(); ++t) {
    const Tri& tri = w.tris[t];
    if (local_repair::is_dead(tri)) continue;
    Piece& p = pieces[find(tri[0])];
    p.tris.push_back(t);
    p.area += 0.5 * norm(area_vector(w.points[tri[0]], w.points[tri[1]], w.points[tri[2]]));
    p.touched |= w.touched[t] || intersecting.count(t);
  }
  if (pieces.size() < 2) return;
  std::vector<uint32_t> doomed, kept;
  for (const auto& [root, p] : pieces) {
    bool small = p.tris.size() <= size_t(params.small_piece_triangles) && p.area <= params.small_piece_area * total_area;
    (small && p.touched ? doomed : kept).insert((small && p.touched ? doomed : kept).end(), p.tris.begin(), p.tris.end());
  }
  if (doomed.empty() || kept.empty()) return;
  // A piece goes only when all of it lies within the deviation bound of what stays.
  std::vector<Tri> kept_tris;
  for (uint32_t t : kept) kept_tris.push_back(w.tris[t]);
  fit::SurfaceIndex rest(w.points, kept_tris);
  for (const auto& [root, p] : pieces) {
    bool small = p.tris.size() <= size_t(params.small_piece_triangles) && p.area <= params.small_piece_area * total_area;
    if (!(small && p.touched)) continue;
    bool near = true;
    for (uint32_t t : p.tris)
      for (uint32_t v : w.tris[t]) near &= std::sqrt(rest.squared_distance(w.points[v])) <= max_dev;
    if (!near) continue;
    ++report.pieces_removed;
    report.piece_triangles_removed += p.tris.size();
    for (uint32_t t : p.tris) w.tris[t] = local_repair::dead_triangle();
  }
  std::unordered_set<uint32_t> gone;
  for (uint32_t t = 0; t < w.tris.size(); ++t)
    if (local_repair::is_dead(w.tris[t])) gone.insert(t);
  std::vector<TrianglePair> p;
  for (const auto& x : w.pairs)
    if (!touches(x, gone)) p.push_back(x);
  w.set_pairs(std::move(p));
}

// ---------------------------------------------------------------------------------------

// The triangles still there (not dead).
std::vector<Tri> live_triangles(const Work& w) {
  std::vector<Tri> live;
  for (const Tri& t : w.tris)
    if (!local_repair::is_dead(t)) live.push_back(t);
  return live;
}

// The live triangles and the points they use, points in their order (an untouched welded
// mesh comes out as it went in).
Mesh compact(const Work& w, const Mesh& input) {
  Mesh out;
  std::vector<uint32_t> remap(w.points.size(), UINT32_MAX);
  for (const Tri& t : w.tris)
    if (!local_repair::is_dead(t))
      for (uint32_t v : t) remap[v] = 0;
  for (size_t v = 0; v < w.points.size(); ++v)
    if (remap[v] == 0) {
      remap[v] = uint32_t(out.points.size());
      out.points.push_back(w.points[v]);
    }
  const bool parts = !input.triangle_part.empty();
  for (size_t t = 0; t < w.tris.size(); ++t) {
    const Tri& tri = w.tris[t];
    if (local_repair::is_dead(tri)) continue;
    out.triangles.push_back({remap[tri[0]], remap[tri[1]], remap[tri[2]]});
    if (parts) out.triangle_part.push_back(w.part[t]);
  }
  out.part_names = input.part_names;
  return out;
}

std::vector<RepairRegion> describe_regions(const Work& w) {
  std::vector<RepairRegion> out;
  for (const auto& region : local_repair::group_regions(w.tris, local_repair::triangles_of(w.pairs), w.pairs)) {
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

RepairResult run_repair(const Mesh& input, const RepairParams& params, ProgressSink* progress) {
  validate(params);
  const auto start = std::chrono::steady_clock::now();
  RepairResult result;
  RepairReport& report = result.report;
  report.params = params;
  {
    StageTimer timer("diagnose input", report.stages);
    if (progress) progress->progress("repair: diagnose input", 0.0, "checking the input");
    report.before = diagnose(input, true);
  }
  check_cancel(progress);
  Work w = make_work(input, params.float_coordinates);
  const std::vector<Tri> input_tris = w.tris;  // the input's triangles (ids stay: deleted ones die in place)
  report.diagonal = report.before.diagonal;
  report.max_deviation = params.max_deviation.resolve(report.diagonal);
  report.accuracy = params.accuracy > 0 ? params.accuracy : std::max(1e-16, 0.05 * shortest_edge(w));
  local_repair::LocalParams lp{params.alpha, params.beta, params.delta, params.gamma, report.accuracy};

  {
    StageTimer timer("find intersections", report.stages);
    w.set_pairs(check::find_intersecting_pairs(w.points, w.tris));
    auto regions = local_repair::group_regions(w.tris, local_repair::triangles_of(w.pairs), w.pairs);
    for (size_t r = 0; r < regions.size(); ++r)
      for (uint32_t t : regions[r]) w.region_of[t] = int32_t(r);
    report.regions_found = regions.size();
  }
  auto clean_regions = [&]() {
    std::vector<uint8_t> clean(report.regions_found, 1);
    for (const auto& p : w.pairs)
      for (uint32_t t : {p.a, p.b})
        if (w.region_of[t] >= 0) clean[size_t(w.region_of[t])] = 0;
    return clean;
  };
  std::vector<std::unique_ptr<local_repair::SolidTest>> solids;  // bodies united: their insides
  if (!w.pairs.empty()) {
    StageTimer timer("stitch cracks", report.stages);
    // Cracks of CAD exports are float noise wide (1e-16 of the model here); 1e-6 of the
    // diagonal stays far below any deviation bound.
    run_stitch(w, std::min(1e-6 * report.diagonal, report.max_deviation), report);
  }
  // Parts 1 and 2 (and the union of closed bodies still crossing after them). `first`: input
  // regions whose crossing bodies are united before part 1, the second pass below.
  std::vector<uint8_t> by_union, clean_after_local;  // regions the union fixed; regions clean after part 1
  size_t unite_tried = 0;                            // groups of closed crossing bodies the union was tried on
  auto unite = [&](const fit::SurfaceIndex& input, const std::set<int32_t>* regions) {
    StageTimer timer("unite crossing bodies", report.stages);
    check_cancel(progress);
    const auto clean_before = clean_regions();
    unite_tried += run_unite(w, params, report.max_deviation, input, solids, report, regions);
    const auto clean_after = clean_regions();
    for (size_t r = 0; r < report.regions_found; ++r) by_union[r] |= !clean_before[r] && clean_after[r];
  };
  auto parts = [&](const std::set<int32_t>& first) {
    by_union.assign(report.regions_found, 0);
    solids.clear();
    if (!first.empty()) {
      fit::SurfaceIndex input(w.origin, live_triangles(w));
      unite(input, &first);
    }
    {
      StageTimer timer("local operations", report.stages);
      run_local(w, params, lp, report.max_deviation, report, progress);
    }
    clean_after_local = clean_regions();
    if (!w.pairs.empty() && params.refill_iterations > 0) {
      // The input surface as it came (vertices at their starting places).
      fit::SurfaceIndex index(w.origin, live_triangles(w));
      {
        StageTimer timer("remove and refill", report.stages);
        run_refill(w, params, report.max_deviation, index, report, progress);
      }
      if (!w.pairs.empty()) {
        StageTimer timer("refine, remove and refill", report.stages);
        run_refine_and_refill(w, params, report.max_deviation, index, report.regions_found, report, progress);
      }
      if (!w.pairs.empty() && params.unite_bodies) unite(index, nullptr);
    }
    if (params.remove_small_pieces) {
      StageTimer timer("remove small pieces", report.stages);
      remove_small_pieces(w, params, report.max_deviation, report);
    }
  };
  const Work stitched = w;
  const RepairReport report_stitched = report;
  parts({});
  const bool united_late = std::any_of(by_union.begin(), by_union.end(), [](uint8_t u) { return u != 0; });
  if (((!w.pairs.empty() && unite_tried > 0) || united_late) && params.unite_bodies) {
    // Second pass for the regions left (or united only after parts 1 and 2 had moved and cut
    // them): their closed bodies (an assembly's walls overlapping face to face, crossing over
    // areas) united first, from the input as it came, then the rest as before. Kept when it
    // leaves fewer regions unfixed, or as few when the first pass needed the union too.
    const auto clean = clean_regions();
    std::set<int32_t> left;
    for (size_t r = 0; r < report.regions_found; ++r)
      if (!clean[r] || by_union[r]) left.insert(int32_t(r));
    Work first_w = std::move(w);
    RepairReport first_report = std::move(report);
    auto first_solids = std::move(solids);
    const auto first_by_union = by_union, first_clean_after_local = clean_after_local;
    w = stitched;
    report = report_stitched;
    report.stages = first_report.stages;
    solids.clear();
    parts(left);
    const auto clean2 = clean_regions();
    const auto left1 = std::count(clean.begin(), clean.end(), 0), left2 = std::count(clean2.begin(), clean2.end(), 0);
    if (left2 > left1 || (left2 == left1 && !united_late)) {
      const auto stages = std::move(report.stages);
      w = std::move(first_w);
      report = std::move(first_report);
      report.stages = stages;
      solids = std::move(first_solids);
      by_union = first_by_union;
      clean_after_local = first_clean_after_local;
      ++report.refusals["unite: uniting the bodies first left no fewer regions (second pass dropped)"];
    }
  }
  const auto clean_at_end = clean_regions();
  for (size_t r = 0; r < report.regions_found; ++r) {
    if (by_union[r]) ++report.fixed_by_union;
    else if (clean_after_local[r]) ++report.fixed_by_local;
    else if (clean_at_end[r]) ++report.fixed_by_refill;
    else ++report.left_unfixed;
  }
  report.unfixed = describe_regions(w);
  result.mesh = compact(w, input);
  check_cancel(progress);
  {
    StageTimer timer("diagnose output", report.stages);
    if (progress) progress->progress("repair: diagnose output", 0.0, "checking the result");
    report.after = diagnose(result.mesh, true);
  }
  if (params.compute_distances) {
    StageTimer timer("distances", report.stages);
    // Metro-style, from the surface the repair changed (elsewhere input and output are the
    // same surface, at distance 0) to the whole other surface, both ways.
    Mesh before{w.origin, input_tris, {}, {}}, after{w.points, {}, {}, {}};
    Mesh changed_before{w.origin, {}, {}, {}}, changed_after{w.points, {}, {}, {}};
    for (size_t t = 0; t < w.tris.size(); ++t) {
      const bool dead = local_repair::is_dead(w.tris[t]);
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
  report.total_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return result;
}

}  // namespace

RepairResult repair(const Mesh& input, const RepairParams& params, ProgressSink* progress) {
  prep::check_input_mesh(input, "repair input");
  // A task arena per job, as in wrap(): its thread limit holds for this job only.
  if (params.threads <= 0) return run_repair(input, params, progress);
  tbb::task_arena arena(params.threads);
  return arena.execute([&] { return run_repair(input, params, progress); });
}

}  // namespace vdbwrap
