// Stage 2b, the user's choice of volume: outside, largest inside, or the volumes of seed
// points (material points); gap closure (openings narrower than a size do not let the volume
// through); leak detection (a seed point's volume reaching the outside or another seed's,
// and the narrowest passage it went through); whether the input encloses anything at all.
#pragma once
#include <functional>
#include <vector>

#include "grid/adaptive_grid.h"
#include "grid/flood_fill.h"
#include "vdbwrap/errors.h"
#include "vdbwrap/params.h"
#include "vdbwrap/progress.h"
#include "vdbwrap/report.h"

namespace vdbwrap::grid {

struct VolumeRequest {
  VolumeChoice choice = VolumeChoice::Outside;
  std::vector<Vec3> seeds;     // local frame
  double gap_closure = 0;      // model units; 0: off
  Vec3 world_offset{0, 0, 0};  // local -> world, for messages
};

struct VolumeSelection {
  int32_t label = 0;           // cells of the chosen volume carry this value
  VolumeReport report;         // gap_closure and closedness filled in
  LeakReport leak;             // local frame
  std::vector<Coord> anchors;  // finest-level cells of the seed points: the pieces to keep
};

// Distance from a point (local frame) to the input, negative behind it (on the back of its
// nearest triangle, against the prepared input's orientation).
using DistanceToInput = std::function<double(const Vec3&)>;

// Labels the free cells and picks the volume. With gap closure, free cells whose centre is
// closer to the input than half the gap are first left out ("narrow"), the volume is flooded
// through the others, then grown back into the narrow cells that a ball of half the gap
// centred in it reaches (a morphological opening of the free space), and last into the narrow
// cells no other volume reaches first and on its own side of the input (so only openings are
// bridged: holes in a surface, gaps into spaces the volume does not hold). On a leak the
// selection comes back with leak.detected set and the chosen label 0.
// Throws Error(WrapFailed) when `inside` finds no enclosed volume, Error(InvalidArgument)
// for a seed point outside the grid or on the input.
VolumeSelection select_volume(AdaptiveGrid& grid, const VolumeRequest& request, const DistanceToInput& distance,
                              ProgressSink* progress);

}  // namespace vdbwrap::grid
