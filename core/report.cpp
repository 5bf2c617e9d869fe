// JSON forms of the report, the diagnostics and the distances (the CLI's --report and the
// server's job report share them).
#include <nlohmann/json.hpp>

#include <charconv>
#include <cmath>
#include <sstream>

#include "vdbwrap/wrap.h"

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
              {"mean_percent_of_diagonal", 100 * s.mean / dg},
              {"p95_percent_of_diagonal", 100 * s.p95 / dg},
              {"max_percent_of_diagonal", 100 * s.max / dg}};
}

json params_json(const WrapParams& p) {
  return json{{"base_size", p.base_size.to_string()},
              {"levels", p.levels},
              {"feature_angle_deg", p.feature_angle_deg},
              {"volume", p.volume == VolumeChoice::Outside ? "outside" : "inside"},
              {"threads", p.threads},
              {"refine_max_triangles", p.refine_max_triangles},
              {"refine_normal_spread_deg", p.refine_normal_spread_deg},
              {"refine_at_features", p.refine_at_features},
              {"weld_tolerance", p.weld_tolerance},
              {"surface_offset", p.surface_offset},
              {"presmooth_iterations", p.presmooth_iterations},
              {"snap_features", p.snap_features},
              {"corner_angle_deg", p.corner_angle_deg},
              {"float_coordinates", p.float_coordinates}};
}
}  // namespace

Length Length::parse(const std::string& text) {
  std::string t = text;
  while (!t.empty() && std::isspace(static_cast<unsigned char>(t.back()))) t.pop_back();
  Length len;
  len.percent_of_diagonal = !t.empty() && t.back() == '%';
  if (len.percent_of_diagonal) t.pop_back();
  double v = 0;
  auto [end, ec] = std::from_chars(t.data(), t.data() + t.size(), v);
  if (t.empty() || ec != std::errc() || end != t.data() + t.size() || !std::isfinite(v) || v <= 0)
    throw Error(ErrorKind::InvalidArgument, "'" + text + "' is not a positive length (model units, or N% of the diagonal)");
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
  for (const auto& s : r.stages) stages.push_back({{"name", s.name}, {"seconds", s.seconds}, {"peak_memory_mb", s.peak_memory_mb}});
  json j{{"input", diag_json(r.input)},
         {"features",
          {{"sharp_edges", r.features.sharp_edges},
           {"boundary_edges", r.features.boundary_edges},
           {"nonmanifold_edges", r.features.nonmanifold_edges},
           {"intersection_segments", r.features.intersection_segments},
           {"curves", r.features.curves},
           {"corners", r.features.corners},
           {"curves_captured", r.features.curves_captured},
           {"corners_captured", r.features.corners_captured},
           {"nodes_snapped", r.features.nodes_snapped}}},
         {"parameters", params_json(r.params)},
         {"grid",
          {{"base_size", r.base_size},
           {"finest_size", r.finest_size},
           {"diagonal", r.diagonal},
           {"cells_on_input_per_level", r.cells_per_level},
           {"cells_excluded_for_manifoldness", r.manifold_fixes}}},
         {"projection", {{"nodes_held_back", r.nodes_held_back}}},
         {"output", diag_json(r.output)},
         {"distance_output_to_input", dist_json(r.output_to_input)},
         {"distance_input_to_output", dist_json(r.input_to_output)},
         {"distance_sharp_edges_to_output", dist_json(r.sharp_edges_to_output)},
         {"stages", stages},
         {"total_seconds", r.total_seconds}};
  return j.dump(indent);
}

}  // namespace vdbwrap
