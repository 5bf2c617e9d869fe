// Step 5 of the repair: small pieces the repair left behind, on their own or still
// intersecting, are deleted where all of them lies within the deviation bound of the rest.
#include <cmath>
#include <numeric>
#include <unordered_map>
#include <unordered_set>
#include <vector>

#include "common/vec.h"
#include "mesh/surface_index.h"
#include "repair/steps.h"

namespace vdbwrap::local_repair {

using check::TrianglePair;

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
    if (is_dead(t)) continue;
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
    if (is_dead(tri)) continue;
    Piece& p = pieces[find(tri[0])];
    p.tris.push_back(t);
    p.area += 0.5 * norm(area_vector(w.points[tri[0]], w.points[tri[1]], w.points[tri[2]]));
    p.touched |= w.touched[t] || intersecting.count(t);
  }
  if (pieces.size() < 2) return;
  std::vector<uint32_t> doomed, kept;
  for (const auto& [root, p] : pieces) {
    bool small =
        p.tris.size() <= size_t(params.small_piece_triangles) && p.area <= params.small_piece_area * total_area;
    (small && p.touched ? doomed : kept)
        .insert((small && p.touched ? doomed : kept).end(), p.tris.begin(), p.tris.end());
  }
  if (doomed.empty() || kept.empty()) return;
  // A piece goes only when all of it lies within the deviation bound of what stays.
  std::vector<Tri> kept_tris;
  for (uint32_t t : kept) kept_tris.push_back(w.tris[t]);
  mesh::SurfaceIndex rest(w.points, kept_tris);
  for (const auto& [root, p] : pieces) {
    bool small =
        p.tris.size() <= size_t(params.small_piece_triangles) && p.area <= params.small_piece_area * total_area;
    if (!(small && p.touched)) continue;
    bool near = true;
    for (uint32_t t : p.tris)
      for (uint32_t v : w.tris[t]) near &= std::sqrt(rest.squared_distance(w.points[v])) <= max_dev;
    if (!near) continue;
    ++report.pieces_removed;
    report.piece_triangles_removed += p.tris.size();
    for (uint32_t t : p.tris) w.tris[t] = dead_triangle();
  }
  std::unordered_set<uint32_t> gone;
  for (uint32_t t = 0; t < w.tris.size(); ++t)
    if (is_dead(w.tris[t])) gone.insert(t);
  std::vector<TrianglePair> p;
  for (const auto& x : w.pairs)
    if (!touches(x, gone)) p.push_back(x);
  w.set_pairs(std::move(p));
}

}  // namespace vdbwrap::local_repair
