// Stage 4, the two ways the spec rebuilds a bad region of the wrap, as pure functions of a
// small problem: the region's boundary contour (and the nodes inside it that must stay), the
// surface it replaces and, for the first way, the input triangles under it (the substrate).
//  1. fill_on_substrate: the substrate split into nearly flat patches; the region projected
//     to its plane and triangulated there (CGAL constrained Delaunay) with the contour, the
//     creases between patches and the kept feature edges as constraints, interior nodes at the
//     characteristic spacing; every new node mapped back onto the patch under it.
//  2. fill_by_ear_clipping: without the input; ear clipping of the contour that respects the
//     characteristic edge length (wide corners get new nodes, their quadrilaterals split in two).
// Neither touches the mesh: the caller checks the fill against it and keeps it or not.
#pragma once
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "common/vec2.h"
#include "vdbwrap/mesh.h"

namespace vdbwrap::post {

// Node numbering of a problem and its fill: [0, contour) contour nodes, then the fixed nodes,
// then the fill's new nodes.
struct RegionProblem {
  std::vector<Vec3> contour;  // the boundary loop, in the region's orientation (counter-clockwise seen from outside)
  std::vector<Vec3> fixed;    // nodes inside the region that must stay (on feature curves)
  std::vector<std::pair<uint32_t, uint32_t>> fixed_edges;  // edges among contour and fixed nodes that must stay
  std::vector<Vec3> old_points;  // the surface replaced (its own numbering), for heights and sides
  std::vector<Tri> old_triangles;
  Vec3 normal{0, 0, 1};  // unit, area-weighted normal of the replaced surface (outward)
  double target = 0;     // characteristic edge length
};

// The input triangles under the region, in the same frame as the problem.
struct Substrate {
  std::vector<Vec3> points;
  std::vector<Tri> triangles;  // oriented consistently where the input is
  double offset = 0;           // new nodes stay this far off the substrate, on the wrap's side
  double flat_angle_deg = 15;  // triangles whose normals differ more than this meet at a crease
};

struct RegionFill {
  bool ok = false;
  std::string why;               // when not ok
  std::vector<Vec3> new_points;  // nodes contour + fixed + i
  std::vector<Tri> triangles;    // oriented like the region
};

RegionFill fill_on_substrate(const RegionProblem& problem, const Substrate& substrate);
RegionFill fill_by_ear_clipping(const RegionProblem& problem);

// A frame for the region's plane: origin at the contour's centroid, axes e1, e2, normal n.
struct PlaneFrame {
  Vec3 origin, e1, e2, n;
  Vec2 to_2d(const Vec3& p) const;
  Vec3 to_3d(const Vec2& q, double height) const;
  double height(const Vec3& p) const;
};
PlaneFrame plane_frame(const RegionProblem& problem);

// Twice the signed area of a 2D polygon (positive: counter-clockwise).
double signed_area2(const std::vector<Vec2>& polygon);
// True when no two non-adjacent edges of the closed 2D polygon touch.
bool is_simple(const std::vector<Vec2>& polygon);

}  // namespace vdbwrap::post
