// Step 4 of the repair: closed bodies still crossing each other are united. An assembly
// exported as one mesh (walls of a box overlapping at every edge, faces lying flat on each
// other) crosses over areas no band refill can cut; the exact union (unite.cpp) keeps every
// face where it is and drops only what is buried inside another body or lies on another
// body's face. Kept only when every body keeps some of its surface (no part buried whole),
// the union lies on the input, every input point it drops is within --max-deviation of it or
// inside it, and the united surface meets nothing and has no degenerate triangle.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <functional>
#include <map>
#include <memory>
#include <numeric>
#include <set>
#include <unordered_map>
#include <unordered_set>
#include <utility>

#include "common/edge_key.h"
#include "common/vec.h"
#include "mesh/surface_index.h"
#include "repair/steps.h"
#include "repair/unite.h"

namespace vdbwrap::local_repair {

size_t run_unite(Work& w, const RepairParams& params, double max_dev, const mesh::SurfaceIndex& original,
                 std::vector<std::unique_ptr<SolidTest>>& solids, RepairReport& report,
                 const std::set<int32_t>* regions) {
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
      if (is_dead(tri)) continue;
      for (int k = 0; k < 3; ++k) {
        const uint32_t u = tri[k], v = tri[(k + 1) % 3];
        auto [it, added] = first_on_edge.emplace(edge_key(u, v), t);
        if (!added) parent[find(t)] = find(it->second);
      }
    }
  }
  std::map<uint32_t, std::vector<uint32_t>> members;  // root -> triangles, by root (deterministic)
  for (uint32_t t = 0; t < w.tris.size(); ++t)
    if (!is_dead(w.tris[t])) members[find(t)].push_back(t);
  // Groups of components linked by intersecting pairs; a component that cuts itself spoils its group.
  std::map<uint32_t, uint32_t> group;  // component root -> group root
  std::function<uint32_t(uint32_t)> gfind = [&](uint32_t c) {
    auto it = group.emplace(c, c).first;
    return it->second == c ? c : (it->second = gfind(it->second));
  };
  std::set<uint32_t> spoiled, wanted;  // wanted: components holding a triangle of `regions`
  for (const auto& p : w.pairs) {
    const uint32_t a = find(p.a), b = find(p.b);
    if (a == b)
      spoiled.insert(a);
    else
      group[gfind(a)] = gfind(b);
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
      for (const auto& [e, n] : directed)
        closed &= n == 1 && directed.count({e.second, e.first}) && directed[{e.second, e.first}] == 1;
      if (!closed) break;
    }
    if (!closed) {
      ++report.refusals["unite: a body is not closed"];
      continue;
    }
    ++tried;
    Union u = unite_bodies(w.points, bodies, params.float_coordinates);
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
    auto solid = std::make_unique<SolidTest>(u.points, u.triangles);
    mesh::SurfaceIndex united(u.points, u.triangles);
    // Every body keeps some of its surface: a triangle outside every other body (not on one).
    // A body inside the others, even one resting on their faces, is a part the union would lose.
    std::vector<std::unique_ptr<SolidTest>> each;
    for (const auto& body : bodies) each.push_back(std::make_unique<SolidTest>(w.points, body));
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
    mesh::SurfaceIndex old_index(w.points, old_tris);
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
    for (uint32_t t : gone) w.tris[t] = dead_triangle();
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

}  // namespace vdbwrap::local_repair
