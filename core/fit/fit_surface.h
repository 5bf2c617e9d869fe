// Stage 3 and the triangulation of stage 4: move every node of the lattice surface to the
// nearest point of the input (a small offset off it), triangulate each polygon choosing the
// diagonal nearest the input, and keep the surface valid at every step by pulling
// offending nodes back toward their lattice positions.
#pragma once
#include <vector>

#include "extract/extract_surface.h"
#include "fit/features.h"
#include "mesh/surface_index.h"
#include "fit/two_sided.h"
#include "grid/adaptive_grid.h"
#include "vdbwrap/progress.h"

namespace vdbwrap::fit {

struct FittedSurface {
  std::vector<Vec3> points;  // output (world) frame: local + origin
  std::vector<Tri> triangles;
  std::vector<uint8_t> snapped;   // per point: on a feature curve (kept by later stages)
  std::vector<double> cell_size;  // per point: edge of the smallest lattice face at it (the local target size)
  std::vector<std::pair<uint32_t, uint32_t>> feature_edges;  // edges traced along the feature curves
  size_t held_back = 0;                                      // nodes that could not go all the way to the input
  std::vector<Vec3> held_back_points;  // where they are (output frame): flagged on the wrap's triangles
  size_t validity_rounds = 0;
  TwoSidedStats two_sided;  // where the wrap's sheets project onto the input from both sides
  // False when the validity loop ran out of rounds: intersecting or degenerate triangles are
  // left for the post-processing (remeshing, then intersection repair) to fix.
  bool valid = true;
  SnapStats snap;
  // Per feature curve: the rim of a sheet wrapped from both sides, which the wrap passes
  // around and which is left to the projection (neither traced nor given nodes).
  std::vector<uint8_t> rim_of_two_sided_sheet;
};

// Offending triangles: those whose doubled area is below min_area2 when there are any (the
// intersection test, the costly part, then waits for the next call: `complete` is false);
// else self-intersecting ones and degenerate faces (`complete` true).
std::vector<uint32_t> invalid_triangles(const std::vector<Vec3>& points, const std::vector<Tri>& triangles,
                                        double min_area2, bool* complete = nullptr);

// What the projection needs of the wrap's parameters (WrapParams has the same fields).
struct FitParams {
  int presmooth_iterations = 16;   // smoothing of the voxel surface before projection (untangling)
  double surface_offset = 0.005;   // nodes stop this fraction of the finest cell off the input
  int validity_rounds = 400;       // rounds of the validity loop
  bool float_coordinates = false;  // validity as it will be stored: coordinates rounded to float
  bool two_sided_sheets = false;   // each side of an input wrapped from both sides projects to its own side
  // How far faces meant to meet stand apart (a crack's gap, model units): the tracing takes a
  // curve point as in reach when the way to it is clear up to two gaps short of it, or half the
  // offset.
  double gap = 0;
};

// `origin` turns the local frame of the grid and the index into output coordinates.
// `curves`: feature curves to snap to (empty: no snapping).
FittedSurface fit_to_input(const extract::LatticeSurface& surface, const grid::AdaptiveGrid& grid,
                           const mesh::SurfaceIndex& input, const std::vector<FeatureCurve>& curves, const Vec3& origin,
                           const FitParams& params, ProgressSink* progress);

}  // namespace vdbwrap::fit
