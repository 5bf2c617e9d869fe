#include "mesh/feature_edges.h"

#include <cmath>

#include "common/vec.h"

namespace vdbwrap::mesh {
namespace {

// Triangles around edge (a, b) whose third corners point the same way from it lie on one another:
// a face given twice with different triangulations (one body tessellated twice, a face exported
// twice). Counted once, an edge with two such sheets is an ordinary edge between two faces.
// Returns the two sheets' first triangles, or false when the edge has more than two.
bool two_sheets(const std::vector<Vec3>& points, const std::vector<Tri>& triangles, uint32_t a, uint32_t b,
                const uint32_t* tris, size_t count, uint32_t sheet[2]) {
  const Vec3 pa = points[a], along = normalized(points[b] - pa);
  auto side = [&](uint32_t t) {
    const Tri& tri = triangles[t];
    const uint32_t c = tri[0] != a && tri[0] != b ? tri[0] : tri[1] != a && tri[1] != b ? tri[1] : tri[2];
    const Vec3 d = points[c] - pa;
    return normalized(d - along * dot(d, along));
  };
  // Third corners this close in direction (a thousandth of a radian) are on one sheet.
  constexpr double kSameSide = 1 - 5e-7;
  Vec3 dir[2];
  size_t sheets = 0;
  for (size_t k = 0; k < count; ++k) {
    const Vec3 d = side(tris[k]);
    bool known = false;
    for (size_t s = 0; s < sheets && !known; ++s) known = dot(d, dir[s]) > kSameSide;
    if (known) continue;
    if (sheets == 2) return false;
    dir[sheets] = d, sheet[sheets] = tris[k], ++sheets;
  }
  return sheets == 2;
}

}  // namespace

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
      uint32_t sheet[2];
      if (kind == ContactEdge::NonManifold && two_sheets(points, triangles, a, b, tris, edge_tris.size(i), sheet)) {
        if (dot(normals[sheet[0]], normals[sheet[1]]) < cos_limit) out.push_back({a, b, FeatureKind::Sharp});
        continue;
      }
      if (kind == ContactEdge::NonManifold) out.push_back({a, b, FeatureKind::NonManifold});
      if (kind == ContactEdge::Sharp) out.push_back({a, b, FeatureKind::Sharp});
    } else if (dot(normals[tris[0]], normals[tris[1]]) < cos_limit) {
      out.push_back({a, b, FeatureKind::Sharp});
    }
  }
  return out;
}

}  // namespace vdbwrap::mesh
