// Stage 4, coarsening: the voxel wrap has a node per finest lattice node, several times the
// triangles the input's shape needs on flat parts. Half-edge collapses (a vertex merged into
// a neighbour, no new positions, so every kept node stays where projection put it) remove
// them while the surface stays closed, 2-manifold, free of self-intersections and close to
// the input; nodes snapped onto feature curves go only along straight runs of their chain.
// Blocks of the surface far enough apart coarsen at once, each on its own; the few edges
// whose rings leave their block's reach are then checked in parallel, in batches of edges
// whose 1-rings do not touch, and applied in queue order. The result does not depend on
// the number of threads.
#pragma once
#include <cstdint>
#include <vector>

#include "mesh/surface_index.h"
#include "vdbwrap/progress.h"

namespace vdbwrap::post {

struct CoarsenParams {
  double max_deviation = 0;         // model units: new triangles' sample points stay this close to the input
  double max_edge = 0;              // longest edge a collapse may make
  double min_area2 = 0;             // smallest doubled triangle area allowed
  double max_normal_turn_deg = 25;  // a triangle may turn at most this much
  double min_angle_deg = 18;        // smallest angle of a new triangle (unless the old one was worse)
  double max_chain_turn_deg = 8;    // a feature node goes only where its chain turns less than this
};

struct CoarsenStats {
  size_t collapses = 0, triangles_before = 0, triangles_after = 0;
  std::vector<uint32_t> remap;  // old point -> new point (UINT32_MAX: merged away), for per-point data
};

// points in output coordinates; `input` is indexed in the local frame (local = output - origin).
// locked: vertices that must stay (snapped feature nodes). Compacts points and triangles
// (stats.remap says where each point went).
CoarsenStats coarsen(std::vector<Vec3>& points, std::vector<Tri>& triangles, const std::vector<uint8_t>& locked,
                     const mesh::SurfaceIndex& input, const Vec3& origin, const CoarsenParams& params,
                     ProgressSink* progress);

}  // namespace vdbwrap::post
