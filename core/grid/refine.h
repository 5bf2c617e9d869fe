// Stage 2a: mark the cells the input passes through and refine them 2x2x2 per level by the
// spec's criteria (triangles per cell, normal spread, features).
#pragma once
#include <memory>

#include "common/box_overlap.h"
#include "grid/adaptive_grid.h"
#include "grid/size_controls.h"
#include "prep/prepare.h"
#include "vdbwrap/progress.h"

namespace vdbwrap::grid {

struct RefineResult {
  std::unique_ptr<AdaptiveGrid> grid;
  size_t thin_cells = 0;  // cells refined for a part thinner than they are
  std::vector<size_t> touched_per_level;
  std::vector<size_t> refined_per_level;
  // Contact prevention: cells at the floor level still holding parts that must stay apart.
  std::vector<Vec3> unresolved_contacts;  // cell centres, local frame
};

// The spec's criteria for refining a cell the input passes through.
struct RefineCriteria {
  int max_triangles = 64;         // more triangles than this in a cell: refine
  double normal_spread_deg = 20;  // normals spread more than this: refine
  bool at_features = true;        // sharp, boundary or intersection edges: refine
  // A point of the cell's boundary (corners, edge midpoints, face centres) farther than this many
  // base cells from the cell's own triangles: refine (0: off). The wrap's held-back nodes sit on
  // such points, up to a cell diagonal off the input.
  double far_point_cells = 0;
  // Points (local frame) where a first fit was far from the input (held-back nodes, faces
  // bridging a concave crease): a touched cell within `near_reach` of one is refined to the
  // criteria's depth, so the lattice nodes there start near the input.
  std::vector<Vec3> refine_near;
  double near_reach = 0;
  double far_point_reach = 0;  // model units: far_point_cells only this near a refine_near point (0: everywhere)
  // Parts of the input thinner than `thin_fraction` of the cell (grid/thin_parts.h): refined
  // up to `thin_levels` below the criteria's depth (0: off).
  int thin_levels = 2;
  double thin_fraction = 0.5;
};

// base_size in model units. The grid pads the input's bounding box by `padding` level-0
// cells on every side so the outside volume wraps around everything.
// The refinement criteria apply down to controls.criteria_levels; control volumes, part
// sizes and contact prevention down to their own levels (the grid has controls.max_level).
RefineResult build_refined_grid(const prep::PreparedInput& input, const RefineCriteria& criteria, double base_size,
                                const SizeControls& controls, ProgressSink* progress, int padding = 2);

// Exact-enough separating-axis tests of a triangle or segment against an axis-aligned box.
using vdbwrap::segment_overlaps_box;
using vdbwrap::triangle_overlaps_box;

}  // namespace vdbwrap::grid
