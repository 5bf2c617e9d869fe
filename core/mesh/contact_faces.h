// Faces where two solids touch (voxel art, a union exported with its contact faces): given once
// by each solid, coincident, turned apart. Wrapping the outside, they lie inside the material,
// and the non-manifold edges they make are judged by the faces around them.
#pragma once
#include <cstdint>
#include <vector>

#include "common/edge_triangles.h"
#include "vdbwrap/mesh.h"

namespace vdbwrap::mesh {

// What the contact faces make of an edge with more than two faces.
enum class ContactEdge : uint8_t {
  NonManifold,  // no contact faces, or a junction the wrap sees as one: stays a non-manifold feature
  Inside,       // every face at it is a contact face: inside the material, no feature
  Flat,         // two faces left, flat, the contact faces behind them: no feature
  Sharp,        // two faces left that meet at an angle (a concave step of voxels): a sharp edge
};

struct ContactFaces {
  std::vector<ContactEdge> edges;  // per edge of the listing
  // Per triangle: a contact face whose every edge with more than two faces was judged (not
  // NonManifold), in a patch of such faces bounded by those edges alone: inside the
  // material, and the outside wrap does without it.
  std::vector<uint8_t> inside;
};

// A contact face is one of a pair of triangles of one part (`triangle_part`
// may be empty: one part) meeting at a non-manifold edge in one half-plane from it (coincident
// fins) and running it opposite ways (facing apart), each triangulated its own way; or one of
// `twin` (per triangle), the kept copy of a face given twice, turned. An edge is judged only when
// the contact faces lie in the material, behind the two faces left: a face given twice as a
// double-sided sheet that sticks out of a solid keeps its edge a feature. The triangles must be
// in the input's orientation, which says where the material is (the pieces of such a mesh between
// non-manifold edges are small, and orienting them guesses).
ContactFaces contact_faces(const std::vector<Vec3>& points, const std::vector<Tri>& triangles,
                           const std::vector<int32_t>& triangle_part, const EdgeTriangles& edges,
                           const std::vector<uint8_t>& twin, double feature_angle_deg);

}  // namespace vdbwrap::mesh
