// Stage 4, proximity refinement: where the wrap is still farther from the input than a
// fraction of a base cell, it is brought nearer by local edits. Two kinds of place:
// - nodes the validity loop held back at their lattice positions (at the corners of coarse
//   cells they can be over a base cell off): each is moved onto the input, or part of the way,
//   or, in a pleat where no move helps, merged into its neighbour nearest the input;
// - faces bridging a concave corner or a narrow gap, their corners on the input and their
//   interior off it: the far edges are split and the new node goes onto the input; where no
//   split comes nearer (a face across a groove, its corners held back under the far distance),
//   the face's farthest corner goes onto the input.
// Every edit keeps the surface valid (no fold, no intersection, exact predicates), makes no
// triangle under the target angle that was not there, keeps the input's sharp edges as near,
// and brings the patch nearer the input (its farthest point no farther, the integral of the
// distance over it smaller).
// Bridges over openings wider than a few cells stay bridges: a node moves at most `max_reach`.
#pragma once
#include <cstddef>
#include <map>
#include <string>

#include "post/remesh.h"

namespace vdbwrap::post {

struct ProximityRefinementParams {
  double far_distance = 0;          // model units: parts of the wrap farther from the input are worked on
  double max_reach = 0;             // model units: a split's new node moves at most this far onto the input
  double offset = 0;                // model units: nodes placed on the input sit this far off it
  double feature_tolerance = 0;     // model units: the input's sharp edges may come this much farther
  double min_angle_deg = 10;        // no new triangle under this angle, unless one as bad was there
  double max_normal_turn_deg = 80;  // no triangle turns more than this in one edit
  int rounds = 6;                   // passes over the far triangles left
  double budget = 0.005;            // at most this many attempts per triangle of the wrap (a bound on the time)
  bool float_coordinates = false;   // placed nodes rounded to float (binary STL output)
};

// The pipeline's parameters: far beyond 3/4 of a base cell, a reach of 1.5 base cells.
ProximityRefinementParams proximity_refinement_params(double base, double offset, double feature_tolerance,
                                                      bool float_coordinates);

struct ProximityRefinementStats {
  size_t far_before = 0, far_after = 0;  // triangles with a point farther than far_distance
  size_t pulls = 0, splits = 0, collapses = 0;
  std::map<std::string, size_t> refusals;  // edits refused, by the first check they failed
};

// Works on `surface` in place (new points and triangles appended; compacted when nodes were
// merged away).
ProximityRefinementStats refine_proximity(PostSurface& surface, const QualityReference& ref,
                                          const ProximityRefinementParams& params);

}  // namespace vdbwrap::post
