// The one public API of the vdbwrap core: wrap a dirty triangle mesh into a closed,
// 2-manifold, outward-oriented, self-intersection-free surface, and diagnose meshes.
// The CLI and the gRPC server are thin layers over these functions.
#pragma once
#include <cstdint>
#include <functional>
#include <map>
#include <memory>
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
  double small_area = 0.01;           // area under this x (local cell size)^2
  double sliver_angle_deg = 5;        // smallest angle under this (needles and caps)
  double short_edge = 0.1;            // edge shorter than this x the local cell size
  double long_edge = 4;               // edge longer than this x the local cell size (the larger at its ends)
  double normal_deviation_deg = 45;   // normal off the input's near the triangle by more than this
  double near_input = 0.25;           // normals are judged where the input is within this x the local cell size
  double feature_tolerance = 0.1;     // sharp-edge samples farther than this x the finest cell are lost ...
  double feature_reach = 2;           // ... unless farther than this x the local cell size (out of the wrap's reach)
};

struct WrapParams {
  Length base_size{1.0, true};     // edge of a level-0 cell
  int levels = 1;                  // most 2x2x2 refinements below the base size
  double feature_angle_deg = 30;   // dihedral angle (between normals) that makes an edge sharp
  VolumeChoice volume = VolumeChoice::Outside;
  std::vector<Vec3> seed_points;   // VolumeChoice::SeedPoints: one or more material points
  int threads = 0;                 // 0: all cores

  // User controls of the voxel stage (spec stage 2).
  std::optional<Length> gap_closure;          // openings narrower than this do not let the volume through
  std::vector<ControlVolume> control_volumes; // finer cells inside these regions
  std::vector<PartSize> part_sizes;           // finer cells where these parts pass
  std::vector<ContactRule> contact_prevention;  // parts kept apart by refining between them
  std::optional<Length> contact_floor;        // smallest cell contact prevention may use (default: finest / 8)

  // Refinement criteria of a cell the input passes through (spec stage 2).
  int refine_max_triangles = 64;        // more triangles than this in a cell: refine
  double refine_normal_spread_deg = 20; // normals spread more than this: refine
  bool refine_at_features = true;       // sharp, boundary or intersection edges: refine

  // Projection (spec stage 3).
  double weld_tolerance = 1e-7;    // fraction of the diagonal under which vertices merge
  double surface_offset = 0.005;   // nodes stop this fraction of the finest cell off the input
  int presmooth_iterations = 16;   // smoothing of the voxel surface before projection (untangling)
  // Rounds of the projection's validity loop (offending nodes pulled back toward the lattice);
  // intersections still left afterwards go to stage 4's remeshing and intersection repair.
  int validity_rounds = 400;

  // Feature snapping (spec stage 3): wrap edges traced along the feature curves and moved
  // onto them, convex and concave alike, with the corners.
  bool snap_features = true;
  double corner_angle_deg = 30;    // a feature curve turning more than this at a point has a corner there

  // Coarsening (stage 4): nodes merged on flat parts while every new triangle stays within
  // this fraction of the base size of the input; 0 turns it off.
  double coarsen_tolerance = 0.02;

  // Stage 4: bad regions (slivers, tiny triangles, very poor normals, intersections) rebuilt
  // from the input (constrained Delaunay on nearly flat patches) or by ear clipping.
  bool remesh = true;
  QualityThresholds quality;       // what counts as a defect (fixed; listed in the report)

  // The output will be stored in single precision (binary STL): coordinates are rounded to
  // float during the validity loop, so the validity checked is that of what is written.
  bool float_coordinates = false;

  bool compute_distances = true;   // sample output-to-input distances for the report
};

// Progress and cancellation, passed in by the caller. Methods may be called from any thread.
class ProgressSink {
 public:
  virtual ~ProgressSink() = default;
  // stage: short stage name; fraction: 0..1 within the stage.
  virtual void progress(const std::string& stage, double fraction, const std::string& message) = 0;
  // Polled often; returning true makes wrap() throw Error(Cancelled) within moments.
  virtual bool cancelled() { return false; }
};

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
  size_t curves = 0, corners = 0, curves_captured = 0, corners_captured = 0, nodes_snapped = 0;
  // Curve points the traced chains missed (sampled every half finest cell), and what was done
  // about them: nodes inserted on the curve by edge splits, nodes moved onto it, points left
  // because every change was refused, points behind the input (buried intersection lines).
  size_t points_missed = 0, nodes_inserted = 0, nodes_moved = 0, inserts_refused = 0, points_unreachable = 0;
};

// What the flood fill found: does the input enclose anything at this cell size?
struct VolumeReport {
  size_t free_volumes = 0;         // connected volumes of cells the input does not touch
  size_t enclosed_volumes = 0;     // of those, the ones that do not reach the outside and hold a whole base cell
  double largest_enclosed = 0;     // model units cubed (cells, so approximate)
  bool encloses_volume = false;    // the input, as given, is closed at this cell size
  double chosen_volume = 0;        // model units cubed, before the surface is fitted
  double gap_closure = 0;          // model units; 0: off
};

// A seed point's volume reached the outside or another seed point's volume.
struct LeakReport {
  bool detected = false;
  std::string description;         // e.g. "seed point 1 reaches the outside"
  Vec3 location{0, 0, 0};          // the narrowest passage on the widest way through
  double width = 0;                // about twice the passage's clearance from the input
  std::vector<Vec3> path;          // from the seed point out, through the passage
};

// Where contact prevention could not keep parts apart above its floor size.
struct ContactReport {
  size_t rules = 0;
  double floor = 0;                // model units
  size_t unresolved_cells = 0;     // cells at the floor still holding parts that must stay apart
  std::vector<Vec3> unresolved_locations;  // one per cluster (at most 100)
  size_t separate_bodies = 0;      // connected pieces of the wrap
};

// Defects of one surface, by kind (QualityThresholds says when each counts).
struct QualityCounts {
  size_t triangles = 0, edges = 0;
  size_t self_intersecting = 0;      // triangles in an intersecting pair, or degenerate
  size_t small_area = 0;             // triangles
  size_t slivers = 0;                // triangles
  size_t short_edges = 0, long_edges = 0;  // edges
  size_t normal_deviation = 0;       // triangles
  size_t feature_samples = 0;        // points along the input's sharp edges (feature angle), every 0.1 % of the diagonal
  size_t lost_feature_samples = 0;   // of those, farther from the surface than the feature tolerance (within reach)
  size_t unreachable_feature_samples = 0;  // farther than the reach: inside other bodies, in slots narrower than the cells
  double min_angle_deg = 0;          // smallest angle of any triangle
  double max_normal_deviation_deg = 0;
};

// Stage 4: the quality analysis before and after the post-processing (remeshing of bad regions
// and, when anything still intersects, the intersection repair), and what each step did.
struct QualityReport {
  QualityCounts before, after;
  size_t regions = 0;                // bad regions tried
  size_t remeshed_on_input = 0;      // rebuilt with the input as substrate (constrained Delaunay)
  size_t remeshed_by_ear_clipping = 0;  // rebuilt by the fallback
  size_t restored = 0;               // rebuilt, but the rebuild was refused: put back as it was
  std::map<std::string, size_t> refusals;  // why rebuilds were refused
  // Intersection repair (spec, second paper) on the wrap when anything still intersected.
  size_t repair_runs = 0;
  size_t intersecting_before_repair = 0, intersecting_after_repair = 0;  // triangles
  std::string repair_summary;        // what the repair did, when it ran
};

struct WrapReport {
  MeshDiagnostics input;
  FeatureStats features;
  WrapParams params;
  double base_size = 0, finest_size = 0, diagonal = 0;
  std::vector<size_t> cells_per_level;  // cells the input passes through, per level
  std::vector<std::pair<std::string, double>> control_sizes;  // control volumes / part sizes and their cell size
  VolumeReport volumes;
  LeakReport leak;
  ContactReport contact;
  size_t manifold_fixes = 0;            // cells taken out of the volume to keep it manifold
  size_t nodes_held_back = 0;           // nodes kept off the input to stay valid
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
    std::string tool_version;                            // "0.1.0"
    std::string file_name;                               // the input's file name, without its folder
    std::vector<std::pair<std::string, size_t>> parts;  // each input part's name and triangle count
  } source;
};

struct WrapResult {
  Mesh surface;
  WrapReport report;
};

// A wrap that stopped with a report worth keeping (a leak, a surface that failed
// validation): the report so far comes with the error.
class WrapFailure : public Error {
 public:
  WrapFailure(const std::string& message, WrapReport report)
      : Error(ErrorKind::WrapFailed, message), report_(std::make_shared<WrapReport>(std::move(report))) {}
  const WrapReport& report() const { return *report_; }

 private:
  std::shared_ptr<WrapReport> report_;
};

// Runs the whole pipeline. Throws Error: InvalidArgument (parameters), InvalidInput
// (mesh unusable, e.g. no triangles left), WrapFailed (no valid surface; a WrapFailure
// with the report so far when there is one, e.g. for a leak), Cancelled.
WrapResult wrap(const Mesh& input, const WrapParams& params, ProgressSink* progress = nullptr);

// Diagnostics of any mesh, welded exactly (exactly equal coordinates) first.
MeshDiagnostics diagnose(const Mesh& mesh, bool find_intersections = true);

// Metro-style one-sided distance: samples on `from` spread by area at a spacing of
// diagonal / samples_per_diagonal (widened so that there are at most about two million),
// plus every vertex; distances to `to`.
DistanceStats sampled_distance(const Mesh& from, const Mesh& to, double samples_per_diagonal = 1000);

// Distance from points sampled every spacing_fraction x diagonal along the input's sharp
// edges (normals more than angle_deg apart) to `surface`: how well it keeps the edges.
DistanceStats sharp_edge_distance(const Mesh& input, const Mesh& surface, double angle_deg = 40,
                                  double spacing_fraction = 0.001);

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
