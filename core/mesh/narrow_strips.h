// Sharp edges between strips too narrow for the wrap to show: a thin tube tessellated with few
// sides (a sculpt's hair strand, a wire, a low-poly finger) has a sharp edge between every two
// sides, and its sides are narrower than a cell. The wrap makes such a tube a round blob; its
// edges would become parallel feature curves a fraction of a cell apart, with nodes snapped and
// inserted on each, folding the blob into slivers.
#pragma once
#include <cstddef>
#include <vector>

#include "mesh/feature_edges.h"
#include "vdbwrap/mesh.h"

namespace vdbwrap::mesh {

// Drops the sharp edges (FeatureKind::Sharp) whose faces on both sides are narrow: a face is a
// smooth region (triangles joined across edges that are no feature edge), and it is narrow when
// every point of it lies within `narrowest` / 2 of its rim (its feature edges), sampled at its
// triangles' centres and the middles of its inner edges. A chamfer or a thin wall's top is
// narrow on one side only and keeps its edges. `edges` keeps its order. Returns the number of
// sharp edges dropped. `closed_piece` (optional, per triangle: mesh::kOpenPiece or a closed
// piece): faces of closed pieces are narrow under `narrowest_closed` instead, as the thin-part
// refinement gives thin closed pieces finer cells, where their edges show.
size_t drop_narrow_strip_edges(const std::vector<Vec3>& points, const std::vector<Tri>& triangles,
                               std::vector<FeatureEdge>& edges, double narrowest,
                               const std::vector<uint32_t>* closed_piece = nullptr, double narrowest_closed = 0);

}  // namespace vdbwrap::mesh
