// Measures of any mesh: its defects, and sampled distances to another mesh.
#pragma once
#include "vdbwrap/mesh.h"
#include "vdbwrap/report.h"

namespace vdbwrap {

// Diagnostics of any mesh, welded exactly (exactly equal coordinates) first.
MeshDiagnostics diagnose(const Mesh& mesh, bool find_intersections = true);

// Metro-style one-sided distance from `from` to `to`. Mean and p95 over points spread by area
// at a spacing of diagonal / samples_per_diagonal, held between 20 thousand and a hundred
// thousand points; the max over those, every vertex of a triangle, and a fine lattice over the
// triangles of the farthest samples.
DistanceStats sampled_distance(const Mesh& from, const Mesh& to, double samples_per_diagonal = 1000);

// Distance from points sampled every spacing_fraction x diagonal along the input's sharp
// edges (normals more than angle_deg apart) to `surface`: how well it keeps the edges. Over
// two hundred thousand such points (a rough scan's noise), every k-th of them.
DistanceStats sharp_edge_distance(const Mesh& input, const Mesh& surface, double angle_deg = 40,
                                  double spacing_fraction = 0.001);

}  // namespace vdbwrap
