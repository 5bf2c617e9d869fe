// Parameters of a wrap: sizes, the volume to enclose, user controls, and the stage switches,
// with their defaults. validate() is the one check of their ranges (the CLI's, the server's).
#pragma once
#include <optional>
#include <string>
#include <vector>

#include "vdbwrap/errors.h"
#include "vdbwrap/mesh.h"

namespace vdbwrap {

// A length given either in model units or as a percentage of the input's
// bounding-box diagonal ("0.5" or "1%").
struct Length {
  double value = 1.0;
  bool percent_of_diagonal = true;

  double resolve(double diagonal) const { return percent_of_diagonal ? value * 0.01 * diagonal : value; }
  static Length parse(const std::string& text);  // throws Error(InvalidArgument)
  std::string to_string() const;
};

// Which volume the wrap encloses: the outside of the input (wrap around it), the largest
// volume the input encloses, or the volumes that contain the user's seed points
// (material points).
enum class VolumeChoice { Outside, Inside, SeedPoints };

// A region of space with its own target cell size (spec stage 2: box, cone, sphere,
// cylinder). Coordinates are in model units.
struct ControlVolume {
  enum class Shape { Box, Sphere, Cylinder, Cone };
  Shape shape = Shape::Box;
  Vec3 a{0, 0, 0};      // box: min corner; sphere: centre; cylinder, cone: start of the axis
  Vec3 b{0, 0, 0};      // box: max corner; cylinder, cone: end of the axis
  double radius = 0;    // sphere, cylinder; cone: radius at a
  double radius_b = 0;  // cone: radius at b
  Length size;          // cell size wanted inside it
  std::string name;     // for messages and the report

  // "box:X0,Y0,Z0,X1,Y1,Z1:SIZE", "sphere:X,Y,Z,R:SIZE", "cylinder:X0,Y0,Z0,X1,Y1,Z1,R:SIZE",
  // "cone:X0,Y0,Z0,X1,Y1,Z1,R0,R1:SIZE". Throws Error(InvalidArgument).
  static ControlVolume parse(const std::string& text);
  std::string to_string() const;
};

// A target cell size for the cells an input part (STL solid, OBJ group) passes through.
struct PartSize {
  std::string part;
  Length size;
  static PartSize parse(const std::string& text);  // "NAME=SIZE"
};

// Parts kept apart: parts in different groups must not be fused by the wrap. One group
// alone ("hot,cold") means every part of it against every other; "a,b:c,d" is a,b against c,d.
struct ContactRule {
  std::vector<std::vector<std::string>> groups;
  static ContactRule parse(const std::string& text);
  std::string to_string() const;
};

// "outside", "inside", or seed points "X,Y,Z" (several separated by ';').
// Throws Error(InvalidArgument).
void parse_volume_choice(const std::string& text, VolumeChoice& choice, std::vector<Vec3>& seed_points);
std::string volume_choice_to_string(VolumeChoice choice, const std::vector<Vec3>& seed_points);

// Stage 4 quality analysis: when a triangle or an edge of the wrap counts as a defect (spec:
// self-intersecting triangles, small-area triangles, edges of uncharacteristic length, poor
// approximation of the input). Sizes are relative to the local cell size of the voxel stage at
// the triangle (the edge of the smallest lattice face at its nodes).
struct QualityThresholds {
  double small_area = 0.01;          // area under this x (local cell size)^2
  double sliver_angle_deg = 5;       // smallest angle under this (needles and caps)
  double short_edge = 0.1;           // edge shorter than this x the local cell size
  double long_edge = 4;              // edge longer than this x the local cell size (the larger at its ends)
  double normal_deviation_deg = 45;  // normal off the input's near the triangle by more than this
  double near_input = 0.25;          // normals are judged where the input is within this x the local cell size
  double feature_tolerance = 0.1;    // sharp-edge samples farther than this x the finest cell are lost ...
  double feature_reach = 2;          // ... unless farther than this x the local cell size (out of the wrap's reach)
};

struct WrapParams {
  Length base_size{1.0, true};    // edge of a level-0 cell
  int levels = 1;                 // most 2x2x2 refinements below the base size
  double feature_angle_deg = 30;  // dihedral angle (between normals) that makes an edge sharp
  VolumeChoice volume = VolumeChoice::Outside;
  std::vector<Vec3> seed_points;  // VolumeChoice::SeedPoints: one or more material points
  int threads = 0;                // 0: all cores

  // User controls of the voxel stage (spec stage 2).
  std::optional<Length> gap_closure;            // openings narrower than this do not let the volume through
  std::vector<ControlVolume> control_volumes;   // finer cells inside these regions
  std::vector<PartSize> part_sizes;             // finer cells where these parts pass
  std::vector<ContactRule> contact_prevention;  // parts kept apart by refining between them
  std::optional<Length> contact_floor;          // smallest cell contact prevention may use (default: finest / 8)

  // Refinement criteria of a cell the input passes through (spec stage 2).
  int refine_max_triangles = 64;         // more triangles than this in a cell: refine
  double refine_normal_spread_deg = 20;  // normals spread more than this: refine
  bool refine_at_features = true;        // sharp, boundary or intersection edges: refine
  // Parts of the input thinner than half a cell across two directions (rods, narrow bars, small
  // closed pieces) are refined up to this many levels below `levels`, so the wrap has nodes enough
  // across them: on a rod a tenth of a cell thick, a cell-sized lattice leaves only slivers.
  // 0 turns it off. Closed pieces only (which side is solid is known there); the outside
  // volume only (a finer grid could open a passage into the inside or a seed point's volume).
  int thin_part_levels = 2;
  // Refine a cell the input passes through when a point of its boundary lies more than a base
  // cell from its triangles: held-back nodes then stay within a base cell of the input.
  bool refine_far_cells = false;
  // Where the projection left the wrap more than a base cell from the input (nodes held back at
  // corners of coarse cells, faces bridging a concave crease), refine the cells around the far
  // parts to the finest level and fit again. It costs stage 2 and the projection again, on the
  // models where it applies (see docs/cli.md).
  bool refine_where_far = true;

  // Projection (spec stage 3).
  double weld_tolerance = 1e-7;   // fraction of the diagonal under which vertices merge
  double surface_offset = 0.005;  // nodes stop this fraction of the finest cell off the input
  // Where the volume lies on both sides of an input surface (open sheets, scans with holes), a node
  // that would make the wrap invalid first moves farther off the input on its own side (up to
  // 64 x the offset) before it is pulled back toward the lattice.
  bool two_sided_sheets = true;
  int presmooth_iterations = 16;  // smoothing of the voxel surface before projection (untangling)
  // Rounds of the projection's validity loop (offending nodes pulled back toward the lattice);
  // intersections still left afterwards go to stage 4's remeshing and intersection repair.
  int validity_rounds = 400;

  // Feature snapping (spec stage 3): wrap edges traced along the feature curves and moved
  // onto them, convex and concave alike, with the corners.
  bool snap_features = true;
  double corner_angle_deg = 30;  // a feature curve turning more than this at a point has a corner there

  // Coarsening (stage 4): nodes merged on flat parts while every new triangle stays within
  // this fraction of the base size of the input; 0 turns it off.
  double coarsen_tolerance = 0.02;

  // Stage 4: bad regions (slivers, tiny triangles, very poor normals, intersections) rebuilt
  // from the input (constrained Delaunay on nearly flat patches) or by ear clipping.
  bool remesh = true;
  // Stage 4: triangles with an angle under 10 degrees left after the rebuilds are removed by edge
  // flips, collapses, tangential moves and rail splits checked against the input.
  bool remove_slivers = true;
  // Stage 4, before the sliver removal: where the wrap is still over 3/4 of a base cell from the
  // input (nodes held back at coarse cells, faces bridging concave corners), nodes are moved onto
  // the input and far edges split, each edit checked against the input and the surface.
  bool proximity_refinement = true;
  QualityThresholds quality;  // what counts as a defect (fixed; listed in the report)

  // The output will be stored in single precision (binary STL): coordinates are rounded to
  // float during the validity loop, so the validity checked is that of what is written.
  bool float_coordinates = false;

  bool compute_distances = true;  // sample output-to-input distances for the report
};

// Throws Error(InvalidArgument) naming the first parameter out of its range.
void validate(const WrapParams& params);

}  // namespace vdbwrap
