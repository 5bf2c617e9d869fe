// Sharp edges that are noise, not creases: a scan's rough surface turns every few triangles by
// more than the feature angle, and its sharp edges form runs a few triangles long in every
// direction. Runs shorter than the wrap can follow are dropped before the feature curves are
// built from them.
#pragma once
#include <cstdint>
#include <vector>

#include "mesh/feature_edges.h"
#include "vdbwrap/mesh.h"

namespace vdbwrap::mesh {

// Drops the sharp edges (FeatureKind::Sharp; boundary and non-manifold edges stay) of every run
// shorter than `shortest` in a cell (2 x `shortest` wide) holding more than two cell lengths of
// such short runs: a small part's edges are short too, but few. A run is a path of sharp edges
// that goes on at each vertex along the straightest other sharp edge there, while that turns
// by less than `corner_angle_deg`: a crease runs on past the noise edges that meet it, and
// ends at a part's corner. `edges` keeps its order. Returns the number of sharp edges dropped.
size_t drop_short_sharp_runs(const std::vector<Vec3>& points, std::vector<FeatureEdge>& edges, double shortest,
                             double corner_angle_deg);

// The same test for lines given by their ends, segment i from ends[2i] to ends[2i + 1], ends
// within `weld` of each other one point: the self-intersection lines of rough sheets that cross
// (an unmerged scan's overlapping views) meander in short runs as densely as a rough
// surface's sharp edges, while parts that cross meet along long runs. `fold` (optional, per
// segment): whether the segment is where a surface folded over crosses itself next to itself
// (fold_crossings.h); a short run of such segments only is noise however sparse (a rough
// surface's folds are scattered; a small part that crosses another meets it between faces far
// apart on the surface). Per segment, whether it is noise.
std::vector<uint8_t> short_line_runs(const std::vector<Vec3>& ends, double shortest, double corner_angle_deg,
                                     double weld, const std::vector<uint8_t>* fold = nullptr);

}  // namespace vdbwrap::mesh
