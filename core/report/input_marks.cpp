#include "report/input_marks.h"

#include <cmath>

#include "check/intersections.h"
#include "common/edge_triangles.h"
#include "common/exact_weld.h"
#include "common/vec.h"

namespace vdbwrap::report {
namespace {

// +1 when triangle t runs a -> b along the edge, -1 when b -> a.
int direction(const Tri& t, uint32_t a, uint32_t b) {
  for (int k = 0; k < 3; ++k)
    if (t[k] == a && t[(k + 1) % 3] == b) return 1;
  return -1;
}

}  // namespace

InputMarks mark_input(const Mesh& input, const ExactWeld& weld, double feature_angle_deg, bool find_intersections) {
  InputMarks marks;
  marks.flags.assign(input.triangles.size(), 0);
  std::vector<Tri> tris(input.triangles.size());
  std::vector<uint8_t> usable(tris.size(), 1);
  std::vector<Vec3> normals(tris.size(), Vec3{0, 0, 0});
  for (size_t t = 0; t < tris.size(); ++t) {
    for (int k = 0; k < 3; ++k) tris[t][k] = weld.remap[input.triangles[t][k]];
    const Tri& w = tris[t];
    if (w[0] == w[1] || w[1] == w[2] || w[0] == w[2] || check::triangle_is_degenerate(weld.unique, w)) {
      marks.flags[t] |= kInputDegenerate;
      usable[t] = w[0] != w[1] && w[1] != w[2] && w[0] != w[2];  // collinear ones still have edges
      continue;
    }
    normals[t] = normalized(area_vector(weld.unique[w[0]], weld.unique[w[1]], weld.unique[w[2]]));
  }
  const EdgeTriangles edges = edge_triangles(tris, &usable);
  const double cos_sharp = std::cos(feature_angle_deg * 3.14159265358979323846 / 180.0);
  for (size_t e = 0; e < edges.edges(); ++e) {
    const uint32_t a = uint32_t(edges.keys[e] >> 32), b = uint32_t(edges.keys[e] & 0xffffffffu);
    const uint32_t* around = edges.begin(e);
    const size_t n = edges.size(e);
    if (n == 1) {
      marks.flags[around[0]] |= kInputBorder;
      continue;
    }
    if (n > 2) {
      for (size_t i = 0; i < n; ++i) marks.flags[around[i]] |= kInputNonManifold;
      continue;
    }
    const uint32_t t0 = around[0], t1 = around[1];
    const int same = direction(tris[t0], a, b) == direction(tris[t1], a, b);
    if (same) marks.flags[t0] |= kInputMisoriented, marks.flags[t1] |= kInputMisoriented;
    if ((marks.flags[t0] | marks.flags[t1]) & kInputDegenerate) continue;
    // Across a misoriented edge one normal is turned over: the angle is the surface's, not the flip's.
    const double c = dot(normals[t0], normals[t1]) * (same ? -1.0 : 1.0);
    if (c < cos_sharp) marks.sharp_edges.push_back({weld.unique[a], weld.unique[b]});
  }
  if (find_intersections) {
    for (uint32_t t : check::intersecting_triangles(weld.unique, tris)) {
      if (!(marks.flags[t] & kInputDegenerate)) marks.flags[t] |= kInputIntersecting;
    }
    marks.intersections_searched = true;
  }
  return marks;
}

}  // namespace vdbwrap::report
