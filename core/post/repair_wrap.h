// Stage 4, last resort: the wrap leaves the pipeline valid or the job fails with a reason.
// When anything still intersects after the remeshing (the projection's validity loop ran out
// of rounds, a crossing the rebuilds could not remove) or the final validation finds an
// intersection, the intersection repair of the second paper (repair()) runs on the surface.
#pragma once
#include <string>

#include "post/remesh.h"
#include "vdbwrap/repair.h"

namespace vdbwrap::post {

struct WrapRepairOutcome {
  bool ran = false;
  size_t intersecting_before = 0, intersecting_after = 0;  // triangles
  std::string summary;                                     // regions found and fixed, or where the unfixed ones are
};

// Repairs the intersections of `surface` when it has any (moves within max_deviation, model
// units; no piece is deleted: a wrap loses no body). Per-point data follow their points; new
// points take the smallest cell size of their neighbours and are not locked.
WrapRepairOutcome repair_intersections(PostSurface& surface, double max_deviation, bool float_coordinates,
                                       ProgressSink* progress);

}  // namespace vdbwrap::post
