// The repair's working mesh: building it from the input, reading it, editing it (see work.h).
#include "repair/work.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <string>

#include "common/debug_switch.h"
#include "common/float_round.h"
#include "common/vec.h"
#include "vdbwrap/errors.h"

namespace vdbwrap::local_repair {

using check::TrianglePair;

void Work::set_pairs(std::vector<TrianglePair> p) {
  p.erase(std::remove_if(p.begin(), p.end(), [](const TrianglePair& x) { return x.a == x.b; }), p.end());
  std::sort(p.begin(), p.end(),
            [](const TrianglePair& u, const TrianglePair& v) { return u.a != v.a ? u.a < v.a : u.b < v.b; });
  pairs = std::move(p);
}

void Work::update_pairs(const std::unordered_set<uint32_t>& changed, const std::vector<TrianglePair>& found) {
  std::vector<TrianglePair> p;
  for (const auto& x : pairs)
    if (!touches(x, changed)) p.push_back(x);
  p.insert(p.end(), found.begin(), found.end());
  set_pairs(std::move(p));
}

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
        throw Error(ErrorKind::InvalidInput,
                    "repair: triangle " + std::to_string(t) + " has a vertex index out of range");
      v = remap[v];
    }
    if (is_dead(tri)) continue;  // all three corners equal: nothing there
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

std::vector<Tri> live_triangles(const Work& w) {
  std::vector<Tri> live;
  for (const Tri& t : w.tris)
    if (!is_dead(t)) live.push_back(t);
  return live;
}

Mesh compact(const Work& w, const Mesh& input) {
  Mesh out;
  std::vector<uint32_t> remap(w.points.size(), UINT32_MAX);
  for (const Tri& t : w.tris)
    if (!is_dead(t))
      for (uint32_t v : t) remap[v] = 0;
  for (size_t v = 0; v < w.points.size(); ++v)
    if (remap[v] == 0) {
      remap[v] = uint32_t(out.points.size());
      out.points.push_back(w.points[v]);
    }
  const bool parts = !input.triangle_part.empty();
  for (size_t t = 0; t < w.tris.size(); ++t) {
    const Tri& tri = w.tris[t];
    if (is_dead(tri)) continue;
    out.triangles.push_back({remap[tri[0]], remap[tri[1]], remap[tri[2]]});
    if (parts) out.triangle_part.push_back(w.part[t]);
  }
  out.part_names = input.part_names;
  return out;
}

std::vector<TrianglePair> pairs_of_region(const Work& w, int32_t only) {
  if (only < 0) return w.pairs;
  std::vector<TrianglePair> out;
  for (const auto& p : w.pairs)
    if (w.region_of[p.a] == only || w.region_of[p.b] == only) out.push_back(p);
  return out;
}

std::vector<uint8_t> clean_regions(const Work& w, size_t regions_found) {
  std::vector<uint8_t> clean(regions_found, 1);
  for (const auto& p : w.pairs)
    for (uint32_t t : {p.a, p.b})
      if (w.region_of[t] >= 0) clean[size_t(w.region_of[t])] = 0;
  return clean;
}

void split_edge(Work& w, std::vector<std::vector<uint32_t>>& vf, uint32_t u, uint32_t v, uint32_t m,
                std::vector<uint32_t>& changed) {
  // vf lists a triangle once per corner: one with a repeated corner (a degenerate triangle,
  // u v u) is listed twice at u, and is cut once. (Cut twice, its second pass looked for the
  // edge u v it no longer had, past the triangle's three corners, and erased a missing entry
  // of vf: heap corruption, found by the 2026-11-26 sweep on a float STL far from the origin.)
  std::vector<uint32_t> on;
  for (uint32_t f : vf[u]) {
    const Tri& t = w.tris[f];
    if ((t[0] == v || t[1] == v || t[2] == v) && std::find(on.begin(), on.end(), f) == on.end()) on.push_back(f);
  }
  vf.resize(std::max<size_t>(vf.size(), m + 1));
  for (uint32_t f : on) {
    Tri t = w.tris[f];
    int k = 0;
    while (k < 3 && !((t[k] == u && t[(k + 1) % 3] == v) || (t[k] == v && t[(k + 1) % 3] == u))) ++k;
    if (k == 3) continue;  // not for u != v; never read past the three corners
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
    const auto at = std::find(row.begin(), row.end(), f);
    if (at != row.end()) row.erase(at);
    vf[m].push_back(f);
    for (uint32_t x : other) vf[x].push_back(id);
    changed.push_back(f);
    changed.push_back(id);
  }
}

void check_cancel(ProgressSink* progress) {
  if (progress && progress->cancelled()) throw Error(ErrorKind::Cancelled, "cancelled");
}

void start_round(ProgressSink* progress, const std::string& step, int round, int rounds, size_t pairs_left) {
  check_cancel(progress);
  if (progress) progress->progress(step, double(round) / rounds, std::to_string(pairs_left) + " intersecting pairs");
}

bool debug_enabled() {
  static const bool on = debug::setting("VDBWRAP_REPAIR_DEBUG") != nullptr;
  return on;
}

}  // namespace vdbwrap::local_repair
