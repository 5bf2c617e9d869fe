// The rims of open pieces too small for the wrap to show: a raw scan's floating fragments.
#pragma once
#include <vector>

#include "mesh/feature_edges.h"
#include "vdbwrap/mesh.h"

namespace vdbwrap::mesh {

// Drops the boundary edges (FeatureKind::Boundary) of every connected set of them whose box
// has a diagonal under `smallest`: a fragment a cell or two across is wrapped as a blob, on
// both sides, and snapping nodes to its rim only folds the blob into slivers. A small hole in
// a larger surface goes too: the wrap bridges it. `edges` keeps its order. Returns the number
// of edges dropped.
size_t drop_small_rims(const std::vector<Vec3>& points, std::vector<FeatureEdge>& edges, double smallest);

}  // namespace vdbwrap::mesh
