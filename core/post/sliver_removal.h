// Stage 4, sliver removal: after the rebuilds of bad regions, triangles with a small angle
// (needles with a short edge, caps with an angle near 180 degrees) are still common where the
// lattice's nodes were projected close together. Local operations remove them, in the manner
// of isotropic remeshing (Botsch and Kobbelt): edge flips where the surface is nearly flat,
// collapses of short edges (the kept node placed on the input), and tangential moves of the
// nodes left around slivers (re-projected onto the input). Strips between two close rows of
// nodes (close feature curves, thin walls' tops) get more nodes: their rails are split; those
// too narrow for any triangle across (strip_width) lose their rungs, the two rows becoming one.
// Every operation is checked before it is applied: the smallest angle around it grows, no
// triangle folds or turns far, the surface stays within the deviation bound of the input (or
// no farther than before), the link condition holds, snapped feature nodes stay where they
// are, and no new triangle meets another (exact predicates). The surface stays closed,
// manifold and oriented.
#pragma once
#include <cstddef>
#include <map>
#include <string>

#include "post/remesh.h"

namespace vdbwrap::post {

struct SliverRemovalParams {
  double target_angle_deg = 10;  // triangles with a smaller angle are worked on
  double max_deviation = 0;      // model units: new triangles stay this close to the input (or as close as before)
  double offset = 0;             // model units: nodes placed on the input sit this far off it
  double flat_angle_deg = 30;    // an edge is flipped only where its triangles' normals are this close
  double feature_tolerance = 0;  // model units: a snapped node goes only when the feature line moves less than this
  // Model units: a sliver whose corners are all on feature curves lies in a strip between two
  // curves; where the strip is narrower than this, the surface and the input's sharp edges may
  // move this far (the two curves become one). No triangle across a strip narrower than
  // tan(target angle) / 2 of the node spacing reaches the target angle.
  double strip_width = 0;
  double max_normal_turn_deg = 60;  // no well-shaped triangle turns more than this in one operation
  double min_gain_deg = 0.5;        // an operation must raise the smallest angle around it by this much
  int rounds = 6;                   // passes over the slivers left
  int rail_passes = 2;              // the slivers' rails split at their middle, then rounds again
  bool float_coordinates = false;   // moved nodes rounded to float (binary STL output)
};

// The parameters with the pipeline's bounds (model units; `finest`: the finest cell, the
// nodes' least spacing), the rest at their defaults.
SliverRemovalParams sliver_removal_params(double max_deviation, double offset, double finest, bool float_coordinates);

struct SliverRemovalStats {
  size_t slivers_before = 0, slivers_after = 0;  // triangles under the target angle
  size_t flips = 0, collapses = 0, moves = 0;
  size_t splits = 0;                       // rails split in strips of needles
  std::map<std::string, size_t> refusals;  // operations refused, by the first check they failed
};

// Works on `surface` in place (compacted afterwards when anything changed). The reference
// gives the input (nearest points, in its local frame: local = output - origin).
SliverRemovalStats remove_slivers(PostSurface& surface, const QualityReference& ref, const SliverRemovalParams& params);

}  // namespace vdbwrap::post
