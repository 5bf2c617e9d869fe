// Cracks: CAD exports whose faces share no vertices (featuretype.STL) have faces that touch
// along their seams, a corner of one face on (or a rounding error, 1e-16, past) a corner or
// the border edge of the next. Exact predicates call such a touch an intersection; the
// surface is fine and only its connectivity is missing. Stitching welds the corner to the
// corner or splits the border edge at it: no point is made, none moves by more than the
// tolerance, and the two faces then share the vertex and the edge pieces between them.
#pragma once
#include <cstdint>
#include <unordered_set>
#include <vector>

#include "check/intersections.h"
#include "repair/regions.h"
#include "vdbwrap/mesh.h"

namespace vdbwrap::local_repair {

// A border edge (u, w) and the vertices lying strictly inside it, ordered from u to w.
struct EdgeSplit {
  uint32_t u = 0, w = 0;
  std::vector<uint32_t> at;
};

// For every intersecting pair, the border vertices of one triangle (a crack, not a corner
// resting on a face: gluing that would pinch two sheets at a point) within `tol` of a border
// vertex of the other (`welds`: the vertex -> the one it becomes, the lower id stays) or of
// the inside of a border edge (one live triangle) of the other (`splits`, one per edge,
// sorted by (u, w)). Vertices in `forbidden` are left out.
struct Stitches {
  std::vector<std::pair<uint32_t, uint32_t>> welds;
  std::vector<EdgeSplit> splits;
};
Stitches find_stitches(const std::vector<Vec3>& points, const std::vector<Tri>& triangles, const VertexFaces& faces,
                       const std::vector<check::TrianglePair>& pairs, double tol,
                       const std::unordered_set<uint32_t>& forbidden);

// Edges among `triangles` (live ones listed) used by more than two triangles, or by two that
// run the same way (inconsistent orientation): what a stitch must not create. Edge keys.
std::vector<std::pair<uint32_t, uint32_t>> bad_edges(const std::vector<Tri>& all,
                                                     const std::vector<uint32_t>& triangles, const VertexFaces& faces);

}  // namespace vdbwrap::local_repair
