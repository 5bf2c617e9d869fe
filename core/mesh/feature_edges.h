// The feature edges of a triangle mesh: sharp, boundary and non-manifold edges.
#pragma once
#include <cstdint>
#include <vector>

#include "common/edge_triangles.h"
#include "mesh/contact_faces.h"
#include "vdbwrap/mesh.h"

namespace vdbwrap::mesh {

enum class FeatureKind : uint8_t { Sharp = 1, Boundary = 2, NonManifold = 3 };

struct FeatureEdge {
  uint32_t a, b;  // vertex indices
  FeatureKind kind;
};

// Sharp (dihedral angle over feature_angle_deg), boundary and non-manifold edges, sorted by (a, b).
// Triangles lying on one another at an edge (a face given twice, triangulated differently) count
// once: an edge whose triangles form two such sheets is sharp or no feature, as between two faces.
// `contact` (optional, per edge of `edges`): what faces where solids touch make of the edges with
// more than two faces (see contact_faces.h).
std::vector<FeatureEdge> find_feature_edges(const std::vector<Vec3>& points, const std::vector<Tri>& triangles,
                                            const std::vector<Vec3>& normals, double feature_angle_deg,
                                            const EdgeTriangles* edges = nullptr,
                                            const std::vector<ContactEdge>* contact = nullptr);

}  // namespace vdbwrap::mesh
