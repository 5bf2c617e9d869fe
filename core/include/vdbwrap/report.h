// What a wrap found and did: the report's plain data, and its JSON form.
#pragma once
#include <cstddef>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include "vdbwrap/mesh.h"
#include "vdbwrap/params.h"

namespace vdbwrap {

struct StageStats {
  std::string name;
  double seconds = 0;
  double peak_memory_mb = 0;  // peak resident memory while the stage ran
};

// Distances from samples on one surface to another, in model units and as fractions of
// the reference diagonal.
struct DistanceStats {
  size_t samples = 0;
  double mean = 0, p95 = 0, max = 0;
  double diagonal = 0;
  Vec3 max_at{0, 0, 0};  // the sample (on the surface measured from) farthest from the other
};

struct MeshDiagnostics {
  size_t vertices = 0, triangles = 0, parts = 0, components = 0;
  size_t border_edges = 0, nonmanifold_edges = 0, nonmanifold_vertices = 0;
  size_t misoriented_edges = 0, degenerate_triangles = 0;
  size_t intersecting_triangles = 0, intersecting_pairs = 0;
  bool closed = false, manifold = false, oriented = false, outward = false;
  bool self_intersecting = false;
  double area = 0, volume = 0, diagonal = 0;
  Vec3 bbox_min{0, 0, 0}, bbox_max{0, 0, 0};

  // closed, manifold, consistently and outward oriented, no self-intersections
  bool valid_closed_surface() const {
    return closed && manifold && oriented && outward && !self_intersecting && degenerate_triangles == 0;
  }
};

struct FeatureStats {
  size_t sharp_edges = 0, boundary_edges = 0, nonmanifold_edges = 0, intersection_segments = 0;
  size_t inside_faces = 0;     // faces where solids touch (voxel art), inside the material: left out
  size_t small_rim_edges = 0;  // of the boundary edges, those of rims under 3 base cells across: not used
  // Of the intersection segments, those in runs too short to follow (rough sheets crossing): not used.
  size_t noise_intersection_segments = 0;
  size_t noise_sharp_edges = 0;  // of the sharp edges, those in runs too short to follow (a rough surface): not used
  // Of the sharp and non-manifold edges, those between faces narrower than the finest cell on
  // every side (a thin tube's sides, struts welded along an edge): not used.
  size_t narrow_strip_edges = 0;
  // Of the intersection segments, those where two such narrow faces cross (a lattice's thin
  // struts): not used.
  size_t narrow_strip_intersection_segments = 0;
  // Of the sharp edges and the intersection segments, those beside a parallel line farther out
  // closer than a sliver is wide (a part placed twice a hair apart): not used.
  size_t duplicate_sharp_edges = 0, duplicate_intersection_segments = 0;
  // Of the boundary edges, those with another beside them a hair apart, parallel (the two sides
  // of a crack between faces that do not share their corners): not used.
  size_t crack_edges = 0;
  // Of the intersection segments, those along a crack (neighbours across it, their corners
  // rounded apart, cross there): not used.
  size_t crack_intersection_segments = 0;
  // The hairline cracks' width: nine in ten of their sides lie at most this far (model units)
  // from the other side, at the middle (0: no crack).
  double crack_gap = 0;
  size_t curves = 0, corners = 0, curves_captured = 0, corners_captured = 0, nodes_snapped = 0;
  // Curve points the traced chains missed (sampled every half finest cell), and what was done
  // about them: nodes inserted on the curve by edge splits, nodes moved onto it, points left
  // because every change was refused, points behind the input (buried intersection lines).
  size_t points_missed = 0, nodes_inserted = 0, nodes_moved = 0, inserts_refused = 0, points_unreachable = 0;
};

// What the flood fill found: does the input enclose anything at this cell size?
struct VolumeReport {
  size_t free_volumes = 0;       // connected volumes of cells the input does not touch
  size_t enclosed_volumes = 0;   // of those, the ones that do not reach the outside and hold a whole base cell
  double largest_enclosed = 0;   // model units cubed (cells, so approximate)
  bool encloses_volume = false;  // the input, as given, is closed at this cell size
  double chosen_volume = 0;      // model units cubed, before the surface is fitted
  double gap_closure = 0;        // model units; 0: off
};

// A seed point's volume reached the outside or another seed point's volume.
struct LeakReport {
  bool detected = false;
  std::string description;  // e.g. "seed point 1 reaches the outside"
  Vec3 location{0, 0, 0};   // the narrowest passage on the widest way through
  double width = 0;         // about twice the passage's clearance from the input
  std::vector<Vec3> path;   // from the seed point out, through the passage
};

// Where contact prevention could not keep parts apart above its floor size.
struct ContactReport {
  size_t rules = 0;
  double floor = 0;                        // model units
  size_t unresolved_cells = 0;             // cells at the floor still holding parts that must stay apart
  std::vector<Vec3> unresolved_locations;  // one per cluster (at most 100)
  size_t separate_bodies = 0;              // connected pieces of the wrap
};

// Defects of one surface, by kind (QualityThresholds says when each counts).
struct QualityCounts {
  size_t triangles = 0, edges = 0;
  size_t self_intersecting = 0;            // triangles in an intersecting pair, or degenerate
  size_t small_area = 0;                   // triangles
  size_t slivers = 0;                      // triangles
  size_t short_edges = 0, long_edges = 0;  // edges
  size_t normal_deviation = 0;             // triangles
  size_t feature_samples = 0;       // points along the input's sharp edges (feature angle), every 0.1 % of the diagonal
  size_t lost_feature_samples = 0;  // of those, farther from the surface than the feature tolerance (within reach)
  size_t unreachable_feature_samples =
      0;                     // farther than the reach: inside other bodies, in slots narrower than the cells
  double min_angle_deg = 0;  // smallest angle of any triangle
  double max_normal_deviation_deg = 0;
};

// Stage 4's sliver removal (after the rebuilds): triangles under its target angle before and
// after, the operations it applied, and why the others were refused (the first check failed).
struct SliverRemovalReport {
  bool ran = false;
  double target_angle_deg = 0;
  size_t slivers_before = 0, slivers_after = 0;  // triangles
  size_t flips = 0, collapses = 0, moves = 0;
  size_t splits = 0;  // rails split in strips of needles
  std::map<std::string, size_t> refusals;
};

// Stage 4's proximity refinement (before the sliver removal): triangles with a point farther
// than its distance from the input before and after, the edits applied, and why others were refused.
struct ProximityRefinementReport {
  bool ran = false;
  double far_distance = 0;  // model units
  size_t far_triangles_before = 0, far_triangles_after = 0;
  size_t pulls = 0, splits = 0, collapses = 0;  // nodes moved onto the input; edges split; nodes merged away
  std::map<std::string, size_t> refusals;
};

// Stage 4: the quality analysis before and after the post-processing (remeshing of bad regions
// and, when anything still intersects, the intersection repair), and what each step did.
struct QualityReport {
  QualityCounts before, after;
  size_t regions = 0;                      // bad regions tried
  size_t remeshed_on_input = 0;            // rebuilt with the input as substrate (constrained Delaunay)
  size_t remeshed_by_ear_clipping = 0;     // rebuilt by the fallback
  size_t restored = 0;                     // rebuilt, but the rebuild was refused: put back as it was
  std::map<std::string, size_t> refusals;  // why rebuilds were refused
  ProximityRefinementReport proximity_refinement;
  SliverRemovalReport sliver_removal;
  // Intersection repair (spec, second paper) on the wrap when anything still intersected.
  size_t repair_runs = 0;
  size_t intersecting_before_repair = 0, intersecting_after_repair = 0;  // triangles
  std::string repair_summary;                                            // what the repair did, when it ran
};

// Where the chosen volume lies on both sides of an input surface (the outside got in through
// openings of the input, or the input is an open sheet), the wrap follows both of its faces.
struct TwoSidedReport {
  double area_fraction = 0;  // of the input's area, wrapped from both sides
  size_t nodes = 0;          // wrap nodes projected onto such places
  size_t nodes_raised = 0;   // of those, moved farther off the input to stay valid (two_sided_sheets)
  size_t openings = 0;       // boundary loops of the input
  Vec3 largest_opening_centre{0, 0, 0};
  double largest_opening_width = 0;  // model units: about the widest ball that passes through it
  double suggested_gap_closure = 0;  // model units, closing every opening; 0: none (open sheets)
};

struct WrapReport {
  MeshDiagnostics input;
  FeatureStats features;
  WrapParams params;
  double base_size = 0, finest_size = 0, diagonal = 0;
  std::vector<size_t> cells_per_level;                        // cells the input passes through, per level
  std::vector<std::pair<std::string, double>> control_sizes;  // control volumes / part sizes and their cell size
  VolumeReport volumes;
  LeakReport leak;
  ContactReport contact;
  size_t manifold_fixes = 0;   // cells taken out of the volume to keep it manifold
  size_t thin_part_cells = 0;  // cells refined below --levels for a part thinner than half of them
  size_t nodes_held_back = 0;  // nodes kept off the input to stay valid
  // The first fit's nodes held back more than a base cell from the input, and its triangles with
  // a point over 3/4 of a base cell off; where any point was over a base cell off, the grid was
  // refined around them and the lattice fitted again (refine_where_far).
  size_t nodes_held_back_far_first_fit = 0;
  size_t triangles_far_first_fit = 0;
  size_t nodes_projected = 0;  // nodes of the lattice surface (with polygon centres)
  TwoSidedReport two_sided;
  size_t triangles_before_coarsening = 0;
  QualityReport quality;
  MeshDiagnostics output;
  DistanceStats output_to_input, input_to_output;
  DistanceStats sharp_edges_to_output;  // samples along the input's sharp edges (over 40 degrees)
  std::vector<StageStats> stages;
  double total_seconds = 0;
  // Filled by the caller, not by wrap(): the program and the input file the report is about
  // (the CLI knows the file's name; the library never sees one). Left out of the JSON when empty.
  struct Source {
    std::string tool_version;                           // "0.1.0"
    std::string file_name;                              // the input's file name, without its folder
    std::vector<std::pair<std::string, size_t>> parts;  // each input part's name and triangle count
    std::vector<std::string> notes;                     // what reading the input assumed (Mesh::notes)
  } source;
};

std::string to_json(const WrapReport& report, int indent = 2);
std::string to_json(const MeshDiagnostics& diagnostics, int indent = 2);
std::string to_json(const DistanceStats& distance, int indent = 2);

// The leak as a small OBJ to load next to the input: an octahedron at the narrowest passage
// (as wide as the passage) and the path from the seed point as a polyline.
std::string leak_to_obj(const LeakReport& leak);

// The leak of a JSON report (to_json(WrapReport)); not detected when there is none.
// Throws Error(InvalidInput) for text that is not JSON.
LeakReport leak_from_report_json(const std::string& report_json);

}  // namespace vdbwrap
