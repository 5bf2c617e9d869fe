// Stage 4, local remeshing of bad regions (spec: "Rebuild every bad region, two ways"): the
// triangles the quality analysis flags (by the trigger kinds) are grouped into small
// disc-shaped regions, each grown by a ring of triangles; a region is rebuilt on the input
// (fill_on_substrate) or, when that fails or is refused, by ear clipping; a rebuild is kept
// only when the surface stays closed, manifold and free of intersections, the region's
// defects drop, and neither the distance to the input nor the input's sharp edges get worse.
#pragma once
#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include "post/quality.h"
#include "prep/prepare.h"

namespace vdbwrap::post {

// The surface through the post-processing, in output coordinates, with its per-point data.
struct PostSurface {
  std::vector<Vec3> points;
  std::vector<Tri> triangles;
  std::vector<double> cell_size;                             // local cell size of the voxel stage
  std::vector<uint8_t> locked;                               // on a feature curve: stays where it is
  std::vector<std::pair<uint32_t, uint32_t>> feature_edges;  // edges along the feature curves: stay edges
};

// The triangles f with alive[f] != 0 and the points they use, with their per-point data;
// remap[v] is v's index in the result (UINT32_MAX: no live triangle uses it). The feature
// edges are left to the caller, which knows which of its own still hold.
PostSurface live_part(const PostSurface& s, const std::vector<uint8_t>& alive, std::vector<uint32_t>& remap);

struct RemeshParams {
  // Triangles with any of these flags are bad: slivers, tiny triangles, poor normals,
  // triangles next to lost sharp edges, intersections (measured on the corpus: a rebuild on
  // the input removes many of them). Edge lengths follow from the cell sizes and the coarsening: a
  // rebuild of a small region rarely changes them, so they are counted, not triggers.
  uint8_t triggers = kSelfIntersecting | kSmallArea | kSliver | kNormalDeviation | kLostFeature;
  double trigger_normal_deviation_deg =
      45;                            // poor normals that trigger: beyond this (may be stricter than the analysis)
  double max_deviation = 0;          // model units: new triangles stay this close to the input (or as close as the old)
  double offset = 0;                 // model units: new nodes on the input sit this far off it
  double flat_angle_deg = 15;        // the substrate's creases: normals more than this apart
  int rounds = 3;                    // regions grown by 1, 2, then 1 ring again
  size_t max_region_triangles = 32;  // bad triangles gathered into one region
  bool float_coordinates = false;    // new nodes rounded to float (binary STL output)
};

struct RemeshStats {
  size_t regions = 0, on_input = 0, ear_clipping = 0, restored = 0;
  std::map<std::string, size_t> refusals;
};

// Rebuilds the bad regions of `surface` in place (compacted afterwards). flags: per triangle,
// from analyse_quality on this surface. `input` is the prepared input the reference's index
// was built on (its triangles give the substrate).
RemeshStats remesh_bad_regions(PostSurface& surface, const std::vector<uint8_t>& flags, const QualityReference& ref,
                               const prep::PreparedInput& input, const RemeshParams& params, ProgressSink* progress);

}  // namespace vdbwrap::post
