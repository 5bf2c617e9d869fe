#include "mesh/feature_edges.h"

#include <cmath>

#include "common/vec.h"

namespace vdbwrap::mesh {

std::vector<FeatureEdge> find_feature_edges(const std::vector<Vec3>& points, const std::vector<Tri>& triangles,
                                            const std::vector<Vec3>& normals, double feature_angle_deg,
                                            const EdgeTriangles* edges, const std::vector<ContactEdge>* contact) {
  EdgeTriangles made;
  const EdgeTriangles& edge_tris = edges ? *edges : (made = edge_triangles(triangles));
  const double cos_limit = std::cos(feature_angle_deg * M_PI / 180.0);
  std::vector<FeatureEdge> out;
  // Keys in increasing order: the edges come out sorted by (a, b).
  for (size_t i = 0; i < edge_tris.edges(); ++i) {
    const uint64_t key = edge_tris.keys[i];
    const uint32_t a = uint32_t(key >> 32), b = uint32_t(key & 0xffffffffu);
    const uint32_t* tris = edge_tris.begin(i);
    if (edge_tris.size(i) == 1) {
      out.push_back({a, b, FeatureKind::Boundary});
    } else if (edge_tris.size(i) > 2) {
      const ContactEdge kind = contact ? (*contact)[i] : ContactEdge::NonManifold;
      if (kind == ContactEdge::NonManifold) out.push_back({a, b, FeatureKind::NonManifold});
      if (kind == ContactEdge::Sharp) out.push_back({a, b, FeatureKind::Sharp});
    } else if (dot(normals[tris[0]], normals[tris[1]]) < cos_limit) {
      out.push_back({a, b, FeatureKind::Sharp});
    }
  }
  return out;
}

}  // namespace vdbwrap::mesh
