// Stage 3, after tracing: feature-curve points the wrap still misses get a node of their own.
// The spec's concave rule ("an edge outside the input is split and the new node put on the
// feature curve"), applied to every curve: where the traced chain could not follow a crease
// (the wrap bridges a concave corner, a groove, or cuts a curved edge's chord), the wrap edge
// nearest the missed point is split and its new node moved onto the curve.
#pragma once
#include <vector>

#include "fit/features.h"
#include "fit/fit_surface.h"
#include "mesh/surface_index.h"

namespace vdbwrap::fit {

struct FeatureInsertParams {
  double spacing = 0;    // curve samples this far apart
  double tolerance = 0;  // a sample nearer the wrap than this is kept
  double max_move = 0;   // a node goes at most this far (the wrap's own scale: about a base cell)
  // Where the wrap passes over half of max_move from a point and no edge within max_move takes
  // it, the edges beyond, out to this, are tried: a narrow groove oblique to the lattice takes
  // no cell near its crease, and the wrap bridges it more than a base cell above. (0: max_move.)
  double far_reach = 0;
  double offset = 0;          // new nodes stop this far off the curve, on the wrap's side
  double min_area2 = 0;       // doubled area below which a triangle is degenerate
  double min_separation = 0;  // a new node this close to another is refused
  double max_deviation = 0;   // changed triangles stay this close to the input, or no farther than before
  bool float_coordinates = false;
};

struct FeatureInsertStats {
  size_t samples_missed = 0;  // samples farther than the tolerance before the pass
  size_t nodes_inserted = 0;  // edge splits
  size_t nodes_moved = 0;     // existing nodes moved onto a curve instead
  size_t refused = 0;         // points left because every change would have made the wrap invalid or left the input
  size_t unreachable = 0;     // points behind the input from the wrap (buried intersection lines)
};

// Works on a valid fitted surface (output frame; `origin` takes the local curves there) and
// keeps it valid: every change is checked against its neighbourhood and undone when it makes
// a degenerate or intersecting triangle, flips one, or touches the input. New and moved nodes
// are marked snapped, and their edges along the curve are added to the feature edges.
FeatureInsertStats insert_feature_nodes(FittedSurface& surface, const std::vector<FeatureCurve>& curves,
                                        const mesh::SurfaceIndex& input, const Vec3& origin,
                                        const FeatureInsertParams& params);

}  // namespace vdbwrap::fit
