// JSON forms of the report, the diagnostics and the distances (the CLI's --report and the
// server's job report share them).
#include <nlohmann/json.hpp>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <sstream>

#include "source_json.h"
#include "vdbwrap/report.h"

namespace vdbwrap {
namespace {
using nlohmann::json;

json diag_json(const MeshDiagnostics& d) {
  return json{{"vertices", d.vertices},
              {"triangles", d.triangles},
              {"parts", d.parts},
              {"components", d.components},
              {"border_edges", d.border_edges},
              {"nonmanifold_edges", d.nonmanifold_edges},
              {"nonmanifold_vertices", d.nonmanifold_vertices},
              {"misoriented_edges", d.misoriented_edges},
              {"degenerate_triangles", d.degenerate_triangles},
              {"intersecting_triangles", d.intersecting_triangles},
              {"intersecting_pairs", d.intersecting_pairs},
              {"closed", d.closed},
              {"manifold", d.manifold},
              {"oriented", d.oriented},
              {"outward", d.outward},
              {"self_intersecting", d.self_intersecting},
              {"valid_closed_surface", d.valid_closed_surface()},
              {"area", d.area},
              {"volume", d.volume},
              {"diagonal", d.diagonal},
              {"bbox_min", d.bbox_min},
              {"bbox_max", d.bbox_max}};
}

json dist_json(const DistanceStats& s) {
  double dg = s.diagonal > 0 ? s.diagonal : 1;
  return json{{"samples", s.samples},
              {"mean", s.mean},
              {"p95", s.p95},
              {"max", s.max},
              {"max_at", s.max_at},
              {"mean_percent_of_diagonal", 100 * s.mean / dg},
              {"p95_percent_of_diagonal", 100 * s.p95 / dg},
              {"max_percent_of_diagonal", 100 * s.max / dg}};
}

json control_volumes_json(const WrapParams& p) {
  json a = json::array();
  for (const auto& cv : p.control_volumes) a.push_back(cv.to_string());
  return a;
}
json part_sizes_json(const WrapParams& p) {
  json a = json::array();
  for (const auto& ps : p.part_sizes) a.push_back(ps.part + "=" + ps.size.to_string());
  return a;
}
json contact_json(const WrapParams& p) {
  json a = json::array();
  for (const auto& r : p.contact_prevention) a.push_back(r.to_string());
  return a;
}

json params_json(const WrapParams& p) {
  return json{{"base_size", p.base_size.to_string()},
              {"levels", p.levels},
              {"thin_part_levels", p.thin_part_levels},
              {"feature_angle_deg", p.feature_angle_deg},
              {"volume", volume_choice_to_string(p.volume, p.seed_points)},
              {"gap_closure", p.gap_closure ? json(p.gap_closure->to_string()) : json(nullptr)},
              {"control_volumes", control_volumes_json(p)},
              {"part_sizes", part_sizes_json(p)},
              {"contact_prevention", contact_json(p)},
              {"contact_floor", p.contact_floor ? json(p.contact_floor->to_string()) : json(nullptr)},
              {"threads", p.threads},
              {"refine_max_triangles", p.refine_max_triangles},
              {"refine_normal_spread_deg", p.refine_normal_spread_deg},
              {"refine_at_features", p.refine_at_features},
              {"refine_far_cells", p.refine_far_cells},
              {"refine_where_far", p.refine_where_far},
              {"weld_tolerance", p.weld_tolerance},
              {"surface_offset", p.surface_offset},
              {"presmooth_iterations", p.presmooth_iterations},
              {"snap_features", p.snap_features},
              {"corner_angle_deg", p.corner_angle_deg},
              {"coarsen_tolerance", p.coarsen_tolerance},
              {"validity_rounds", p.validity_rounds},
              {"remesh", p.remesh},
              {"remove_slivers", p.remove_slivers},
              {"proximity_refinement", p.proximity_refinement},
              {"two_sided_sheets", p.two_sided_sheets},
              {"float_coordinates", p.float_coordinates}};
}
json counts_json(const QualityCounts& q) {
  return json{{"triangles", q.triangles},
              {"edges", q.edges},
              {"self_intersecting_triangles", q.self_intersecting},
              {"small_area_triangles", q.small_area},
              {"sliver_triangles", q.slivers},
              {"short_edges", q.short_edges},
              {"long_edges", q.long_edges},
              {"normal_deviation_triangles", q.normal_deviation},
              {"feature_samples", q.feature_samples},
              {"lost_feature_samples", q.lost_feature_samples},
              {"unreachable_feature_samples", q.unreachable_feature_samples},
              {"min_angle_deg", q.min_angle_deg},
              {"max_normal_deviation_deg", q.max_normal_deviation_deg}};
}

json quality_json(const QualityReport& q, const WrapParams& p) {
  const QualityThresholds& t = p.quality;
  return json{{"thresholds",
               {{"small_area", t.small_area},
                {"sliver_angle_deg", t.sliver_angle_deg},
                {"short_edge", t.short_edge},
                {"long_edge", t.long_edge},
                {"normal_deviation_deg", t.normal_deviation_deg},
                {"near_input", t.near_input},
                {"feature_tolerance", t.feature_tolerance},
                {"feature_reach", t.feature_reach}}},
              {"before", counts_json(q.before)},
              {"after", counts_json(q.after)},
              {"remesh",
               {{"enabled", p.remesh},
                {"regions", q.regions},
                {"rebuilt_on_input", q.remeshed_on_input},
                {"rebuilt_by_ear_clipping", q.remeshed_by_ear_clipping},
                {"restored", q.restored},
                {"refusals", q.refusals}}},
              {"proximity_refinement",
               {{"enabled", p.proximity_refinement},
                {"ran", q.proximity_refinement.ran},
                {"far_distance", q.proximity_refinement.far_distance},
                {"far_triangles_before", q.proximity_refinement.far_triangles_before},
                {"far_triangles_after", q.proximity_refinement.far_triangles_after},
                {"pulls", q.proximity_refinement.pulls},
                {"splits", q.proximity_refinement.splits},
                {"collapses", q.proximity_refinement.collapses},
                {"refusals", q.proximity_refinement.refusals}}},
              {"sliver_removal",
               {{"enabled", p.remove_slivers},
                {"ran", q.sliver_removal.ran},
                {"target_angle_deg", q.sliver_removal.target_angle_deg},
                {"slivers_before", q.sliver_removal.slivers_before},
                {"slivers_after", q.sliver_removal.slivers_after},
                {"flips", q.sliver_removal.flips},
                {"collapses", q.sliver_removal.collapses},
                {"moves", q.sliver_removal.moves},
                {"splits", q.sliver_removal.splits},
                {"refusals", q.sliver_removal.refusals}}},
              {"intersection_repair",
               {{"runs", q.repair_runs},
                {"intersecting_triangles_before", q.intersecting_before_repair},
                {"intersecting_triangles_after", q.intersecting_after_repair},
                {"summary", q.repair_summary}}}};
}

json leak_json(const LeakReport& l) {
  if (!l.detected) return json{{"detected", false}};
  return json{{"detected", true},
              {"description", l.description},
              {"location", l.location},
              {"width", l.width},
              {"path", l.path}};
}

}  // namespace

LeakReport leak_from_report_json(const std::string& text) {
  LeakReport leak;
  try {
    const json j = json::parse(text);
    if (!j.contains("leak") || !j["leak"].value("detected", false)) return leak;
    const json& l = j["leak"];
    leak.detected = true;
    leak.description = l.value("description", "");
    leak.location = l.at("location").get<Vec3>();
    leak.width = l.value("width", 0.0);
    if (l.contains("path")) leak.path = l["path"].get<std::vector<Vec3>>();
  } catch (const json::exception& e) {
    throw Error(ErrorKind::InvalidInput, std::string("report: ") + e.what());
  }
  return leak;
}

std::string leak_to_obj(const LeakReport& leak) {
  std::ostringstream o;
  o.precision(9);
  o << "# vdbwrap leak: " << leak.description << "\n# narrowest passage at " << leak.location[0] << ' '
    << leak.location[1] << ' ' << leak.location[2] << ", about " << leak.width << " wide\n";
  // A small octahedron at the passage, then the path as a polyline.
  const double r = std::max(leak.width * 0.5, 1e-9);
  const Vec3& c = leak.location;
  const double d[6][3] = {{r, 0, 0}, {-r, 0, 0}, {0, r, 0}, {0, -r, 0}, {0, 0, r}, {0, 0, -r}};
  o << "o leak_passage\n";
  for (const auto& v : d) o << "v " << c[0] + v[0] << ' ' << c[1] + v[1] << ' ' << c[2] + v[2] << "\n";
  const int f[8][3] = {{1, 3, 5}, {3, 2, 5}, {2, 4, 5}, {4, 1, 5}, {3, 1, 6}, {2, 3, 6}, {4, 2, 6}, {1, 4, 6}};
  for (const auto& t : f) o << "f " << t[0] << ' ' << t[1] << ' ' << t[2] << "\n";
  o << "o leak_path\n";
  for (const Vec3& p : leak.path) o << "v " << p[0] << ' ' << p[1] << ' ' << p[2] << "\n";
  if (leak.path.size() > 1) {
    o << "l";
    for (size_t i = 0; i < leak.path.size(); ++i) o << ' ' << 7 + i;
    o << "\n";
  }
  return o.str();
}

Length Length::parse(const std::string& text) {
  std::string t = text;
  while (!t.empty() && std::isspace(static_cast<unsigned char>(t.back()))) t.pop_back();
  Length len;
  len.percent_of_diagonal = !t.empty() && t.back() == '%';
  if (len.percent_of_diagonal) t.pop_back();
  double v = 0;
  auto [end, ec] = std::from_chars(t.data(), t.data() + t.size(), v);
  if (t.empty() || ec != std::errc() || end != t.data() + t.size() || !std::isfinite(v) || v <= 0)
    throw Error(ErrorKind::InvalidArgument,
                "'" + text + "' is not a positive length (model units, or N% of the diagonal)");
  len.value = v;
  return len;
}

std::string Length::to_string() const {
  std::ostringstream s;
  s << value;
  if (percent_of_diagonal) s << '%';
  return s.str();
}

std::string to_json(const MeshDiagnostics& d, int indent) { return diag_json(d).dump(indent); }
std::string to_json(const DistanceStats& s, int indent) { return dist_json(s).dump(indent); }

std::string to_json(const WrapReport& r, int indent) {
  json stages = json::array();
  for (const auto& s : r.stages)
    stages.push_back({{"name", s.name}, {"seconds", s.seconds}, {"peak_memory_mb", s.peak_memory_mb}});
  json sizes = json::array();
  for (const auto& [what, size] : r.control_sizes) sizes.push_back({{"control", what}, {"cell_size", size}});
  json j{{"input", diag_json(r.input)},
         {"features",
          {{"sharp_edges", r.features.sharp_edges},
           {"boundary_edges", r.features.boundary_edges},
           {"nonmanifold_edges", r.features.nonmanifold_edges},
           {"noise_intersection_segments", r.features.noise_intersection_segments},
           {"noise_sharp_edges", r.features.noise_sharp_edges},
           {"small_rim_edges", r.features.small_rim_edges},
           {"narrow_strip_edges", r.features.narrow_strip_edges},
           {"narrow_strip_intersection_segments", r.features.narrow_strip_intersection_segments},
           {"duplicate_sharp_edges", r.features.duplicate_sharp_edges},
           {"duplicate_intersection_segments", r.features.duplicate_intersection_segments},
           {"crack_edges", r.features.crack_edges},
           {"crack_intersection_segments", r.features.crack_intersection_segments},
           {"crack_gap", r.features.crack_gap},
           {"inside_faces", r.features.inside_faces},
           {"intersection_segments", r.features.intersection_segments},
           {"curves", r.features.curves},
           {"corners", r.features.corners},
           {"curves_captured", r.features.curves_captured},
           {"corners_captured", r.features.corners_captured},
           {"nodes_snapped", r.features.nodes_snapped},
           {"points_missed_by_tracing", r.features.points_missed},
           {"nodes_inserted", r.features.nodes_inserted},
           {"nodes_moved", r.features.nodes_moved},
           {"inserts_refused", r.features.inserts_refused},
           {"points_unreachable", r.features.points_unreachable}}},
         {"parameters", params_json(r.params)},
         {"grid",
          {{"base_size", r.base_size},
           {"finest_size", r.finest_size},
           {"diagonal", r.diagonal},
           {"cells_on_input_per_level", r.cells_per_level},
           {"thin_part_cells", r.thin_part_cells},
           {"cells_excluded_for_manifoldness", r.manifold_fixes}}},
         {"volumes",
          {{"free_volumes", r.volumes.free_volumes},
           {"enclosed_volumes", r.volumes.enclosed_volumes},
           {"largest_enclosed_volume", r.volumes.largest_enclosed},
           {"input_encloses_a_volume", r.volumes.encloses_volume},
           {"chosen_volume", r.volumes.chosen_volume},
           {"gap_closure", r.volumes.gap_closure}}},
         {"leak", leak_json(r.leak)},
         {"contact_prevention",
          {{"rules", r.contact.rules},
           {"floor", r.contact.floor},
           {"unresolved_cells", r.contact.unresolved_cells},
           {"unresolved_locations", r.contact.unresolved_locations},
           {"separate_bodies", r.contact.separate_bodies}}},
         {"control_sizes", sizes},
         {"projection",
          {{"nodes_held_back", r.nodes_held_back},
           {"nodes_held_back_far_first_fit", r.nodes_held_back_far_first_fit},
           {"triangles_far_first_fit", r.triangles_far_first_fit},
           {"nodes", r.nodes_projected},
           {"triangles_before_coarsening", r.triangles_before_coarsening}}},
         {"two_sided",
          {{"area_percent", 100 * r.two_sided.area_fraction},
           {"nodes", r.two_sided.nodes},
           {"nodes_raised", r.two_sided.nodes_raised},
           {"openings", r.two_sided.openings},
           {"largest_opening_centre", r.two_sided.largest_opening_centre},
           {"largest_opening_width", r.two_sided.largest_opening_width},
           {"suggested_gap_closure", r.two_sided.suggested_gap_closure}}},
         {"quality", quality_json(r.quality, r.params)},
         {"output", diag_json(r.output)},
         {"distance_output_to_input", dist_json(r.output_to_input)},
         {"distance_input_to_output", dist_json(r.input_to_output)},
         {"distance_sharp_edges_to_output", dist_json(r.sharp_edges_to_output)},
         {"stages", stages},
         {"total_seconds", r.total_seconds}};
  // New keys only, and only when the caller set them: older readers see the report unchanged.
  if (!r.source.tool_version.empty()) j["vdbwrap_version"] = r.source.tool_version;
  if (!r.source.file_name.empty() || !r.source.parts.empty()) {
    j["source"] = source_json(r.source);
  }
  return j.dump(indent);
}

// Here, not in source.cpp: the fuzzers' API library links the report without the rest.
nlohmann::json source_json(const WrapReport::Source& src) {
  nlohmann::json parts = nlohmann::json::array();
  for (const auto& [name, triangles] : src.parts) parts.push_back({{"name", name}, {"triangles", triangles}});
  nlohmann::json j = {{"file_name", src.file_name}, {"parts", parts}};
  if (!src.notes.empty()) j["notes"] = src.notes;
  return j;
}

}  // namespace vdbwrap
