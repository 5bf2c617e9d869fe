// Sharp edges of a rough surface that are not sharp at the wrap's scale: a scan's noise folds
// its triangles by more than the feature angle at edges that line up into runs longer than a
// cell (the straight lines of a regular tessellation), while the surface seen over a cell on
// either hand is smooth. A crease has a flat side on each hand however far one looks.
#pragma once
#include <cstdint>
#include <vector>

#include "mesh/feature_edges.h"
#include "vdbwrap/mesh.h"

namespace vdbwrap::mesh {

// Per point, whether a sharp edge of `edges` ends there.
std::vector<uint8_t> on_sharp_edge(size_t points, const std::vector<FeatureEdge>& edges);

// Drops each sharp edge (FeatureKind::Sharp with two faces, shorter than `radius`) in rough
// surroundings whose two sides are smooth and continue each other over `radius`. The
// surroundings are the faces within `radius` of the edge's middle (grown from the edge's faces
// through shared corners); they are rough when over half of them have every corner `on_sharp`
// (a scan's noise makes sharp edges at almost every vertex; a finely tessellated part's
// creases, however close, leave most faces around them a smooth corner). A side is the
// surroundings on its own hand of the plane halving the angle between the edge's faces; it is
// smooth when its area-weighted normal is at least kCoherent of its area (its faces face one
// way: a small hole's wall, a pin or a fin curls round and keeps its rim's edges); the sides
// continue each other when those normals are less than `feature_angle_deg` apart. Faces as
// big as the radius leave fewer than kFewestFaces around: a CAD model's creases stay. `edges`
// keeps its order. Returns the number dropped.
size_t drop_edges_smooth_at_scale(const std::vector<Vec3>& points, const std::vector<Tri>& triangles,
                                  std::vector<FeatureEdge>& edges, const std::vector<uint8_t>& on_sharp, double radius,
                                  double feature_angle_deg);

}  // namespace vdbwrap::mesh
