#include "mesh/bundled_lines.h"

#include <algorithm>
#include <cmath>
#include <utility>

#include <tbb/parallel_for.h>

#include "common/cell_lists.h"
#include "common/edge_key.h"
#include "common/vec.h"
#include "mesh/orient.h"

namespace vdbwrap::mesh {
namespace {

// Lines whose faces are closer to opposite than this (the sum of their unit normals shorter)
// have no outward side to compare along: a knife edge, faces that touch back to back.
constexpr double kShortestOutward = 0.2;
// Along `out`, lines nearer than this fraction of the width are level: copies of one body
// tessellated twice coincide up to the float rounding of a file.
constexpr double kLevel = 1e-3;
// Steps of a quarter cell along the lines, in all, that the lookup grid is sized for.
constexpr size_t kMostSteps = size_t(1) << 20;

Vec3 outward(const Vec3& sum) {
  const double n = norm(sum);
  return n > kShortestOutward ? sum * (1 / n) : Vec3{0, 0, 0};
}

bool oriented(const OrientedLine& l) { return norm2(l.out) > 0; }

// Lists line i in every cell of `grid` it passes through: in steps of a quarter cell, each
// step's box (at most two cells a side) holds its piece of the line.
void list_line(CellLists<uint32_t>& grid, const OrientedLine& l, uint32_t i, double cell) {
  const double length = norm(l.b - l.a);
  const size_t steps = std::max<size_t>(1, size_t(std::ceil(4 * length / cell)));
  for (size_t s = 0; s < steps; ++s) {
    const Vec3 p = lerp(l.a, l.b, double(s) / double(steps)), q = lerp(l.a, l.b, double(s + 1) / double(steps));
    const GridKey lo = grid.cell_of(Vec3{std::min(p[0], q[0]), std::min(p[1], q[1]), std::min(p[2], q[2])});
    const GridKey hi = grid.cell_of(Vec3{std::max(p[0], q[0]), std::max(p[1], q[1]), std::max(p[2], q[2])});
    CellLists<uint32_t>::for_cells(lo, hi, [&](const GridKey& k) {
      std::vector<uint32_t>& list = grid[k];
      if (list.empty() || list.back() != i) list.push_back(i);  // a line's steps come one after another
    });
  }
}

}  // namespace

std::vector<uint8_t> inner_lines_of_bundles(const std::vector<OrientedLine>& lines, double width, double cell,
                                            double angle_deg) {
  std::vector<uint8_t> inner(lines.size(), 0);
  if (!(width > 0) || !(cell > 0) || lines.size() < 2) return inner;
  // Long lines listed in many cells cost memory and time: the cells widen until the lines
  // take at most kMostSteps steps (each step at most eight cells, mostly one or two).
  double total = 0;
  size_t oriented_lines = 0;
  for (const OrientedLine& l : lines)
    if (oriented(l)) total += norm(l.b - l.a), ++oriented_lines;
  const double most_steps = double(std::max<size_t>(kMostSteps, 8 * oriented_lines));
  cell = std::max({cell, 4 * width, 4 * total / most_steps});
  CellLists<uint32_t> grid(cell);
  for (size_t i = 0; i < lines.size(); ++i)
    if (oriented(lines[i])) list_line(grid, lines[i], uint32_t(i), cell);
  const double parallel = std::cos(angle_deg * M_PI / 180), level = kLevel * width;
  // Whether a line farther out than line i, parallel to it and facing its way, passes within
  // `width` of p.
  auto beside_farther = [&](uint32_t i, const Vec3& dir, const Vec3& p) {
    const OrientedLine& s = lines[i];
    const Vec3 r{width, width, width};
    return CellLists<uint32_t>::for_cells(grid.cell_of(p - r), grid.cell_of(p + r), [&](const GridKey& k) {
      const std::vector<uint32_t>* list = grid.find(k);
      if (!list) return false;
      for (uint32_t j : *list) {
        if (j == i) continue;
        const OrientedLine& t = lines[j];
        if (dot(s.out, t.out) < parallel || std::abs(dot(dir, normalized(t.b - t.a))) < parallel) continue;
        // Beside p, not on from it: the next piece of the same edge ends within `width` of p too.
        const Vec3 ab = t.b - t.a;
        const double at = dot(p - t.a, ab);
        if (!(at >= 0 && at <= norm2(ab))) continue;
        const Vec3 d = t.a + ab * (at / norm2(ab)) - p;
        if (norm2(d) > width * width) continue;
        const double h = dot(d, s.out);
        if (h > level || (h >= -level && j < i)) return true;
      }
      return false;
    });
  };
  tbb::parallel_for(tbb::blocked_range<size_t>(0, lines.size(), 256), [&](const tbb::blocked_range<size_t>& r) {
    for (size_t i = r.begin(); i != r.end(); ++i) {
      const OrientedLine& s = lines[i];
      if (!oriented(s) || !(norm2(s.b - s.a) > 0)) continue;
      const Vec3 dir = normalized(s.b - s.a);
      bool covered = true;
      for (double f : {0.5, 0.25, 0.75})
        if (!(covered = beside_farther(uint32_t(i), dir, lerp(s.a, s.b, f)))) break;
      inner[i] = covered;
    }
  });
  return inner;
}

std::vector<Vec3> sharp_edges_outward(const std::vector<Tri>& triangles, const std::vector<Vec3>& normals,
                                      const std::vector<uint32_t>& closed_piece,
                                      const std::vector<FeatureEdge>& edges) {
  std::vector<Vec3> out(edges.size(), Vec3{0, 0, 0});
  if (closed_piece.size() != triangles.size() || normals.size() != triangles.size()) return out;
  std::vector<std::pair<uint64_t, uint32_t>> sharp;  // (edge key, index into edges), sorted
  for (size_t i = 0; i < edges.size(); ++i)
    if (edges[i].kind == FeatureKind::Sharp) sharp.emplace_back(edge_key(edges[i].a, edges[i].b), uint32_t(i));
  if (sharp.empty()) return out;
  std::sort(sharp.begin(), sharp.end());
  std::vector<Vec3> sum(edges.size(), Vec3{0, 0, 0});
  std::vector<uint8_t> faces(edges.size(), 0), open(edges.size(), 0);
  for (size_t t = 0; t < triangles.size(); ++t)
    for (int e = 0; e < 3; ++e) {
      const uint64_t key = edge_key(triangles[t][e], triangles[t][(e + 1) % 3]);
      const auto it = std::lower_bound(sharp.begin(), sharp.end(), std::make_pair(key, uint32_t(0)));
      if (it == sharp.end() || it->first != key) continue;
      sum[it->second] = sum[it->second] + normals[t];
      faces[it->second] = uint8_t(std::min(faces[it->second] + 1, 3));
      open[it->second] |= closed_piece[t] == kOpenPiece;
    }
  for (size_t i = 0; i < edges.size(); ++i)
    if (faces[i] == 2 && !open[i]) out[i] = outward(sum[i]);
  return out;
}

Vec3 crossing_outward(uint32_t a, uint32_t b, const std::vector<Vec3>& normals,
                      const std::vector<uint32_t>& closed_piece) {
  if (a >= closed_piece.size() || b >= closed_piece.size() || a >= normals.size() || b >= normals.size())
    return Vec3{0, 0, 0};
  if (closed_piece[a] == kOpenPiece || closed_piece[b] == kOpenPiece) return Vec3{0, 0, 0};
  return outward(normals[a] + normals[b]);
}

}  // namespace vdbwrap::mesh
