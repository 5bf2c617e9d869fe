// Deviation fields: where a surface (a wrap) lies off a reference (its input), vertex by
// vertex, with per-triangle defect flags, and the files that show them in a viewer
// (ParaView for .vtp, most mesh viewers for .ply). Plain data in and out.
#pragma once
#include <cstdint>
#include <string>
#include <vector>

#include "vdbwrap/errors.h"
#include "vdbwrap/mesh.h"

namespace vdbwrap {

// Bits of DeviationField::triangle_flags and WrapResult::triangle_flags. The first seven are the
// stage 4 quality analysis' kinds (QualityThresholds says when each counts); an edge defect
// flags both triangles of the edge.
enum DefectFlag : uint8_t {
  kDefectSelfIntersecting = 1 << 0,  // in an intersecting pair, or degenerate
  kDefectSmallArea = 1 << 1,
  kDefectSliver = 1 << 2,  // smallest angle under the sliver angle
  kDefectShortEdge = 1 << 3,
  kDefectLongEdge = 1 << 4,
  kDefectNormalDeviation = 1 << 5,  // normal off the input's near it
  kDefectLostFeature = 1 << 6,      // a sharp-edge sample of the input near it was not reached
  kDefectHeldBack = 1 << 7,         // a corner is a node the fit kept off the input to stay valid
};

// Short names of the bits set in `flags`, lowest bit first ("sliver", "small_area", ...).
std::vector<std::string> defect_flag_names(uint8_t flags);

// What the sign of DeviationField::distance means. It comes from the reference's orientation
// at the nearest point (the angle-weighted pseudo-normal of the nearest face, edge or vertex).
enum class DistanceSign {
  Outside,    // the reference is closed and consistently oriented: + outside it, - inside
  FrontSide,  // open but consistently oriented: + on the side its triangles face (near a hole
              // the nearest triangle decides, which may not be what a closed version would say)
  Unsigned,   // inconsistent orientation or no reference triangles: every distance is >= 0
};

struct DeviationField {
  std::vector<double> distance;  // per surface vertex, model units, signed as `sign` says
  DistanceSign sign = DistanceSign::Unsigned;
  double diagonal = 0;   // of the reference's bounding box (for percentages)
  double max_abs = 0;    // largest |distance|
  Vec3 max_at{0, 0, 0};  // the vertex where it is
  uint32_t max_vertex = 0;
  double mean_abs = 0, p95_abs = 0;
  // Per surface triangle, DefectFlag bits; empty when the surface has no triangles.
  std::vector<uint8_t> triangle_flags;

  double percent_of_diagonal(double d) const { return diagonal > 0 ? 100.0 * d / diagonal : 0.0; }
};

// Distance of every vertex of `surface` to `reference` (nearest point on its triangles, in
// parallel). `defect_flags` (one byte per surface triangle, DefectFlag bits), when given, become
// the field's triangle_flags; without them the flags that need only the surface's geometry are
// computed (geometric_defect_flags). Throws Error(InvalidArgument) when defect_flags has the
// wrong size; a reference without triangles gives zero distances, Unsigned.
DeviationField measure_deviation(const Mesh& surface, const Mesh& reference,
                                 const std::vector<uint8_t>* defect_flags = nullptr);

// Flags from geometry alone (kDefectSelfIntersecting for degenerate triangles only,
// kDefectSmallArea, kDefectSliver) with the default QualityThresholds, sizes relative to
// `cell_size`; 0: the surface's median edge length stands for the cell size.
std::vector<uint8_t> geometric_defect_flags(const Mesh& surface, double cell_size = 0);

// Is this a file name write_deviation takes (".vtp" or ".ply", any case)?
bool is_deviation_path(const std::string& path);

// Writes the surface with the field: point data "distance" (model units) and
// "distance_percent_of_diagonal", cell data "part" (int32, the surface's part index) and
// "defects" (uint8, DefectFlag bits); in .vtp the part names are field data "part_names",
// in .ply the faces carry "part" and "defects" and the vertices the two distances.
// Throws Error(InvalidArgument) for another extension or a field that does not fit the
// surface, Error(OutputFailed) when the file cannot be written (written to PATH.tmp, renamed).
void write_deviation(const std::string& path, const Mesh& surface, const DeviationField& field);

}  // namespace vdbwrap
