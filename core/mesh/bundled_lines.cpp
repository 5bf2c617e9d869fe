#include "mesh/bundled_lines.h"

#include <algorithm>
#include <cmath>
#include <utility>

#include <tbb/parallel_for.h>

#include "common/edge_key.h"
#include "common/vec.h"
#include "mesh/orient.h"
#include "mesh/segment_grid.h"

namespace vdbwrap::mesh {
namespace {

// Lines whose faces are closer to opposite than this (the sum of their unit normals shorter)
// have no outward side to compare along: a knife edge, faces that touch back to back.
constexpr double kShortestOutward = 0.2;
// Along `out`, lines nearer than this fraction of the width are level: copies of one body
// tessellated twice coincide up to the float rounding of a file.
constexpr double kLevel = 1e-3;

Vec3 outward(const Vec3& sum) {
  const double n = norm(sum);
  return n > kShortestOutward ? sum * (1 / n) : Vec3{0, 0, 0};
}

bool oriented(const OrientedLine& l) { return norm2(l.out) > 0; }

}  // namespace

std::vector<uint8_t> inner_lines_of_bundles(const std::vector<OrientedLine>& lines, double width, double cell,
                                            double angle_deg) {
  std::vector<uint8_t> inner(lines.size(), 0);
  if (!(width > 0) || !(cell > 0) || lines.size() < 2) return inner;
  double total = 0;
  size_t oriented_lines = 0;
  for (const OrientedLine& l : lines)
    if (oriented(l)) total += norm(l.b - l.a), ++oriented_lines;
  SegmentGrid grid(cell, width, total, oriented_lines);
  for (size_t i = 0; i < lines.size(); ++i)
    if (oriented(lines[i])) grid.add(uint32_t(i), lines[i].a, lines[i].b);
  const double parallel = std::cos(angle_deg * M_PI / 180), level = kLevel * width;
  // Whether a line farther out than line i, parallel to it and facing its way, passes within
  // `width` of p.
  auto beside_farther = [&](uint32_t i, const Vec3& dir, const Vec3& p) {
    const OrientedLine& s = lines[i];
    return grid.beside(p, i, [&](uint32_t j, const Vec3& d) {
      const OrientedLine& t = lines[j];
      if (dot(s.out, t.out) < parallel || std::abs(dot(dir, normalized(t.b - t.a))) < parallel) return false;
      const double h = dot(d, s.out);
      return h > level || (h >= -level && j < i);
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
