// JSON form of the repair report (the CLI's --report; the server can send the same).
#include <nlohmann/json.hpp>

#include "vdbwrap/repair.h"

namespace vdbwrap {

std::string to_json(const RepairReport& r, int indent) {
  using nlohmann::json;
  const RepairParams& p = r.params;
  json params{{"local_iterations", p.local_iterations},
              {"alpha", p.alpha},
              {"beta", p.beta},
              {"delta", p.delta},
              {"gamma", p.gamma},
              {"area_ratio", p.area_ratio},
              {"accuracy", p.accuracy},
              {"refill_iterations", p.refill_iterations},
              {"refill_area_ratio", p.refill_area_ratio},
              {"fair", p.fair},
              {"max_deviation", p.max_deviation.to_string()},
              {"remove_small_pieces", p.remove_small_pieces},
              {"small_piece_triangles", p.small_piece_triangles},
              {"small_piece_area", p.small_piece_area},
              {"float_coordinates", p.float_coordinates},
              {"threads", p.threads}};
  json unfixed = json::array();
  for (const RepairRegion& u : r.unfixed)
    unfixed.push_back({{"triangles", u.triangles},
                       {"pairs", u.pairs},
                       {"center", u.center},
                       {"bbox_min", u.bbox_min},
                       {"bbox_max", u.bbox_max}});
  json stages = json::array();
  for (const StageStats& s : r.stages)
    stages.push_back({{"name", s.name}, {"seconds", s.seconds}, {"peak_memory_mb", s.peak_memory_mb}});
  json out{
      {"params", params},
      {"accuracy_used", r.accuracy},
      {"max_deviation_used", r.max_deviation},
      {"diagonal", r.diagonal},
      {"all_fixed", r.all_fixed()},
      {"regions",
       {{"found", r.regions_found},
        {"fixed_by_local_operations", r.fixed_by_local},
        {"fixed_by_refill", r.fixed_by_refill},
        {"fixed_by_union", r.fixed_by_union},
        {"left_unfixed", r.left_unfixed}}},
      {"unfixed_regions", unfixed},
      {"local_operations",
       {{"iterations", r.local_iterations_run},
        {"vertex_shifts", r.vertex_shifts},
        {"triangle_shifts", r.triangle_shifts},
        {"untangles", r.untangles}}},
      {"refill", {{"iterations", r.refill_iterations_run}, {"refills", r.refills}, {"failures", r.refill_failures}}},
      {"cracks_stitched", r.cracks_stitched},
      {"bodies_united", r.bodies_united},
      {"refined", {{"regions", r.regions_refined}, {"triangles_added", r.refined_triangles_added}}},
      {"refusals", r.refusals},
      {"small_pieces_removed", {{"pieces", r.pieces_removed}, {"triangles", r.piece_triangles_removed}}},
      {"before", json::parse(to_json(r.before))},
      {"after", json::parse(to_json(r.after))},
      {"distance_output_to_input", json::parse(to_json(r.output_to_input))},
      {"distance_input_to_output", json::parse(to_json(r.input_to_output))},
      {"max_deviation_fraction_of_diagonal", r.deviation},
      {"stages", stages},
      {"total_seconds", r.total_seconds}};
  return out.dump(indent);
}

}  // namespace vdbwrap
