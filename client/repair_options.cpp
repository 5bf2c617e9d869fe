#include "repair_options.h"

namespace vdbwrap::cli {

void RepairOptions::add_to(CLI::App* cmd, bool with_threads) {
  auto add = [&](CLI::Option* o) {
    options_.push_back(o);
    return o->group(with_threads ? "Repair" : "Repair (with --repair)");
  };
  add(cmd->add_option("--max-deviation", max_deviation_,
                      "How far any vertex or refill may end from the input: model units (0.05) or percent of the "
                      "bounding-box diagonal (0.5%)"))
      ->capture_default_str();
  add(cmd->add_option("--local-iterations", p_.local_iterations, "Iterations of part 1 (vertex/triangle shifts)"))
      ->capture_default_str()
      ->check(CLI::Range(0, 1000));
  add(cmd->add_option("--alpha", p_.alpha, "Vertex shift: clearance past the crossing, share of the gap"))
      ->capture_default_str();
  add(cmd->add_option("--beta", p_.beta, "Vertex shift: alpha x gap must stay under beta x the longest region edge"))
      ->capture_default_str();
  add(cmd->add_option("--delta", p_.delta, "Triangle shift: eps_move = delta x accuracy ..."))->capture_default_str();
  add(cmd->add_option("--gamma", p_.gamma, "... capped at gamma x the longest region edge"))->capture_default_str();
  add(cmd->add_option("--area-ratio", p_.area_ratio,
                      "eps_S: least min/max area ratio of the triangles a local operation changes"))
      ->capture_default_str();
  add(cmd->add_option("--accuracy", p_.accuracy, "Model accuracy in model units (0: 0.05 x the shortest edge)"))
      ->capture_default_str();
  add(cmd->add_option("--refill-iterations", p_.refill_iterations, "Iterations of part 2 (remove and refill)"))
      ->capture_default_str()
      ->check(CLI::Range(0, 100));
  add(cmd->add_option("--refill-area-ratio", p_.refill_area_ratio,
                      "Least min/max area ratio of a removed region and its refill"))
      ->capture_default_str();
  add(cmd->add_flag("--no-fair", no_fair_, "Refine refills but do not fair them"));
  add(cmd->add_flag("--keep-small-pieces", keep_pieces_, "Do not delete small pieces the repair leaves behind"));
  add(cmd->add_flag(
      "--no-unite", no_unite_,
      "Never unite closed bodies that still cross (each body stays a separate solid; their crossings may be left)"));
  add(cmd->add_option("--small-piece-triangles", p_.small_piece_triangles,
                      "A leftover piece is small with at most this many triangles ..."))
      ->capture_default_str();
  add(cmd->add_option("--small-piece-area", p_.small_piece_area, "... and at most this fraction of the total area"))
      ->capture_default_str();
  if (with_threads)
    add(cmd->add_option("--threads", p_.threads, "Worker threads (0: all cores)"))
        ->capture_default_str()
        ->check(CLI::NonNegativeNumber);
}

RepairParams RepairOptions::resolve() const {
  RepairParams p = p_;
  try {
    p.max_deviation = Length::parse(max_deviation_);
  } catch (const Error& e) {
    throw Error(e.kind(), std::string("--max-deviation: ") + e.what());
  }
  p.fair = !no_fair_;
  p.remove_small_pieces = !keep_pieces_;
  p.unite_bodies = !no_unite_;
  return p;
}

std::vector<std::string> RepairOptions::given() const {
  std::vector<std::string> out;
  for (const CLI::Option* o : options_)
    if (o->count() > 0) out.push_back(o->get_name());
  return out;
}

}  // namespace vdbwrap::cli
