// Local repair of self-intersections in a triangle surface (spec: "Intersection repair",
// the second paper): the mesh is changed only where triangles intersect, first by moving
// vertices and triangles (part 1), then by removing and refilling regions (part 2).
// Usable on any input (CAD tessellations, scans, the wrap's own output).
#pragma once
#include <cstddef>
#include <map>
#include <string>
#include <vector>

#include "vdbwrap/errors.h"
#include "vdbwrap/mesh.h"
#include "vdbwrap/params.h"  // Length
#include "vdbwrap/progress.h"
#include "vdbwrap/report.h"  // MeshDiagnostics, DistanceStats

namespace vdbwrap {

struct RepairParams {
  // Part 1: local operations (vertex shift, triangle shift).
  int local_iterations = 15;
  double alpha = 0.25;       // vertex shift: share of |x b| kept between the new point and b
  double beta = 0.1;         // vertex shift: alpha |x b| must stay under beta L (L: longest region edge)
  double delta = 0.5;        // triangle shift: eps_move = delta * accuracy ...
  double gamma = 0.001;      // ... capped at gamma * L
  double area_ratio = 0.95;  // eps_S: min/max area of the modified triangles must be at least this
  double accuracy = 0;       // model accuracy eps; 0: 0.05 x the shortest edge (floored at 1e-16)

  // Part 2: remove and refill.
  int refill_iterations = 3;
  double refill_area_ratio = 0.5;  // min/max area of the removed region and its refill (the paper gives none)
  bool fair = true;                // fair the refill (bi-Laplacian, Botsch & Sorkine) after refining it

  // No vertex ends further than this from where it was, and no refill further than this
  // from the surface it replaces (model units or percent of the diagonal).
  Length max_deviation{0.5, true};

  // Afterwards, delete pieces that the repair left disconnected or still intersecting when
  // they have at most this many triangles and at most this fraction of the total area.
  bool remove_small_pieces = true;
  bool unite_bodies = true;  // last stage: closed bodies still crossing are united (exact union)
  int small_piece_triangles = 16;
  double small_piece_area = 1e-3;

  // Coordinates will be stored in single precision (binary STL): every moved or new point is
  // rounded to float, so the checks hold for what is written.
  bool float_coordinates = false;

  int threads = 0;                // 0: all cores
  bool compute_distances = true;  // Metro-style deviation of the result from the input
};

// One region of intersecting triangles (a connected set; regions share no vertex).
struct RepairRegion {
  size_t triangles = 0, pairs = 0;
  Vec3 center{0, 0, 0}, bbox_min{0, 0, 0}, bbox_max{0, 0, 0};
};

struct RepairReport {
  RepairParams params;
  double accuracy = 0;       // the model accuracy used (given or from the shortest edge)
  double max_deviation = 0;  // the bound in model units
  double diagonal = 0;       // of the input's bounding box

  size_t regions_found = 0;    // regions of the input
  size_t fixed_by_local = 0;   // of those, free of intersections after part 1 (and stitching)
  size_t fixed_by_refill = 0;  // ... after part 2 (or when tiny leftovers were removed)
  size_t fixed_by_union = 0;   // ... by uniting the closed bodies that cross there (bodies_united)
  size_t left_unfixed = 0;
  std::vector<RepairRegion> unfixed;  // the regions of intersecting triangles left in the output

  size_t local_iterations_run = 0, vertex_shifts = 0, triangle_shifts = 0;
  size_t untangles = 0;  // needle untangling moves kept (repair/untangle.h)
  size_t refill_iterations_run = 0, refills = 0, refill_failures = 0;
  // Regions refilled after their triangles near the intersections were bisected (edges down to
  // a third of --max-deviation; geometry unchanged), and the triangles that added.
  size_t regions_refined = 0, refined_triangles_added = 0;
  // Crack stitches before part 1: corners welded to the corner they touched, and corners
  // inserted into the border edge they lay on (nothing moves by more than 1e-6 of the diagonal).
  size_t cracks_stitched = 0;
  // Closed bodies still crossing after part 2, united (exact union: buried surface and faces
  // lying on another body's face dropped, nothing else moved).
  size_t bodies_united = 0;
  size_t pieces_removed = 0, piece_triangles_removed = 0;
  // Why operations and refills were refused (reason -> how often): what stood in the way.
  std::map<std::string, size_t> refusals;

  MeshDiagnostics before, after;
  // Sampled (Metro-style) distances from the triangles the repair changed (moved, new or
  // deleted) to the whole other surface; everywhere else the two are the same surface.
  DistanceStats output_to_input, input_to_output;
  double deviation = 0;  // two-sided max distance, as a fraction of the input's diagonal
  std::vector<StageStats> stages;
  double total_seconds = 0;

  bool all_fixed() const { return left_unfixed == 0 && unfixed.empty(); }
};

struct RepairResult {
  Mesh mesh;  // welded (exactly equal points merged); parts kept
  RepairReport report;
};

// Repairs the intersections of `input`. Throws Error: InvalidArgument (parameters),
// InvalidInput (no triangles, non-finite points), Cancelled. Intersections that cannot be
// repaired within the limits are left and listed in the report (not an error).
RepairResult repair(const Mesh& input, const RepairParams& params, ProgressSink* progress = nullptr);

std::string to_json(const RepairReport& report, int indent = 2);

}  // namespace vdbwrap
