// Sharp edges between strips too narrow for the wrap to show: a thin tube tessellated with few
// sides (a sculpt's hair strand, a wire, a low-poly finger) has a sharp edge between every two
// sides, and its sides are narrower than a cell. The wrap makes such a tube a round blob; its
// edges would become parallel feature curves a fraction of a cell apart, with nodes snapped and
// inserted on each, folding the blob into slivers. Where such tubes cross (a lattice's struts),
// the lines they cross along are no creases either.
#pragma once
#include <cstddef>
#include <cstdint>
#include <vector>

#include "mesh/feature_edges.h"
#include "vdbwrap/mesh.h"

namespace vdbwrap::mesh {

// Which faces are narrow strips. A face is a smooth region (triangles joined across edges that
// are no feature edge), and it is narrow when every point of it lies within `narrowest` / 2 of
// its rim (its feature edges), sampled at its triangles' centres and the middles of its inner
// edges. `closed_piece` (optional, per triangle: mesh::kOpenPiece or a closed piece): faces of
// closed pieces are narrow under `narrowest_closed` instead, as the thin-part refinement gives
// thin closed pieces finer cells, where their edges show. Only the faces beside a sharp or a
// non-manifold edge and those of the triangles in `also_judged` are judged; the others count
// as not narrow.
struct NarrowFaces {
  std::vector<uint8_t> triangles;  // per triangle, whether its face is narrow
  // Per feature edge, whether it is sharp or non-manifold (struts welded along an edge) with
  // narrow faces on every side.
  std::vector<uint8_t> between_narrow;
};
NarrowFaces narrow_faces(const std::vector<Vec3>& points, const std::vector<Tri>& triangles,
                         const std::vector<FeatureEdge>& edges, double narrowest,
                         const std::vector<uint32_t>* closed_piece = nullptr, double narrowest_closed = 0,
                         const std::vector<uint32_t>& also_judged = {});

// Drops the sharp and non-manifold edges with narrow faces on every side (`narrow` judged on
// these `edges`): a chamfer or a thin wall's top is narrow on one side only and keeps its
// edges. `edges` keeps its order. Returns the number of edges dropped.
size_t drop_narrow_strip_edges(std::vector<FeatureEdge>& edges, const NarrowFaces& narrow);

}  // namespace vdbwrap::mesh
