#include "prep/prepare.h"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <unordered_map>

#include <tbb/parallel_for.h>
#include <tbb/parallel_sort.h>

#include "check/intersections.h"
#include "common/edge_key.h"
#include "common/edge_triangles.h"
#include "common/exact_weld.h"
#include "common/fill_vector.h"
#include "common/grid_key.h"
#include "common/sorted_point_grid.h"
#include "common/vec.h"
#include "vdbwrap/errors.h"

namespace vdbwrap::prep {
namespace {

// Per point: is another point within the tolerance? In parallel, on a grid of cells much
// wider than the tolerance, so that most points look in their own cell only. A point that
// has none is its own weld whatever the order (and no other point's), so only the crowded
// ones need the ordered pass below: on most inputs none.
std::vector<uint8_t> crowded_points(const std::vector<Vec3>& points, double tolerance) {
  const size_t n = points.size();
  const double tol2 = tolerance * tolerance;
  const SortedPointGrid grid(points, 1024 * tolerance);
  std::vector<uint8_t> crowded(n, 0);
  tbb::parallel_for(tbb::blocked_range<size_t>(0, n, 4096), [&](const tbb::blocked_range<size_t>& r) {
    for (size_t i = r.begin(); i != r.end(); ++i) {
      const Vec3& p = points[i];
      crowded[i] = grid.any_near(p, tolerance, [&](uint32_t j) { return j != i && norm2(points[j] - p) <= tol2; }) ? 1 : 0;
    }
  });
  return crowded;
}

}  // namespace

std::vector<uint32_t> weld_points(const std::vector<Vec3>& points, double tolerance, std::vector<Vec3>& welded) {
  // Bit-identical copies first, in parallel (an STL file repeats every point about six
  // times); then the tolerance, among the distinct points only.
  std::vector<Vec3> distinct;
  const std::vector<uint32_t> copy_of = exact_weld(points, distinct);
  std::vector<uint32_t> distinct_to_welded(distinct.size());
  welded.clear();
  if (tolerance > 0) {
    // In order, each crowded point goes to the first weld within the tolerance (hash grid with
    // cells of the tolerance: a match can only be in the 27 cells around), or starts one.
    const std::vector<uint8_t> crowded = crowded_points(distinct, tolerance);
    const double inv = 1.0 / tolerance, tol2 = tolerance * tolerance;
    std::unordered_map<GridKey, std::vector<uint32_t>, GridKeyHash> buckets;
    for (size_t i = 0; i < distinct.size(); ++i) {
      const Vec3& p = distinct[i];
      uint32_t found = UINT32_MAX;
      if (crowded[i]) {
        const GridKey key = grid_key(p, inv);
        for (int dx = -1; dx <= 1 && found == UINT32_MAX; ++dx)
          for (int dy = -1; dy <= 1 && found == UINT32_MAX; ++dy)
            for (int dz = -1; dz <= 1 && found == UINT32_MAX; ++dz) {
              auto it = buckets.find({key.x + dx, key.y + dy, key.z + dz});
              if (it == buckets.end()) continue;
              for (uint32_t w : it->second)
                if (norm2(welded[w] - p) <= tol2) {
                  found = w;
                  break;
                }
            }
        if (found == UINT32_MAX) buckets[key].push_back(uint32_t(welded.size()));
      }
      if (found == UINT32_MAX) {
        found = uint32_t(welded.size());
        welded.push_back(p);
      }
      distinct_to_welded[i] = found;
    }
  } else {
    welded = distinct;
    for (size_t i = 0; i < distinct.size(); ++i) distinct_to_welded[i] = uint32_t(i);
  }
  std::vector<uint32_t> remap(points.size());
  tbb::parallel_for(tbb::blocked_range<size_t>(0, points.size(), 8192), [&](const tbb::blocked_range<size_t>& r) {
    for (size_t i = r.begin(); i != r.end(); ++i) remap[i] = distinct_to_welded[copy_of[i]];
  });
  return remap;
}

size_t orient_pieces(const std::vector<Vec3>& points, std::vector<Tri>& triangles, const EdgeTriangles* edges) {
  // Triangles meeting at an edge used by exactly two of them must traverse it in opposite
  // directions; a breadth-first walk flips neighbours that disagree.
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
        if (edge_tris.size(edge) != 2) continue;
        const uint32_t* nb = edge_tris.begin(edge);
        const uint32_t n = nb[0] == t ? nb[1] : nb[0];
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

std::vector<FeatureEdge> find_feature_edges(const std::vector<Vec3>& points, const std::vector<Tri>& triangles,
                                            const std::vector<Vec3>& normals, double feature_angle_deg,
                                            const EdgeTriangles* edges) {
  (void)points;
  EdgeTriangles made;
  const EdgeTriangles& edge_tris = edges ? *edges : (made = edge_triangles(triangles));
  const double cos_limit = std::cos(feature_angle_deg * M_PI / 180.0);
  std::vector<FeatureEdge> out;
  // Keys in increasing order: the edges come out sorted by (a, b).
  for (size_t i = 0; i < edge_tris.edges(); ++i) {
    const uint64_t key = edge_tris.keys[i];
    const uint32_t a = uint32_t(key >> 32), b = uint32_t(key & 0xffffffffu);
    const uint32_t* tris = edge_tris.begin(i);
    if (edge_tris.size(i) == 1) {
      out.push_back({a, b, FeatureKind::Boundary});
    } else if (edge_tris.size(i) > 2) {
      out.push_back({a, b, FeatureKind::NonManifold});
    } else if (dot(normals[tris[0]], normals[tris[1]]) < cos_limit) {
      out.push_back({a, b, FeatureKind::Sharp});
    }
  }
  return out;
}

InputIntersections input_intersections(const std::vector<check::TrianglePair>& mesh_pairs,
                                       const std::vector<uint32_t>& input_to_mesh, size_t mesh_triangles) {
  // copies[k]: input triangles that became mesh triangle k (1, or more for duplicates).
  std::vector<uint32_t> copies(mesh_triangles, 0);
  for (uint32_t k : input_to_mesh)
    if (k != UINT32_MAX) ++copies[k];
  InputIntersections counts;
  std::vector<uint8_t> hit(mesh_triangles, 0);
  for (const auto& p : mesh_pairs) {
    counts.pairs += size_t(copies[p.a]) * copies[p.b];
    hit[p.a] = hit[p.b] = 1;
  }
  for (size_t k = 0; k < mesh_triangles; ++k) {
    // Copies of one triangle lie on each other: every two of them make an intersecting pair.
    counts.pairs += copies[k] > 1 ? size_t(copies[k]) * (copies[k] - 1) / 2 : 0;
    if (hit[k] || copies[k] > 1) counts.triangles += copies[k];
  }
  return counts;
}

PreparedInput prepare(const Mesh& input, const PrepareParams& params, ProgressSink* progress, const ExactWeld* input_weld) {
  PreparedInput out;
  if (input.triangles.empty()) throw Error(ErrorKind::InvalidInput, "input contains no triangles");
  for (const Vec3& p : input.points)
    if (!std::isfinite(p[0]) || !std::isfinite(p[1]) || !std::isfinite(p[2]))
      throw Error(ErrorKind::InvalidInput, "input has a vertex with a non-finite coordinate");
  // The extent of the surface, not of the file: stray points that no triangle uses (scans keep
  // them) would otherwise widen every size given in % of the diagonal.
  Box3 box;
  for (const Tri& t : input.triangles)
    for (uint32_t v : t) box.add(input.points[v]);
  out.origin = box.center();
  out.diagonal = box.diagonal();
  if (!(out.diagonal > 0)) throw Error(ErrorKind::InvalidInput, "input has zero extent (all vertices coincide)");

  if (progress) progress->progress("prepare", 0.0, "welding vertices");
  // Points equal in the input stay equal in the local frame, and the weld's distinct points
  // come in the order of first appearance either way: welding the input's distinct points
  // and composing gives what welding all of them would (an STL file repeats each about six
  // times, and their exact weld was half of this step).
  const std::vector<Vec3>& from = input_weld ? input_weld->unique : input.points;
  std::vector<Vec3> local(from.size());
  tbb::parallel_for(tbb::blocked_range<size_t>(0, local.size(), 8192), [&](const tbb::blocked_range<size_t>& r) {
    for (size_t i = r.begin(); i != r.end(); ++i) local[i] = from[i] - out.origin;
  });
  std::vector<Vec3> welded;
  std::vector<uint32_t> remap = weld_points(local, params.weld_tolerance * out.diagonal, welded);
  if (input_weld) {
    std::vector<uint32_t> composed(input.points.size());
    tbb::parallel_for(tbb::blocked_range<size_t>(0, composed.size(), 8192), [&](const tbb::blocked_range<size_t>& r) {
      for (size_t i = r.begin(); i != r.end(); ++i) composed[i] = remap[input_weld->remap[i]];
    });
    remap.swap(composed);
  }
  out.welded_vertices = input.points.size() - welded.size();

  // Drop triangles with repeated or collinear vertices (normal undefined) and exact duplicates.
  Mesh& m = out.mesh;
  m.points = std::move(welded);
  m.part_names = input.part_names;
  if (m.part_names.empty()) m.part_names.push_back("part0");
  // Per input triangle, in parallel: its welded corners, and whether it is degenerate. Then
  // copies by a parallel sort of the sorted corner triples: the first of each group (in input
  // order) stays, the others map to it. (A hash map of buckets, one heap block per triangle,
  // was a serial tenth of preparing a million triangles.)
  const size_t n = input.triangles.size();
  std::vector<Tri> welded_tris(n);
  std::vector<uint8_t> degenerate(n, 0);
  struct Corners {
    Tri sorted;
    uint32_t t;
    bool operator<(const Corners& o) const { return sorted != o.sorted ? sorted < o.sorted : t < o.t; }
  };
  std::vector<Corners> corners(n);
  tbb::parallel_for(tbb::blocked_range<size_t>(0, n, 4096), [&](const tbb::blocked_range<size_t>& r) {
    for (size_t t = r.begin(); t != r.end(); ++t) {
      const Tri tri{remap[input.triangles[t][0]], remap[input.triangles[t][1]], remap[input.triangles[t][2]]};
      welded_tris[t] = tri;
      const Vec3 &a = m.points[tri[0]], &b = m.points[tri[1]], &c = m.points[tri[2]];
      const double longest2 = std::max({norm2(b - a), norm2(c - b), norm2(a - c)});
      degenerate[t] = tri[0] == tri[1] || tri[1] == tri[2] || tri[0] == tri[2] ||
                      norm2(area_vector(a, b, c)) <= 1e-24 * longest2 * longest2;
      Tri sorted = tri;
      std::sort(sorted.begin(), sorted.end());
      corners[t] = {sorted, uint32_t(t)};
    }
  });
  tbb::parallel_sort(corners.begin(), corners.end());
  std::vector<uint32_t> copy_of(n, UINT32_MAX);  // the first non-degenerate triangle with the same corners
  for (size_t k = 0; k < n;) {
    size_t e = k;
    uint32_t first = UINT32_MAX;
    for (; e < n && corners[e].sorted == corners[k].sorted; ++e)
      if (!degenerate[corners[e].t]) {
        if (first == UINT32_MAX) first = corners[e].t;
        copy_of[corners[e].t] = first;
      }
    k = e;
  }
  out.input_to_mesh.assign(n, UINT32_MAX);
  for (size_t t = 0; t < n; ++t) {
    if (degenerate[t]) {
      ++out.dropped_degenerate;
    } else if (copy_of[t] != t) {
      out.input_to_mesh[t] = out.input_to_mesh[copy_of[t]];  // an earlier triangle: numbered
      ++out.dropped_duplicate;
    } else {
      out.input_to_mesh[t] = uint32_t(m.triangles.size());
      m.triangles.push_back(welded_tris[t]);
      m.triangle_part.push_back(input.part_of(t));
    }
  }
  if (m.triangles.empty())
    throw Error(ErrorKind::InvalidInput, "input has no usable triangles: all " + std::to_string(input.triangles.size()) +
                                             " are degenerate");
  if (progress && progress->cancelled()) throw Error(ErrorKind::Cancelled, "cancelled");

  if (progress) progress->progress("prepare", 0.3, "orienting connected pieces");
  // One edge listing for orienting and for the feature edges: flips change no triangle's edges.
  const EdgeTriangles edges = edge_triangles(m.triangles);
  out.flipped_triangles = orient_pieces(m.points, m.triangles, &edges);

  out.normals.resize(m.triangles.size());
  tbb::parallel_for(tbb::blocked_range<size_t>(0, m.triangles.size(), 4096), [&](const tbb::blocked_range<size_t>& r) {
    for (size_t t = r.begin(); t != r.end(); ++t) {
      const Tri& tri = m.triangles[t];
      out.normals[t] = normalized(area_vector(m.points[tri[0]], m.points[tri[1]], m.points[tri[2]]));
    }
  });
  if (progress) progress->progress("prepare", 0.5, "finding feature edges");
  out.feature_edges = find_feature_edges(m.points, m.triangles, out.normals, params.feature_angle_deg, &edges);

  if (progress) progress->progress("prepare", 0.7, "finding self-intersection lines");
  out.intersecting_pairs = check::find_intersecting_pairs(m.points, m.triangles, check::SoupKind::kInput, &edges);
  for (const auto& seg : check::intersection_segments(m.points, m.triangles, out.intersecting_pairs))
    out.intersections.push_back({seg.a, seg.b, seg.tri_a, seg.tri_b});
  if (progress) progress->progress("prepare", 1.0, "done");
  return out;
}

}  // namespace vdbwrap::prep
