// Part 1 of the repair: per cluster of intersecting triangles (regions.h, group_clusters) a
// queue of local operations (vertex and triangle shifts, planned by local_operations.cpp, then
// untanglings, untangle.cpp), tried on all clusters at once, round by round, each kept or
// undone by judge().
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <string>
#include <unordered_set>
#include <utility>

#include "common/float_round.h"
#include "common/vec.h"
#include "repair/judge.h"
#include "repair/local_operations.h"
#include "repair/steps.h"
#include "repair/untangle.h"

namespace vdbwrap::local_repair {
namespace {

using check::TrianglePair;

struct RegionPlan {
  std::vector<uint32_t> triangles;
  size_t too_far = 0, area_refused = 0;  // candidates dropped by --max-deviation and eps_S
  std::vector<Move> queue;               // passing the area criterion and the deviation bound, by volume change
};

RegionPlan plan_region(const Work& w, const VertexFaces& faces, std::vector<uint32_t> region, const LocalParams& lp,
                       const RepairParams& params, double max_dev) {
  RegionPlan plan;
  plan.triangles = std::move(region);
  std::unordered_set<uint32_t> in(plan.triangles.begin(), plan.triangles.end());
  std::vector<TrianglePair> pairs;
  for (const auto& p : w.pairs)
    if (in.count(p.a) || in.count(p.b)) pairs.push_back(p);
  auto crossings = edge_crossings(w.points, w.tris, pairs);
  std::vector<Move> moves = plan_vertex_shifts(w.points, w.tris, plan.triangles, crossings, lp, 8);
  for (Move& m : plan_triangle_shifts(w.points, w.tris, plan.triangles, pairs, crossings, lp))
    moves.push_back(std::move(m));
  for (Move& m : plan_untangling(w.points, w.tris, faces, plan.triangles, crossings)) moves.push_back(std::move(m));
  // A shift reaching beyond --max-deviation (from where its vertices started) is also tried
  // cut short at the bound, after the others: it often still clears the crossing. (Not an
  // untangling: cut short, it no longer puts the vertices between their neighbours.)
  const size_t planned = moves.size();
  for (size_t i = 0; i < planned; ++i) {
    if (moves[i].kind == Move::Kind::Untangle) continue;
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
    measure_move(w.points, w.tris, faces, m);
    if (m.area_ratio >= params.area_ratio)
      plan.queue.push_back(std::move(m));
    else
      ++plan.area_refused;
  }
  // The paper's operations by increasing volume change, then the other vertices' shifts and
  // the moves cut short.
  std::stable_sort(plan.queue.begin(), plan.queue.end(), [](const Move& a, const Move& b) {
    return a.primary != b.primary ? a.primary : a.volume_change < b.volume_change;
  });
  return plan;
}

std::unordered_set<uint32_t> degenerate_among(const Work& w, const std::vector<uint32_t>& tris) {
  std::unordered_set<uint32_t> out;
  for (uint32_t t : tris)
    if (!is_dead(w.tris[t]) && check::triangle_is_degenerate(w.points, w.tris[t])) out.insert(t);
  return out;
}

}  // namespace

void run_local(Work& w, const RepairParams& params, const LocalParams& lp, double max_dev, RepairReport& report,
               ProgressSink* progress) {
  for (int iter = 0; iter < params.local_iterations && !w.pairs.empty(); ++iter) {
    start_round(progress, "repair: local operations", iter, params.local_iterations, w.pairs.size());
    report.local_iterations_run = size_t(iter + 1);
    const VertexFaces faces = vertex_faces(w.points.size(), w.tris);
    auto regions = group_clusters(w.tris, triangles_of(w.pairs), w.pairs);
    std::vector<RegionPlan> plans(regions.size());
    tbb::parallel_for(size_t(0), regions.size(),
                      [&](size_t i) { plans[i] = plan_region(w, faces, std::move(regions[i]), lp, params, max_dev); });
    for (const auto& p : plans) {
      if (p.too_far) report.refusals["local operation: would move a vertex beyond --max-deviation"] += p.too_far;
      if (p.area_refused) report.refusals["local operation: area criterion (eps_S)"] += p.area_refused;
    }
    std::vector<uint8_t> done(plans.size(), 0);
    std::vector<size_t> next(plans.size(), 0);  // per cluster: its next operation
    size_t accepted_this_iteration = 0;
    // Each round applies each unresolved cluster's next operation, all clusters at once. Clusters
    // of one region may share a vertex (a fan's hub): a move touching a vertex another move of
    // the round already moves waits for the next round, so that each can be undone alone.
    for (;;) {
      check_cancel(progress);
      std::vector<size_t> who, op;
      std::vector<Trial> trials;
      std::vector<std::vector<std::pair<uint32_t, Vec3>>> saved;
      std::unordered_set<uint32_t> claimed;
      for (size_t i = 0; i < plans.size(); ++i) {
        if (done[i] || next[i] >= plans[i].queue.size()) continue;
        const Move& m = plans[i].queue[next[i]];
        bool free = true;
        for (const auto& [v, pos] : m.positions) free &= claimed.count(v) == 0;
        if (!free) continue;
        for (const auto& [v, pos] : m.positions) claimed.insert(v);
        op.push_back(next[i]++);
        Trial t;
        t.changed = triangles_moved(faces, m);
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
        for (const auto& [v, pos] : plans[who[j]].queue[op[j]].positions) {
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
        switch (plans[who[j]].queue[op[j]].kind) {
          case Move::Kind::VertexShift:
            ++report.vertex_shifts;
            break;
          case Move::Kind::TriangleShift:
            ++report.triangle_shifts;
            break;
          case Move::Kind::Untangle:
            ++report.untangles;
            break;
        }
      }
      w.update_pairs(changed, found);
    }
    if (accepted_this_iteration == 0) break;  // nothing moved: the next iteration would be the same
  }
}

}  // namespace vdbwrap::local_repair
