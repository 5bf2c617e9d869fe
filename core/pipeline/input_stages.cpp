// Stages 0 and 1: the input's diagnosis and its preparation.
#include <algorithm>
#include <cmath>
#include <vector>

#include "check/diagnostics.h"
#include "common/float_round.h"
#include "common/stage_timer.h"
#include "mesh/bundled_lines.h"
#include "mesh/cracks.h"
#include "mesh/fold_crossings.h"
#include "mesh/narrow_strips.h"
#include "mesh/orient.h"
#include "mesh/rough_edges.h"
#include "mesh/short_feature_runs.h"
#include "mesh/small_rims.h"
#include "pipeline/stage_params.h"
#include "pipeline/stages.h"

namespace vdbwrap::pipeline {

void diagnose_input(WrapRun& run) {
  StageTimer timer("diagnose input", run.report.stages);
  if (run.progress) run.progress->progress("diagnose input", 0.0, "checking the input for defects");
  // Intersections are left to prepare, whose one search serves both the report and the
  // intersection lines; the counts are filled in there.
  run.input_weld = exact_weld(run.input.points);
  run.report.input = check::diagnose_welded(run.input, run.input_weld, false);
  run.check_cancel();
}

namespace {

// The finest cell of the wrap (the thin-part levels aside), in model units.
double finest_cell(const WrapRun& run) { return run.base / double(int64_t(1) << std::min(run.params.levels, 30)); }

// Lines closer than this lie within a sliver's width of the finest cell (kBundleAngle).
double sliver_width(const WrapRun& run) { return std::tan(kBundleAngle * M_PI / 180) / 2 * finest_cell(run); }

// The widest crack: a gap the wrap cannot enter (stage_params.h); never narrower than the
// bundles' sliver width.
double crack_width(const WrapRun& run) { return std::max(sliver_width(run), kCrackWidth * finest_cell(run)); }

// Output written in single precision keeps the wrap valid as written: far from the origin a
// float's steps grow as coarse as the cells (a survey's coordinates, a part placed in a large
// assembly), nodes round onto one another and the wrap comes out as steps or not at all.
void check_float_steps(const WrapRun& run) {
  if (!run.params.float_coordinates) return;
  double far = 0;  // the largest coordinate the wrap may reach: the input's, a base cell out
  for (int k = 0; k < 3; ++k)
    far = std::max({far, std::fabs(run.report.input.bbox_min[k]), std::fabs(run.report.input.bbox_max[k])});
  far += run.base;
  const double step = float_step(far);
  const double share = step / finest_cell(run);
  if (share < kFloatStepWarned) return;
  char text[400];
  std::snprintf(text, sizeof text,
                "the output is stored in single precision (STL): at coordinates up to %.3g a float's step is "
                "%.3g, %.2g of the finest cell (%.3g)",
                far, step, share, finest_cell(run));
  const std::string remedy =
      ": write .obj, .ply or .vtp, which keep doubles, move the model nearer the origin, or take a larger "
      "--base-size";
  if (share >= kCoarsestFloatStep)
    throw Error(ErrorKind::InvalidArgument,
                std::string(text) + ", too coarse for a valid wrap that follows the input" + remedy);
  if (run.progress)
    run.progress->progress("prepare", 1.0,
                           std::string("warning: ") + text + ", so the wrap follows the input less closely" + remedy);
}

// Drops the items i for which dropped(i) holds (read before any item moves), the others keeping
// their order. Returns how many went.
template <typename T, typename Dropped>
size_t drop_where(std::vector<T>& items, Dropped&& dropped) {
  size_t kept = 0;
  for (size_t i = 0; i < items.size(); ++i)
    if (!dropped(i)) items[kept++] = items[i];
  const size_t gone = items.size() - kept;
  items.resize(kept);
  return gone;
}

// A part placed more than once a hair apart brings each sharp edge as a bundle of parallel lines
// (mesh/bundled_lines.h); the wrap follows the outermost. Bundled lines closer than a sliver's
// width at the finest cell: curves on both would make nothing but slivers between them.
void drop_duplicate_lines(WrapRun& run) {
  prep::PreparedInput& prepared = run.prepared;
  auto& edges = prepared.feature_edges;
  auto& crossings = prepared.intersections;
  const std::vector<Vec3> edge_out =
      mesh::sharp_edges_outward(prepared.mesh.triangles, prepared.normals, prepared.closed_piece, edges);
  std::vector<mesh::OrientedLine> lines;
  lines.reserve(edges.size() + crossings.size());
  for (size_t i = 0; i < edges.size(); ++i)
    lines.push_back({prepared.mesh.points[edges[i].a], prepared.mesh.points[edges[i].b], edge_out[i]});
  for (const auto& s : crossings)
    lines.push_back({s.a, s.b, mesh::crossing_outward(s.tri_a, s.tri_b, prepared.normals, prepared.closed_piece)});
  const double width = sliver_width(run);
  const std::vector<uint8_t> inner = mesh::inner_lines_of_bundles(lines, width, run.base, kBundleAngle);
  const size_t first_crossing = edges.size();
  run.report.features.duplicate_sharp_edges = drop_where(edges, [&](size_t i) { return inner[i]; });
  run.report.features.duplicate_intersection_segments =
      drop_where(crossings, [&](size_t i) { return inner[first_crossing + i]; });
}

// Nine in ten sides of the hairline cracks lie at most this far from the other side (0: no
// crack): the plates of a soup rounded apart stand about that far above and below each other.
double crack_gap(const std::vector<mesh::CrackSide>& crack, const std::vector<mesh::CrackAcross>& across) {
  std::vector<double> width;
  for (size_t i = 0; i < crack.size(); ++i)
    if (crack[i] != mesh::CrackSide::None) width.push_back(across[i].width);
  if (width.empty()) return 0;
  const auto at = width.begin() + std::ptrdiff_t(width.size() * 9 / 10);
  std::nth_element(width.begin(), at, width.end());
  return *at;
}

// The two sides of a crack are no rims: the surface goes on across it, or turns at a crease,
// which one side keeps as a sharp edge; the lines where the faces across it cross go too
// (mesh/cracks.h).
void drop_crack_sides(WrapRun& run) {
  prep::PreparedInput& prepared = run.prepared;
  std::vector<mesh::FeatureEdge>& edges = prepared.feature_edges;
  // A hairline crack's sides first, then the sides of wider gaps among the edges left (a
  // wider search alone finds other partners beside a hairline crack's: a face written twice).
  std::vector<mesh::CrackAcross> across, hairline_across;
  const std::vector<mesh::CrackSide> hairline =
      mesh::crack_sides(prepared.mesh.points, prepared.mesh.triangles, prepared.normals, edges, sliver_width(run),
                        run.base, kBundleAngle, run.params.feature_angle_deg, false, &hairline_across);
  const std::vector<mesh::CrackSide> wide =
      mesh::crack_sides(prepared.mesh.points, prepared.mesh.triangles, prepared.normals, edges, crack_width(run),
                        run.base, kCrackAngle, run.params.feature_angle_deg, true, &across, &hairline);
  std::vector<mesh::CrackSide> crack = hairline;
  std::vector<std::pair<uint32_t, uint32_t>> gap_faces;  // the two faces across a gap, sorted
  for (size_t i = 0; i < edges.size(); ++i)
    if (crack[i] == mesh::CrackSide::None && wide[i] != mesh::CrackSide::None) {
      crack[i] = wide[i];
      gap_faces.emplace_back(std::min(across[i].face, across[i].other), std::max(across[i].face, across[i].other));
    }
  run.report.features.crack_gap = crack_gap(hairline, hairline_across);
  std::sort(gap_faces.begin(), gap_faces.end());
  for (size_t i = 0; i < edges.size(); ++i)
    if (crack[i] == mesh::CrackSide::Crease) edges[i].kind = mesh::FeatureKind::Sharp;
  // Where the faces across a crack cross (their corners rounded apart): beside a hairline
  // crack's sides; where two faces across a gap cross, that pair (a search a gap wide would
  // look at many sides per point of a soup of small faces).
  std::vector<std::array<Vec3, 2>> lines;
  for (const auto& s : prepared.intersections) lines.push_back({s.a, s.b});
  const std::vector<uint8_t> along = mesh::crossings_along_cracks(prepared.mesh.points, edges, hairline, lines,
                                                                  sliver_width(run), run.base, kBundleAngle);
  // Of the faces that cross, the corners on a crack: a soup's (a welded fold's corners near
  // each other are no crack's).
  std::vector<uint8_t> on_crack(prepared.mesh.points.size(), 0);
  for (size_t i = 0; i < edges.size(); ++i)
    if (crack[i] != mesh::CrackSide::None) on_crack[edges[i].a] = on_crack[edges[i].b] = 1;
  const auto corners = [&](uint32_t t) {
    std::array<Vec3, 3> at;
    for (int k = 0; k < 3; ++k) {
      const uint32_t v = prepared.mesh.triangles[t][k];
      at[k] = on_crack[v] ? prepared.mesh.points[v] : Vec3{NAN, NAN, NAN};  // (within no width)
    }
    return at;
  };
  run.report.features.crack_intersection_segments = drop_where(prepared.intersections, [&](size_t i) {
    const auto& s = prepared.intersections[i];
    return along[i] ||
           mesh::crossing_at_shared_corner(corners(s.tri_a), corners(s.tri_b), s.a, s.b, sliver_width(run)) ||
           std::binary_search(gap_faces.begin(), gap_faces.end(),
                              std::make_pair(std::min(s.tri_a, s.tri_b), std::max(s.tri_a, s.tri_b)));
  });
  // A hairline crease kept from one side runs where the planes of its two faces meet (a gap's
  // would part from the rims beside it).
  mesh::move_creases_to_plane_meet(prepared.mesh.points, prepared.mesh.triangles, prepared.normals, hairline,
                                   hairline_across, sliver_width(run), edges);
  // A hairline crease's ends lie within the sliver width; a gap's, a gap apart, join no nearer.
  mesh::join_crease_ends(prepared.mesh.points, hairline, sliver_width(run), edges);
  // (a crease's edge shorter than the width has its two ends joined: it goes too)
  run.report.features.crack_edges =
      drop_where(edges, [&](size_t i) { return crack[i] == mesh::CrackSide::Goes || edges[i].a == edges[i].b; });
}

}  // namespace

void prepare_input(WrapRun& run) {
  WrapReport& report = run.report;
  {
    StageTimer timer("prepare", report.stages);
    run.prepared = prep::prepare(run.input, prepare_params(run.params), run.progress, &run.input_weld);
    run.input_weld = ExactWeld();  // its memory back
  }
  const prep::PreparedInput& prepared = run.prepared;
  const prep::InputIntersections crossing =
      prep::input_intersections(prepared.intersecting_pairs, prepared.input_to_mesh, prepared.mesh.triangles.size());
  report.input.intersecting_pairs = crossing.pairs;
  report.input.intersecting_triangles = crossing.triangles;
  report.input.self_intersecting = crossing.pairs > 0;
  for (const auto& f : prepared.feature_edges) {
    if (f.kind == prep::FeatureKind::Sharp) ++report.features.sharp_edges;
    if (f.kind == prep::FeatureKind::Boundary) ++report.features.boundary_edges;
    if (f.kind == prep::FeatureKind::NonManifold) ++report.features.nonmanifold_edges;
  }
  report.features.intersection_segments = prepared.intersections.size();
  report.features.inside_faces = prepared.dropped_inside;
  report.diagonal = prepared.diagonal;
  run.base = run.params.base_size.resolve(prepared.diagonal);
  report.base_size = run.base;
  if (prepared.diagonal / run.base > kMostCellsAcross)
    throw Error(ErrorKind::InvalidArgument, "base size " + run.params.base_size.to_string() +
                                                " is too small for this model (over " +
                                                std::to_string(kMostCellsAcross) + " cells across its diagonal)");
  check_float_steps(run);
  // Faces that do not share their corners meet along cracks, each side a rim.
  drop_crack_sides(run);
  // A rough surface's sharp edges (a scan's noise) form runs shorter than the wrap can follow:
  // they would become thousands of feature curves, each with nodes snapped and inserted.
  mesh::Roughness rough =
      mesh::roughness(run.prepared.mesh.points.size(), run.prepared.mesh.triangles, run.prepared.feature_edges);
  report.features.noise_sharp_edges = mesh::drop_short_sharp_runs(
      run.prepared.mesh.points, run.prepared.feature_edges, kShortestSharpRun * run.base, run.params.corner_angle_deg);
  // The rest of a rough surface's sharp edges line up into longer runs (the straight lines of
  // a regular tessellation); seen over a base cell on either hand, the surface is smooth there.
  report.features.noise_sharp_edges +=
      mesh::drop_edges_smooth_at_scale(run.prepared.mesh.points, run.prepared.mesh.triangles,
                                       run.prepared.feature_edges, rough, run.base, run.params.feature_angle_deg);
  run.prepared.sharp_all_round = std::move(rough.sharp_all_round);
  // Where rough sheets cross, so do their self-intersection lines, in short runs just as dense;
  // where a rough surface folds over, it crosses itself next to itself in short runs; where
  // open sheets cross in a clump, in runs as short as the sheets are wide.
  {
    std::vector<Vec3> ends, sheet_ends;
    std::vector<size_t> sheet_lines;
    std::vector<std::pair<uint32_t, uint32_t>> pairs;
    const std::vector<uint32_t>& piece = prepared.closed_piece;
    auto open = [&](uint32_t t) { return t < piece.size() && piece[t] == mesh::kOpenPiece; };
    for (size_t i = 0; i < run.prepared.intersections.size(); ++i) {
      const auto& s = run.prepared.intersections[i];
      ends.push_back(s.a), ends.push_back(s.b), pairs.emplace_back(s.tri_a, s.tri_b);
      if (open(s.tri_a) && open(s.tri_b))
        sheet_ends.push_back(s.a), sheet_ends.push_back(s.b), sheet_lines.push_back(i);
    }
    const std::vector<uint8_t> fold = mesh::fold_crossings(prepared.mesh.points.size(), prepared.mesh.triangles, pairs);
    std::vector<uint8_t> noise = mesh::short_line_runs(ends, kShortestSharpRun * run.base, run.params.corner_angle_deg,
                                                       kLineWeld * prepared.diagonal, &fold);
    const std::vector<uint8_t> sheet_noise = mesh::short_line_runs(
        sheet_ends, kShortestSheetCrossing * run.base, run.params.corner_angle_deg, kLineWeld * prepared.diagonal);
    for (size_t k = 0; k < sheet_lines.size(); ++k) noise[sheet_lines[k]] |= sheet_noise[k];
    report.features.noise_intersection_segments =
        drop_where(run.prepared.intersections, [&](size_t i) { return noise[i]; });
  }
  // A raw scan's floating fragments, a cell or two across, are wrapped as blobs: their rims
  // would be thousands more curves, folding the blobs into slivers.
  report.features.small_rim_edges =
      mesh::drop_small_rims(run.prepared.mesh.points, run.prepared.feature_edges, kSmallestRim * run.base);
  // A thin tube with few sides (hair, a wire) is wrapped as a round blob: the edges between its
  // sides, narrower than the finest cell, would be parallel curves a fraction of a cell apart;
  // so would the lines where such tubes cross (a lattice's struts).
  {
    const int thin = std::clamp(refine_criteria(run.params).thin_levels, 0, 30);
    const double finest = finest_cell(run);
    auto& lines = run.prepared.intersections;
    std::vector<uint32_t> crossing;
    for (const auto& s : lines) crossing.push_back(s.tri_a), crossing.push_back(s.tri_b);
    const mesh::NarrowFaces narrow =
        mesh::narrow_faces(run.prepared.mesh.points, run.prepared.mesh.triangles, run.prepared.feature_edges, finest,
                           &run.prepared.closed_piece, finest / double(int64_t(1) << thin), crossing);
    report.features.narrow_strip_edges = mesh::drop_narrow_strip_edges(run.prepared.feature_edges, narrow);
    report.features.narrow_strip_intersection_segments = drop_where(
        lines, [&](size_t i) { return narrow.triangles[lines[i].tri_a] && narrow.triangles[lines[i].tri_b]; });
  }
  drop_duplicate_lines(run);
}

}  // namespace vdbwrap::pipeline
