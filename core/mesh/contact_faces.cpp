#include "mesh/contact_faces.h"

#include <cmath>

#include "common/vec.h"

namespace vdbwrap::mesh {

namespace {

constexpr size_t kMostAtAnEdge = 16;

// Unit direction from edge (a, b) towards the triangle's third corner, square to the edge. Around
// an edge with many triangles, the angles between fins say which are flat, folded or coincident
// whatever the triangles' orientations.
inline Vec3 edge_fin(const std::vector<Vec3>& points, const Tri& t, uint32_t a, uint32_t b) {
  const uint32_t c = t[0] != a && t[0] != b ? t[0] : t[1] != a && t[1] != b ? t[1] : t[2];
  const Vec3 e = points[b] - points[a], d = points[c] - points[a];
  return normalized(d - e * (dot(d, e) / dot(e, e)));
}

// Contact faces: the twins, and coincident pairs facing apart at non-manifold edges.
std::vector<uint8_t> paired_faces(const std::vector<Vec3>& points, const std::vector<Tri>& triangles,
                                  const std::vector<int32_t>& triangle_part, const EdgeTriangles& edges,
                                  const std::vector<uint8_t>& twin) {
  std::vector<uint8_t> contact = twin;
  // Coincident within half a degree: the same plane in float coordinates.
  const double coincident = std::cos(0.5 * M_PI / 180.0);
  auto part = [&](uint32_t t) { return triangle_part.empty() ? 0 : triangle_part[t]; };
  for (size_t i = 0; i < edges.edges(); ++i) {
    const size_t n = edges.size(i);
    // Solids touching in faces put three or four at an edge; hundreds (a fan of copies) are
    // no contact, and pairing them would take their square.
    if (n < 3 || n > kMostAtAnEdge) continue;
    const uint32_t a = uint32_t(edges.keys[i] >> 32), b = uint32_t(edges.keys[i] & 0xffffffffu);
    const uint32_t* tris = edges.begin(i);
    for (size_t k = 0; k < n; ++k)
      for (size_t l = k + 1; l < n; ++l) {
        const uint32_t s = tris[k], t = tris[l];
        // In one half-plane, facing apart means running the edge opposite ways.
        if (part(s) != part(t) || (directed_side(triangles[s], a, b) >= 0) == (directed_side(triangles[t], a, b) >= 0))
          continue;
        if (dot(edge_fin(points, triangles[s], a, b), edge_fin(points, triangles[t], a, b)) > coincident)
          contact[s] = contact[t] = 1;
      }
  }
  return contact;
}

// Angle of `f` from `f0` about the unit edge direction `e`, in [0, 2 pi).
double turn(const Vec3& f0, const Vec3& f, const Vec3& e) {
  const double angle = std::atan2(dot(cross(f0, f), e), dot(f0, f));
  return angle < 0 ? angle + 2 * M_PI : angle;
}

}  // namespace

ContactFaces contact_faces(const std::vector<Vec3>& points, const std::vector<Tri>& triangles,
                           const std::vector<int32_t>& triangle_part, const EdgeTriangles& edges,
                           const std::vector<uint8_t>& twin, double feature_angle_deg) {
  const std::vector<uint8_t> contact = paired_faces(points, triangles, triangle_part, edges, twin);
  const double cos_limit = std::cos(feature_angle_deg * M_PI / 180.0);
  ContactFaces result;
  std::vector<ContactEdge>& out = result.edges;
  out.assign(edges.edges(), ContactEdge::NonManifold);
  for (size_t i = 0; i < edges.edges(); ++i) {
    const size_t n = edges.size(i);
    if (n < 3 || n > kMostAtAnEdge) continue;  // (a face's checks below then stay short too)
    const uint32_t a = uint32_t(edges.keys[i] >> 32), b = uint32_t(edges.keys[i] & 0xffffffffu);
    const uint32_t* tris = edges.begin(i);
    uint32_t outer[2];
    size_t outers = 0, inners = 0;
    for (size_t k = 0; k < n; ++k) {
      if (contact[tris[k]]) {
        ++inners;
        continue;
      }
      if (outers < 2) outer[outers] = tris[k];
      ++outers;
    }
    if (inners == 0) continue;
    if (outers == 0) {
      out[i] = ContactEdge::Inside;
      continue;
    }
    if (outers != 2) continue;
    // The material wedge: from the first face's fin, turning towards its back, to the second's.
    // Both faces must have their backs in it, and every contact face must lie in it.
    const Vec3 e = normalized(points[b] - points[a]);
    const Vec3 f0 = edge_fin(points, triangles[outer[0]], a, b), f1 = edge_fin(points, triangles[outer[1]], a, b);
    const Vec3 back0 = -1.0 * area_vector(points[triangles[outer[0]][0]], points[triangles[outer[0]][1]],
                                          points[triangles[outer[0]][2]]);
    const Vec3 back1 = -1.0 * area_vector(points[triangles[outer[1]][0]], points[triangles[outer[1]][1]],
                                          points[triangles[outer[1]][2]]);
    const bool forward = dot(back0, cross(e, f0)) > 0;  // the wedge turns the positive way from f0
    const double end = turn(f0, f1, e);
    if ((dot(back1, cross(e, f1)) > 0) == forward) continue;  // the second face's back points out of it
    bool behind = true;
    for (size_t k = 0; k < n && behind; ++k) {
      if (!contact[tris[k]]) continue;
      const double at = turn(f0, edge_fin(points, triangles[tris[k]], a, b), e);
      behind = forward ? at > 0 && at < end : at > end;
    }
    if (behind) out[i] = dot(f0, f1) > -cos_limit ? ContactEdge::Sharp : ContactEdge::Flat;
  }
  // Inside: judged at every non-manifold edge it has, and it has one (a double-sided sheet on
  // its own has none).
  result.inside.assign(triangles.size(), 0);
  for (size_t t = 0; t < triangles.size(); ++t) {
    if (!contact[t]) continue;
    int judged = 0;
    bool unjudged = false;
    for (int k = 0; k < 3; ++k) {
      const size_t i = edges.find(edge_key(triangles[t][k], triangles[t][(k + 1) % 3]));
      if (edges.size(i) < 3) continue;
      if (out[i] == ContactEdge::NonManifold) unjudged = true;
      ++judged;
    }
    result.inside[t] = judged > 0 && !unjudged;
  }
  // A face paired at one edge can reach past its partner (a large box's top under a small
  // one's bottom, split its own way): only whole patches of them go, whose every side off a
  // judged non-manifold edge is shared with another face of the patch. Dropping them leaves no
  // hole.
  std::vector<uint32_t> check;
  for (size_t t = 0; t < triangles.size(); ++t)
    if (result.inside[t]) check.push_back(uint32_t(t));
  while (!check.empty()) {  // a face that stays puts its neighbours in the patch back to check
    const uint32_t t = check.back();
    check.pop_back();
    if (!result.inside[t]) continue;
    // Its neighbours across sides of two faces and edges inside the material (every face
    // there a contact face): all of them must go with it, or a rim would be left.
    size_t side[3];
    bool whole = true;
    for (int k = 0; k < 3; ++k) {
      side[k] = edges.find(edge_key(triangles[t][k], triangles[t][(k + 1) % 3]));
      if (edges.size(side[k]) < 2) whole = false;
    }
    auto ties = [&](size_t i) { return edges.size(i) == 2 || out[i] == ContactEdge::Inside; };
    for (size_t i : side)
      if (ties(i))
        for (const uint32_t* o = edges.begin(i); o != edges.begin(i) + edges.size(i); ++o)
          whole = whole && result.inside[*o];
    if (whole) continue;
    result.inside[t] = 0;
    for (size_t i : side)
      if (ties(i))
        for (const uint32_t* o = edges.begin(i); o != edges.begin(i) + edges.size(i); ++o)
          if (result.inside[*o]) check.push_back(*o);
  }
  return result;
}

}  // namespace vdbwrap::mesh
