// Stage 1: pre-processing of the input (spec: weld, orient, drop degenerate triangles,
// find feature curves). Works in a local frame centred on the bounding box for precision.
#pragma once
#include <array>
#include <cstdint>
#include <vector>

#include "check/intersections.h"
#include "common/edge_triangles.h"
#include "common/exact_weld.h"
#include "mesh/feature_edges.h"
#include "mesh/orient.h"
#include "vdbwrap/mesh.h"
#include "vdbwrap/progress.h"
#include "vdbwrap/report.h"

namespace vdbwrap::prep {

// The prepared input's feature edges (vertex indices into PreparedInput::mesh.points).
using mesh::FeatureEdge;
using mesh::FeatureKind;

// A segment where two input triangles pierce each other (an assembly's junction line).
struct IntersectionSegment {
  Vec3 a, b;
  uint32_t tri_a, tri_b;
};

struct PreparedInput {
  Mesh mesh;             // welded, degenerate-free, oriented, in the local frame
  Vec3 origin{0, 0, 0};  // world = local + origin
  double diagonal = 0;
  std::vector<Vec3> normals;  // unit normal per triangle
  // Per triangle, its closed piece (an index into closed_piece_size), whose normals point out
  // of the material, or mesh::kOpenPiece; the thin-part refinement reads which side is solid
  // and which pieces are small. Empty when unknown.
  std::vector<uint32_t> closed_piece;
  std::vector<float> closed_piece_size;  // per closed piece, the longest side of its bounding box
  std::vector<FeatureEdge> feature_edges;
  // Per triangle, whether every edge of it was sharp before noise edges were dropped
  // (mesh/rough_edges.h): the thin-part refinement takes the folds of a surface cut up by
  // noise for no parts. Empty when unknown.
  std::vector<uint8_t> sharp_all_round;
  std::vector<IntersectionSegment> intersections;
  // Pairs of mesh triangles that intersect, sorted: the pipeline's only search for them. The
  // segments above come from these, and so do the report's counts on the input (see
  // input_intersections).
  std::vector<check::TrianglePair> intersecting_pairs;
  // Input triangle t became mesh triangle input_to_mesh[t]; an exact duplicate points at the
  // copy that was kept; UINT32_MAX for a triangle dropped as degenerate or inside the material.
  std::vector<uint32_t> input_to_mesh;
  size_t dropped_degenerate = 0, dropped_duplicate = 0, welded_vertices = 0, flipped_triangles = 0;
  size_t dropped_inside = 0;  // faces where solids touch, inside the material (contact_faces.h)
};

// Intersection counts of the input mesh (MeshDiagnostics::intersecting_pairs / _triangles)
// from the pairs found on the prepared mesh, so the input need not be searched a second
// time. Copies of a triangle dropped as duplicates count as they do in the input: a copy
// intersects the kept triangle and everything the kept triangle intersects. Differences
// from a search on the raw input are limited to what prepare changes beyond duplicates:
// nearly collinear triangles it drops, vertices it welds within the weld tolerance.
struct InputIntersections {
  size_t pairs = 0, triangles = 0;
};
InputIntersections input_intersections(const std::vector<check::TrianglePair>& mesh_pairs,
                                       const std::vector<uint32_t>& input_to_mesh, size_t mesh_triangles);

// The whole stage. Throws Error(InvalidInput) when nothing usable is left. `input_weld`, when
// given, is the exact weld of input.points (the input's diagnosis makes one): the welding
// starts from its distinct points instead of all of them, with the same result.
// What prepare needs of the wrap's parameters.
struct PrepareParams {
  double weld_tolerance = 1e-7;   // fraction of the diagonal under which vertices merge
  double feature_angle_deg = 30;  // dihedral angle (between normals) that makes an edge sharp
  // A face given twice with opposite orientations in one part lies between two solids that
  // touch (voxel art: every voxel its own cube). Wrapping the outside, such a face is inside
  // the material, and the edges it makes non-manifold are judged by the faces around it.
  bool contact_faces_inside = false;
  bool parts_kept_apart = false;  // contact prevention: a contact between two parts stays a feature
};
PreparedInput prepare(const Mesh& input, const PrepareParams& params, ProgressSink* progress,
                      const ExactWeld* input_weld = nullptr);

}  // namespace vdbwrap::prep
