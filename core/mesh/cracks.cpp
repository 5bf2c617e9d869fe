#include "mesh/cracks.h"

#include <algorithm>
#include <cmath>
#include <utility>

#include <tbb/parallel_for.h>

#include "common/edge_key.h"
#include "common/union_find.h"
#include "common/vec.h"
#include "mesh/segment_grid.h"
#include "mesh/weld.h"

namespace vdbwrap::mesh {
namespace {

// Partners of a gap's side within this many times the nearest's distance, or a sixteenth of the
// width (the nearest may be a copy of the side itself), are as near.
constexpr double kAsNear = 4;

// Whether `beside(p)` holds at the middle of a-b, a quarter from each end and two widths from
// each end: a side overlapped but for its end (a panel's edge beside a window's, shorter) is
// the rim of an opening there.
template <typename Beside>
bool covered_along(const Vec3& a, const Vec3& b, double width, Beside&& beside) {
  const double inset = std::min(0.25, 2 * width / norm(b - a));
  for (double f : {0.5, 0.25, 0.75, inset, 1 - inset})
    if (!beside(lerp(a, b, f))) return false;
  return true;
}

}  // namespace

std::vector<CrackSide> crack_sides(const std::vector<Vec3>& points, const std::vector<Tri>& triangles,
                                   const std::vector<Vec3>& normals, const std::vector<FeatureEdge>& edges,
                                   double width, double cell, double angle_deg, double feature_angle_deg,
                                   bool nearest_partner, std::vector<std::array<uint32_t, 2>>* faces_across,
                                   const std::vector<CrackSide>* decided) {
  std::vector<CrackSide> crack(edges.size(), CrackSide::None);
  if (faces_across) faces_across->assign(edges.size(), {UINT32_MAX, UINT32_MAX});
  if (!(width > 0) || !(cell > 0) || normals.size() != triangles.size()) return crack;
  // The one face of each boundary edge.
  std::vector<std::pair<uint64_t, uint32_t>> rim;  // (edge key, index into edges), sorted
  double total = 0;
  for (size_t i = 0; i < edges.size(); ++i)
    if (edges[i].kind == FeatureKind::Boundary) {
      rim.emplace_back(edge_key(edges[i].a, edges[i].b), uint32_t(i));
      total += norm(points[edges[i].b] - points[edges[i].a]);
    }
  if (rim.size() < 2) return crack;
  // A gap wider than a quarter of the faces' edges tilts the faces across it as much as a
  // crease (a soup of confetti: its rims go as small ones, its tilts as noise), and the search
  // would look at many edges per point.
  if (nearest_partner) width = std::min(width, total / double(rim.size()) / 4);
  std::sort(rim.begin(), rim.end());
  std::vector<uint32_t> face(edges.size(), UINT32_MAX);
  for (size_t t = 0; t < triangles.size(); ++t)
    for (int e = 0; e < 3; ++e) {
      const uint64_t key = edge_key(triangles[t][e], triangles[t][(e + 1) % 3]);
      const auto it = std::lower_bound(rim.begin(), rim.end(), std::make_pair(key, uint32_t(0)));
      if (it != rim.end() && it->first == key) face[it->second] = uint32_t(t);
    }
  // Cells about as long as the edges: a soup's are many to a base cell.
  SegmentGrid grid(std::min(cell, 2 * total / double(rim.size())), width, total, rim.size());
  for (const auto& [key, i] : rim)
    if (face[i] != UINT32_MAX) grid.add(i, points[edges[i].a], points[edges[i].b]);
  // The surface's connected pieces: across a gap wider than a hairline, the other side is
  // another piece (a soup's triangle, a CAD face tessellated on its own); within a piece, edges
  // side by side are a jagged rim's zigzag.
  std::vector<uint32_t> piece(triangles.size(), 0);
  if (nearest_partner) {
    UnionFind joined(points.size());
    for (const Tri& t : triangles) joined.unite(t[0], t[1]), joined.unite(t[1], t[2]);
    for (size_t t = 0; t < triangles.size(); ++t) piece[t] = joined.find(triangles[t][0]);
  }
  const double parallel = std::cos(angle_deg * M_PI / 180), crease = std::cos(feature_angle_deg * M_PI / 180);
  tbb::parallel_for(tbb::blocked_range<size_t>(0, rim.size(), 256), [&](const tbb::blocked_range<size_t>& r) {
    std::vector<std::pair<double, uint32_t>> beside;  // (squared distance, edge) at an edge's middle
    for (size_t k = r.begin(); k != r.end(); ++k) {
      const uint32_t i = rim[k].second;
      const Vec3 &a = points[edges[i].a], &b = points[edges[i].b];
      if (face[i] == UINT32_MAX || !(norm2(b - a) > 0) || (decided && (*decided)[i] != CrackSide::None)) continue;
      const Vec3 dir = normalized(b - a);
      auto parallel_side = [&](uint32_t j) {
        const auto& s = grid.segment(j);
        return (!nearest_partner || piece[face[j]] != piece[face[i]]) &&
               std::abs(dot(dir, normalized(s[1] - s[0]))) >= parallel;
      };
      // The other side, at the middle: a hairline crack's first parallel edge found; a gap's
      // nearest (a soup's neighbours of either side lie within a gap's width too: a row of a
      // fine tessellation beside a crease)...
      const Vec3 middle = lerp(a, b, 0.5);
      uint32_t other = UINT32_MAX;
      double nearest = INFINITY;
      beside.clear();
      grid.beside(middle, i, [&](uint32_t j, const Vec3& d) {
        if (!parallel_side(j)) return false;
        if (norm2(d) < nearest) nearest = norm2(d), other = j;
        if (nearest_partner) beside.emplace_back(norm2(d), j);
        return !nearest_partner;
      });
      if (other == UINT32_MAX) continue;
      // ... or, as near, the face across a crease: a face written twice lies as near as that.
      const double near = std::max(kAsNear * std::sqrt(nearest), width / 16);
      double across = INFINITY;
      for (const auto& [d2, j] : beside)
        if (d2 <= near * near && d2 < across && dot(normals[face[i]], normals[face[j]]) < crease)
          across = d2, other = j;
      const bool covered = covered_along(a, b, width, [&](const Vec3& p) {
        // In a soup one edge of the other side covers all of this one: asked first.
        return grid.passes_beside(other, p) ||
               grid.beside(p, i, [&](uint32_t j, const Vec3&) { return parallel_side(j); });
      });
      if (!covered) continue;
      if (faces_across) (*faces_across)[i] = {face[i], face[other]};
      if (dot(normals[face[i]], normals[face[other]]) >= crease) {
        crack[i] = CrackSide::Goes;
        continue;
      }
      // A crease: the side whose normal leads in the largest component of the two normals'
      // difference stays; all along the crack the same side, however its edges pair up.
      const Vec3 d = normals[face[i]] - normals[face[other]];
      int lead = 0;
      for (int c = 1; c < 3; ++c)
        if (std::abs(d[c]) > std::abs(d[lead])) lead = c;
      crack[i] = d[lead] < 0 ? CrackSide::Goes : CrackSide::Crease;
    }
  });
  return crack;
}

std::vector<uint8_t> crossings_along_cracks(const std::vector<Vec3>& points, const std::vector<FeatureEdge>& edges,
                                            const std::vector<CrackSide>& side,
                                            const std::vector<std::array<Vec3, 2>>& lines, double width, double cell,
                                            double angle_deg) {
  std::vector<uint8_t> along(lines.size(), 0);
  if (!(width > 0) || !(cell > 0) || lines.empty()) return along;
  double total = 0;
  size_t count = 0;
  for (size_t i = 0; i < edges.size(); ++i)
    if (side[i] != CrackSide::None) total += norm(points[edges[i].b] - points[edges[i].a]), ++count;
  if (count == 0) return along;
  SegmentGrid grid(std::min(cell, 2 * total / double(count)), width, total, count);
  for (size_t i = 0; i < edges.size(); ++i)
    if (side[i] != CrackSide::None) grid.add(uint32_t(i), points[edges[i].a], points[edges[i].b]);
  const double parallel = std::cos(angle_deg * M_PI / 180);
  tbb::parallel_for(tbb::blocked_range<size_t>(0, lines.size(), 256), [&](const tbb::blocked_range<size_t>& r) {
    for (size_t k = r.begin(); k != r.end(); ++k) {
      const Vec3 &a = lines[k][0], &b = lines[k][1];
      if (!(norm2(b - a) > 0)) continue;
      const Vec3 dir = normalized(b - a);
      along[k] = covered_along(a, b, width, [&](const Vec3& p) {
        return grid.beside(p, UINT32_MAX, [&](uint32_t j, const Vec3&) {
          const auto& s = grid.segment(j);
          return std::abs(dot(dir, normalized(s[1] - s[0]))) >= parallel;
        });
      });
    }
  });
  return along;
}

void join_crease_ends(const std::vector<Vec3>& points, const std::vector<CrackSide>& side, double width,
                      std::vector<FeatureEdge>& edges) {
  if (!(width > 0)) return;
  // The kept edges' ends in edge order, welded; each weld's first end stands for it.
  std::vector<uint32_t> ends;
  for (size_t i = 0; i < edges.size(); ++i)
    if (side[i] == CrackSide::Crease) ends.push_back(edges[i].a), ends.push_back(edges[i].b);
  std::vector<Vec3> at(ends.size()), welded;
  for (size_t k = 0; k < ends.size(); ++k) at[k] = points[ends[k]];
  const std::vector<uint32_t> weld = weld_points(at, width, welded);
  std::vector<uint32_t> first(welded.size(), UINT32_MAX);
  for (size_t k = 0; k < ends.size(); ++k)
    if (first[weld[k]] == UINT32_MAX) first[weld[k]] = ends[k];
  size_t k = 0;
  for (size_t i = 0; i < edges.size(); ++i)
    if (side[i] == CrackSide::Crease) edges[i].a = first[weld[k++]], edges[i].b = first[weld[k++]];
}

}  // namespace vdbwrap::mesh
