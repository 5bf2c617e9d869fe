#include "mesh/orient.h"

#include <tbb/parallel_for.h>

#include <utility>

#include "common/edge_key.h"
#include "common/vec.h"
#include "mesh/radial_pairs.h"

namespace vdbwrap::mesh {

size_t orient_pieces(const std::vector<Vec3>& points, std::vector<Tri>& triangles, const EdgeTriangles* edges,
                     std::vector<uint32_t>* closed) {
  // Triangles meeting at an edge used by exactly two of them must traverse it in opposite
  // directions; a breadth-first walk flips neighbours that disagree. At an edge of more, only
  // triangles paired around it (radial_pairs.h) are neighbours.
  EdgeTriangles made;
  const EdgeTriangles& edge_tris = edges ? *edges : (made = edge_triangles(triangles));

  // Per triangle side, in parallel (the edge lookups were most of the walk): the triangle
  // across it when the edge has exactly two, and whether that one runs the edge the same way.
  constexpr uint32_t none = UINT32_MAX;
  std::vector<uint32_t> across(3 * triangles.size(), none);
  std::vector<uint8_t> same_way(3 * triangles.size(), 0);
  tbb::parallel_for(tbb::blocked_range<size_t>(0, triangles.size(), 4096), [&](const tbb::blocked_range<size_t>& r) {
    for (size_t t = r.begin(); t != r.end(); ++t)
      for (int e = 0; e < 3; ++e) {
        const uint32_t a = triangles[t][e], b = triangles[t][(e + 1) % 3];
        const size_t edge = edge_tris.find(edge_key(a, b));
        const uint32_t* nb = edge_tris.begin(edge);
        // Solids welded along an edge (struts meeting at a lattice node) pair their own
        // triangles there: each stays one closed piece.
        const uint32_t n = edge_tris.size(edge) == 2
                               ? (nb[0] == t ? nb[1] : nb[0])
                               : radial_partner(points, triangles, a, b, nb, edge_tris.size(edge), t);
        if (n == none) continue;
        across[3 * t + e] = n;
        same_way[3 * t + e] = directed_side(triangles[n], a, b) >= 0 ? 1 : 0;
      }
  });

  std::vector<int32_t> piece(triangles.size(), -1);
  std::vector<uint8_t> flip(triangles.size(), 0);
  std::vector<uint32_t> queue;
  int32_t pieces = 0;
  for (uint32_t seed = 0; seed < triangles.size(); ++seed) {
    if (piece[seed] >= 0) continue;
    piece[seed] = pieces;
    queue.assign(1, seed);
    for (size_t q = 0; q < queue.size(); ++q) {
      const uint32_t t = queue[q];
      // A flipped triangle runs its sides backwards, last first.
      static constexpr int forward[3] = {0, 1, 2}, backward[3] = {2, 1, 0};
      for (int e : flip[t] ? backward : forward) {
        const uint32_t n = across[3 * t + e];
        if (n == none || piece[n] >= 0) continue;
        piece[n] = pieces;
        // The neighbour must run the edge the other way from t as t now stands; if it runs
        // it the same way it disagrees and is flipped.
        flip[n] = same_way[3 * t + e] ^ flip[t];
        queue.push_back(n);
      }
    }
    ++pieces;
  }
  // Outward: a piece whose signed volume is negative is turned over as a whole.
  std::vector<double> volume(pieces, 0.0);
  for (uint32_t t = 0; t < triangles.size(); ++t) {
    Tri cur = triangles[t];
    if (flip[t]) std::swap(cur[1], cur[2]);
    volume[piece[t]] += dot(points[cur[0]], cross(points[cur[1]], points[cur[2]]));
  }
  if (closed) {
    std::vector<uint8_t> open(pieces, 0);
    for (uint32_t t = 0; t < triangles.size(); ++t)
      for (int e = 0; e < 3; ++e)
        if (across[3 * t + e] == none) open[piece[t]] = 1;
    // Closed pieces numbered in order of their first triangle.
    std::vector<uint32_t> number(pieces, kOpenPiece);
    uint32_t closed_pieces = 0;
    closed->resize(triangles.size());
    for (uint32_t t = 0; t < triangles.size(); ++t) {
      if (!open[piece[t]] && number[piece[t]] == kOpenPiece) number[piece[t]] = closed_pieces++;
      (*closed)[t] = number[piece[t]];
    }
  }
  size_t flipped = 0;
  for (uint32_t t = 0; t < triangles.size(); ++t) {
    bool f = flip[t] != (volume[piece[t]] < 0 ? 1 : 0);
    if (f) {
      std::swap(triangles[t][1], triangles[t][2]);
      ++flipped;
    }
  }
  return flipped;
}

}  // namespace vdbwrap::mesh
