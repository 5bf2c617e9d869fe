// Stage 2c: the closed, mostly-quad polygon surface made of the cell faces between the
// chosen volume and the rest (the faces nearest the input that do not cross it).
#pragma once
#include <cstdint>
#include <vector>

#include "grid/adaptive_grid.h"
#include "vdbwrap/params.h"
#include "vdbwrap/progress.h"

namespace vdbwrap::extract {

using grid::Coord;

struct LatticeSurface {
  std::vector<Coord> nodes;                     // positions on the finest node lattice
  std::vector<int32_t> node_size;               // smallest incident face edge, in fine units
  std::vector<std::vector<uint32_t>> polygons;  // counter-clockwise seen from outside the wrap
};

// Faces between leaves with value `label` (the chosen volume; outside the box counts as
// chosen for VolumeChoice::Outside) and every other leaf. Nodes that lie on a polygon's
// edges (level transitions) are inserted into it, so the result is conforming.
LatticeSurface extract_faces(const grid::AdaptiveGrid& grid, int32_t label, VolumeChoice choice);

// After `taken_out` left the volume `label` (one piece before), the pieces cut off from
// the rest, found by searches from the volume cells next to the taken-out ones, are taken
// out too (`dropped`: how many). Returns false, changing nothing, when the searches cannot
// tell within their budget, or a piece is not below `pocket_share` of the volume left: a
// full labelling must decide. `total_budget`: the cells all searches together may queue (past
// it a labelling of the whole volume is the cheaper way).
bool drop_cut_off_pockets(grid::AdaptiveGrid& grid, int32_t label, const std::vector<std::pair<int, Coord>>& taken_out,
                          double pocket_share, size_t total_budget, size_t& dropped,
                          std::vector<std::pair<int, Coord>>* dropped_cells = nullptr);

struct ExtractStats {
  size_t excluded_cells = 0, rounds = 0, dropped_pieces = 0;
};

// Extract, repair and repeat until the surface is a closed 2-manifold; keeps only the main
// piece of the volume (the outside one, the largest inside one, or with seed points the
// pieces holding the `anchors`, finest-level cells). `label` may change. Cells finer than
// min_exclude_level (the depth of the refinement criteria) may be taken out of the volume.
// After the first round, a round looks only near the cells the last one changed, unless
// `whole_rounds` (every round over the whole surface: the reference the tests compare with).
LatticeSurface extract_manifold_surface(grid::AdaptiveGrid& grid, int32_t& label, VolumeChoice choice,
                                        ExtractStats& stats, ProgressSink* progress,
                                        const std::vector<Coord>& anchors = {}, int min_exclude_level = -1,
                                        bool whole_rounds = false);

}  // namespace vdbwrap::extract
