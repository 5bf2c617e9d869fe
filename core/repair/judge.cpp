// Keep or undo (see judge.h).
#include "repair/judge.h"

#include <algorithm>
#include <set>
#include <unordered_map>
#include <utility>

namespace vdbwrap::local_repair {

using check::TrianglePair;

std::vector<TrianglePair> judge(Work& w, std::vector<Trial>& trials,
                                const std::unordered_set<uint32_t>& degenerate_before,
                                const std::function<void(size_t)>& undo) {
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
          if (a_in && b_in)
            ok = false;
          else
            ok = t.partners_allowed.count(a_in ? pr.second : pr.first) > 0;
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

}  // namespace vdbwrap::local_repair
