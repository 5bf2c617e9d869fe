// Feature lines of a part placed more than once a hair apart (a body exported twice, an
// assembly's part copied onto itself, one CAD body tessellated twice). Each sharp edge then
// comes as a bundle of parallel lines closer than a sliver is wide, with the lines where the
// copies' faces cross beside them; a curve on each folds the wrap into slivers between them.
// The wrap goes round the union of the copies, whose edge is the bundle's outermost line (a
// copy's edge, or the line where one copy's face crosses another's): the others are inside.
#pragma once
#include <cstdint>
#include <vector>

#include "mesh/feature_edges.h"
#include "vdbwrap/mesh.h"

namespace vdbwrap::mesh {

// A feature line with the side away from the material: the sum of the two faces' outward
// normals (both at a sharp edge, the two crossing faces at an intersection line), unit length.
// Zero where that side is unknown (a face of an open piece) or ill-defined (faces nearly
// opposite); such a line is never in a bundle.
struct OrientedLine {
  Vec3 a, b, out;
};

// Per line, whether it lies inside a bundle: at its middle and at a quarter from each end,
// another line runs beside it (the point's foot on that line within its ends) within `width`,
// parallel to it and facing the same way (both within `angle_deg`), and farther out along
// `out` (on a tie, the lower index is the farther),
// so each bundle keeps its outermost line. `cell` is the side of the grid the lines are
// looked up in (a few `width`s or more; a base cell suits); it widens where the lines are long
// enough to pass through millions of cells.
std::vector<uint8_t> inner_lines_of_bundles(const std::vector<OrientedLine>& lines, double width, double cell,
                                            double angle_deg);

// The side away from the material of each sharp edge (FeatureKind::Sharp) of `edges`, as
// OrientedLine::out: zero for the other kinds, for an edge with a face of an open piece
// (`closed_piece`, per triangle, as PreparedInput's; empty: all unknown) and for a knife edge.
std::vector<Vec3> sharp_edges_outward(const std::vector<Tri>& triangles, const std::vector<Vec3>& normals,
                                      const std::vector<uint32_t>& closed_piece, const std::vector<FeatureEdge>& edges);

// The same of an intersection line between triangles a and b.
Vec3 crossing_outward(uint32_t a, uint32_t b, const std::vector<Vec3>& normals,
                      const std::vector<uint32_t>& closed_piece);

}  // namespace vdbwrap::mesh
