// Step 1 of the repair, once the pairs are found: cracks (faces that share no vertices and
// touch along their seams) are stitched. stitch.cpp finds the welds and splits; this applies
// them round by round. A round is kept only when the intersecting pairs drop, each pair found
// is one the triangles' originals had, no triangle becomes degenerate and no edge ends up on
// three triangles or on two that run the same way (a vertex that would do that is left alone
// in the next try).
#include <algorithm>
#include <numeric>
#include <set>
#include <unordered_set>
#include <utility>

#include "repair/steps.h"
#include "repair/stitch.h"

namespace vdbwrap::local_repair {

using check::TrianglePair;

void run_stitch(Work& w, double tol, RepairReport& report) {
  std::unordered_set<uint32_t> forbidden;
  std::set<std::pair<uint32_t, uint32_t>> input_pairs;
  for (const auto& p : w.pairs) input_pairs.insert({p.a, p.b});
  std::vector<uint32_t> original_of(w.tris.size());  // triangle -> the input triangle it is part of
  std::iota(original_of.begin(), original_of.end(), 0);
  for (int round = 0, tries = 0; round < 8 && tries < 16 && !w.pairs.empty(); ++tries) {
    const VertexFaces faces = vertex_faces(w.points.size(), w.tris);
    const auto st = find_stitches(w.points, w.tris, faces, w.pairs, tol, forbidden);
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
        if (!is_dead(w.tris[t]))
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
    const VertexFaces after = vertex_faces(w.points.size(), w.tris);
    bool refused = false;
    for (const auto& [u, v] : bad_edges(w.tris, changed, after)) {
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
    ++report.refusals
          ["stitch: would make a degenerate triangle, a new intersection, or a non-manifold or misoriented edge"];
    if (forbidden.size() == forbidden_before)
      forbidden.insert(placed.begin(), placed.end());  // no culprit found: leave them
  }
}

}  // namespace vdbwrap::local_repair
