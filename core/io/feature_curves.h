// The input's feature curves (the polylines the wrap snaps to, WrapResult::feature_curves) as
// a file: OBJ lines or OpenFOAM's edge mesh (.eMesh, what snappyHexMesh and
// surfaceFeatureExtract read), for checking them or meshing with the same features.
#pragma once
#include <string>
#include <vector>

#include "vdbwrap/mesh.h"

namespace vdbwrap::io {

enum class CurveFormat { Unknown, Obj, EMesh };

// From the extension, case-insensitive: .obj, .eMesh.
CurveFormat curve_format_from_extension(const std::string& path);

// Points shared by curves (corners, a closed curve's ends) are written once, so the edges form
// one connected graph; every consecutive pair of a curve's points is an edge.
// OBJ: `v` lines, then one `l` line per curve. eMesh: FoamFile header (class
// featureEdgeMesh), the points as a pointField, then the edges as an edgeList.
std::string feature_curves_to_text(const std::vector<std::vector<Vec3>>& curves, CurveFormat format);

// Writes the file (beside, then renamed). Throws Error(InvalidArgument) for another extension,
// Error(OutputFailed) when it cannot be written.
void write_feature_curves(const std::string& path, const std::vector<std::vector<Vec3>>& curves);

}  // namespace vdbwrap::io
