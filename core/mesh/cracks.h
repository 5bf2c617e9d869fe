// Cracks: a surface whose faces do not share their corners (a triangle soup written with
// rounded coordinates, CAD faces tessellated each on its own) is cut along every crack into
// rims that run side by side a hair apart. Each rim would be a feature curve, and the wrap,
// pinned to thousands of them, would fold into slivers along every edge of the input; the
// surface goes on across a crack, so a crack is no rim. Where the faces on its two sides meet
// at an angle (a crease tessellated face by face), one of the two rims stays as the crease.
#pragma once
#include <array>
#include <cstdint>
#include <vector>

#include "mesh/feature_edges.h"
#include "vdbwrap/mesh.h"

namespace vdbwrap::mesh {

// Per side of a crack: its face, the other side's face, and the gap between the two sides at the
// side's middle.
struct CrackAcross {
  uint32_t face = UINT32_MAX, other = UINT32_MAX;
  double width = 0;
};

enum class CrackSide : uint8_t {
  None = 0,    // no side of a crack
  Goes = 1,    // a side of a crack across a smooth surface, or the other side of a crease
  Crease = 2,  // the side of a crease that stays: a sharp edge, no rim
};

// Per edge of `edges`, whether it is a side of a crack: a boundary edge (FeatureKind::Boundary)
// with, at its middle, a quarter from each end and two widths from each end, another boundary
// edge beside it (the point's foot on that edge within its ends) within `width`, parallel to it
// within `angle_deg`. The other side is the first such edge found at the middle (a hairline
// crack's is plain). With `nearest_partner` (gaps up to a cell wide), the other side must lie in
// another connected piece of the surface (within a piece, edges side by side are a jagged rim's
// zigzag), `width` is at most a quarter of the boundary edges' mean length, and the other side
// is the nearest such edge at the middle or, as near, one across a crease (a soup's neighbours
// of either side lie within the width too; a face written twice as near as the other side).
// The faces of the two sides (`normals`, per triangle; the other face turned like this one, as
// the pieces of a soup are turned each on its own) make a crease when they turn from each other
// by more than `feature_angle_deg` and, across a hairline crack, both faces' doubt: a face whose
// corners lie off by the rounding (what nine in ten sides' nearest side at their middle stay
// within) may turn about its edge by twice that over its height above the edge (a CAD fan's
// needles, rounded, turn any way). Of a crease, the side whose normal leads in the largest
// component of the normals' difference stays (the pair turned so that their sum leads
// positive). `across`, when given: per edge of a crack, the faces across it and its width (for
// other edges, UINT32_MAX faces). Edges `decided` already (not None) are not looked at again;
// they stay the other side of others. `cell` sizes the lookup grid, as for SegmentGrid
// (narrowed to twice the edges' mean length).
std::vector<CrackSide> crack_sides(const std::vector<Vec3>& points, const std::vector<Tri>& triangles,
                                   const std::vector<Vec3>& normals, const std::vector<FeatureEdge>& edges,
                                   double width, double cell, double angle_deg, double feature_angle_deg,
                                   bool nearest_partner = false, std::vector<CrackAcross>* across = nullptr,
                                   const std::vector<CrackSide>* decided = nullptr);

// Per line (`lines`: where faces cross), whether it runs along a crack: at the same points, a
// side of a crack (`side`, per edge of `edges`, not None) lies beside it within `width`,
// parallel within `angle_deg`. Neighbours across a crack whose corners were rounded apart
// cross each other along it: no crease of the surface (a crease's stays as the side kept).
// `cell` sizes the lookup grid.
std::vector<uint8_t> crossings_along_cracks(const std::vector<Vec3>& points, const std::vector<FeatureEdge>& edges,
                                            const std::vector<CrackSide>& side,
                                            const std::vector<std::array<Vec3, 2>>& lines, double width, double cell,
                                            double angle_deg);

// Whether two triangles that cross (`a`, `b`: corners) cross only at a corner they share up to
// `width`, but not exactly, the crossing (`from`-`to`) within `width` of it: the faces around a
// soup's corner, their corners rounded apart, overlap there by a hair; no line of the surface
// (faces of one vertex crossing next to it are a fold).
bool crossing_at_shared_corner(const std::array<Vec3, 3>& a, const std::array<Vec3, 3>& b, const Vec3& from,
                               const Vec3& to, double width);

// The creases kept from one side (edges marked CrackSide::Crease, `across`: its face and the
// other side's, as crack_sides gives them) lie on one face's rim, which stands a gap off the
// other face, behind it or beyond: the wrap could not reach a concave one, nor hug a convex
// one, without touching the other face. Each such edge goes where the planes of the two faces
// meet: its ends' nearest points on both planes, new points appended to `points` (no triangle
// uses them), where they lie within `width` and four of the crack's widths of the ends, and
// both faces stand ten widths clear of their longest edge (a needle's plane is a guess).
void move_creases_to_plane_meet(std::vector<Vec3>& points, const std::vector<Tri>& triangles,
                                const std::vector<Vec3>& normals, const std::vector<CrackSide>& side,
                                const std::vector<CrackAcross>& across, double width, std::vector<FeatureEdge>& edges);

// The creases kept from one side (edges marked CrackSide::Crease) run on from triangle to
// triangle of a soup, whose corners do not meet: ends within `width` of each other are made one
// vertex (the first of them in edge order), so that the edges join into curves and do not end
// in a corner at every triangle.
void join_crease_ends(const std::vector<Vec3>& points, const std::vector<CrackSide>& side, double width,
                      std::vector<FeatureEdge>& edges);

}  // namespace vdbwrap::mesh
