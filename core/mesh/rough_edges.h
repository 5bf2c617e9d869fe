// Sharp edges of a rough surface that are not sharp at the wrap's scale: a scan's noise folds
// its triangles by more than the feature angle at edges that line up into runs longer than a
// cell (the straight lines of a regular tessellation), while the surface seen over a cell on
// either hand is smooth; noise as coarse as the faces folds them every way, along edges
// longer than a cell too. A crease has a flat side on each hand however far one looks.
#pragma once
#include <cstdint>
#include <vector>

#include "mesh/feature_edges.h"
#include "vdbwrap/mesh.h"

namespace vdbwrap::mesh {

// What the sharp edges make of a surface before any is dropped as noise.
struct Roughness {
  std::vector<uint8_t> on_sharp;  // per point: a sharp edge ends there
  // Per triangle: every edge of it is sharp. Noise as coarse as a scan's faces folds them every
  // way, a tenth of them or more at all three edges; a part's faces, however small, are flat
  // or curved faces cut into triangles (a box's quads, a cylinder's strips) with a smooth edge
  // inside each.
  std::vector<uint8_t> sharp_all_round;
};
Roughness roughness(size_t points, const std::vector<Tri>& triangles, const std::vector<FeatureEdge>& edges);

// Whether the faces `faces` (at least a dozen) are a surface cut up by noise: a tenth or more
// of them sharp all round (per triangle, as Roughness::sharp_all_round). No crease or part
// there is one the wrap could follow.
bool cut_up_by_noise(const std::vector<uint8_t>& sharp_all_round, const std::vector<uint32_t>& faces);

// Drops each sharp edge (FeatureKind::Sharp with two faces) in rough surroundings that are
// cut up by noise where a side is not smooth, and each one shorter than `radius` whose two
// sides are smooth and continue each other over `radius`. The surroundings are the faces within `radius` of the edge's
// middle (grown from the edge's faces through shared corners); they are rough when over half
// of them have every corner on a sharp edge (a scan's noise makes sharp edges at almost every
// vertex; a finely tessellated part's creases, however close, leave most faces around them a
// smooth corner). Cut up by noise (cut_up_by_noise), the noise is as coarse as the faces: the
// sides' normals scatter, the folds run every way, longer than a cell or not, and no edge is
// a line the wrap could follow. A side is the surroundings on its own hand of the plane
// halving the angle between the edge's faces; it is smooth when its area-weighted normal is
// at least kCoherent of its area (its faces face one way: a small hole's wall, a pin or a fin
// curls round and keeps its rim's edges); the sides continue each other when those normals
// are less than `feature_angle_deg` apart. Faces as big as the radius leave fewer than
// kFewestFaces around: a CAD model's creases stay. `edges` keeps its order. Returns the
// number dropped.
size_t drop_edges_smooth_at_scale(const std::vector<Vec3>& points, const std::vector<Tri>& triangles,
                                  std::vector<FeatureEdge>& edges, const Roughness& rough, double radius,
                                  double feature_angle_deg);

}  // namespace vdbwrap::mesh
