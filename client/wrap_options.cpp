#include "wrap_options.h"

#ifdef VDBWRAP_WITH_REMOTE
#include "params_file.h"
#endif

namespace vdbwrap::cli {

template <typename T>
CLI::Option* WrapOptions::bind(CLI::App* cmd, const std::string& name, T& value, const std::string& help,
                               std::function<void(WrapParams&)> apply) {
  CLI::Option* opt = cmd->add_option(name, value, help);
  bindings_.push_back({opt, std::move(apply)});
  return opt;
}

void WrapOptions::add_to(CLI::App* cmd, const std::string& threads_help) {
  // Added group by group: the help lists the groups in the order they first appear.
  bind(cmd, "--base-size", base_size_,
       "Level-0 cell edge: model units (0.5) or percent of the bounding-box diagonal (1%)",
       [this](WrapParams& p) { p.base_size = Length::parse(base_size_); })
      ->capture_default_str()
      ->group("Size");
  bind(cmd, "--levels", cli_.levels,
       "Most 2x2x2 refinement levels below the base size by the refinement criteria (0-6)",
       [this](WrapParams& p) { p.levels = cli_.levels; })
      ->capture_default_str()
      ->check(CLI::Range(0, 6))
      ->group("Size");
  bind(cmd, "--thin-part-levels", cli_.thin_part_levels,
       "Refine parts of the input thinner than half a cell across (rods, narrow bars) up to this many levels "
       "below --levels, so their wrap is not made of slivers (0-3; 0: off; closed pieces only)",
       [this](WrapParams& p) { p.thin_part_levels = cli_.thin_part_levels; })
      ->capture_default_str()
      ->check(CLI::Range(0, 3))
      ->group("Size");
  bind(cmd, "--refine-triangles", cli_.refine_max_triangles, "Refine a cell holding more input triangles than this",
       [this](WrapParams& p) { p.refine_max_triangles = cli_.refine_max_triangles; })
      ->capture_default_str()
      ->check(CLI::PositiveNumber)
      ->group("Size");
  bind(cmd, "--refine-normal-spread", cli_.refine_normal_spread_deg,
       "Refine a cell whose input normals spread more than this many degrees",
       [this](WrapParams& p) { p.refine_normal_spread_deg = cli_.refine_normal_spread_deg; })
      ->capture_default_str()
      ->group("Size");
  CLI::Option* fc =
      cmd->add_flag("--refine-far-cells,!--no-refine-far-cells", refine_far_cells_,
                    "Refine a cell the input passes through when a point of its boundary lies more than a "
                    "base cell from the input there (the wrap's held-back nodes stay within a base cell)")
          ->group("Size");
  bindings_.push_back({fc, [this](WrapParams& p) { p.refine_far_cells = refine_far_cells_; }});
  CLI::Option* hb =
      cmd->add_flag("--refine-where-far,--refine-held-back,!--no-refine-where-far,!--no-refine-held-back",
                    refine_where_far_,
                    "Where the projection left the wrap over a base cell from the input (held-back nodes, faces "
                    "bridging a concave crease), refine the cells around the far parts to the finest level and fit "
                    "again (the outside volume; on by default)")
          ->group("Size");
  bindings_.push_back({hb, [this](WrapParams& p) { p.refine_where_far = refine_where_far_; }});
  bind(cmd, "--volume", volume_,
       "Volume to wrap: outside (around the input), inside (the largest volume it encloses), or the volume(s) "
       "holding seed points X,Y,Z (several separated by ';'); a seed point's volume reaching the outside is a leak",
       [this](WrapParams& p) { parse_volume_choice(volume_, p.volume, p.seed_points); })
      ->capture_default_str()
      ->group("Volume");
  bind(cmd, "--gap-closure", gap_closure_,
       "Openings narrower than this (model units or N%) do not let the volume through, whatever the cell size",
       [this](WrapParams& p) { p.gap_closure = Length::parse(gap_closure_); })
      ->group("Volume");
  bind(cmd, "--feature-angle", cli_.feature_angle_deg,
       "Angle in degrees between adjacent triangles' normals that makes their edge sharp",
       [this](WrapParams& p) { p.feature_angle_deg = cli_.feature_angle_deg; })
      ->capture_default_str()
      ->check(CLI::Range(0.0, 180.0))
      ->group("Features");
  bind(cmd, "--corner-angle", cli_.corner_angle_deg,
       "Degrees a feature curve must turn at a point to make a corner there",
       [this](WrapParams& p) { p.corner_angle_deg = cli_.corner_angle_deg; })
      ->capture_default_str()
      ->check(CLI::Range(0.0, 180.0))
      ->group("Features");
  CLI::Option* nf =
      cmd->add_flag("--no-features", no_features_, "Do not snap the wrap onto sharp edges, boundaries and corners")
          ->group("Features");
  bindings_.push_back({nf, [this](WrapParams& p) { p.snap_features = !no_features_; }});
  bind(cmd, "--control-volume", control_volumes_,
       "A region with its own cell size, repeatable: box:X0,Y0,Z0,X1,Y1,Z1:SIZE, sphere:X,Y,Z,R:SIZE, "
       "cylinder:X0,Y0,Z0,X1,Y1,Z1,R:SIZE, cone:X0,Y0,Z0,X1,Y1,Z1,R0,R1:SIZE",
       [this](WrapParams& p) {
         p.control_volumes.clear();
         for (const auto& s : control_volumes_) p.control_volumes.push_back(ControlVolume::parse(s));
       })
      ->take_all()
      ->group("Controls");
  bind(cmd, "--part-size", part_sizes_,
       "Cell size where an input part (STL solid, OBJ group) passes, repeatable: NAME=SIZE",
       [this](WrapParams& p) {
         p.part_sizes.clear();
         for (const auto& s : part_sizes_) p.part_sizes.push_back(PartSize::parse(s));
       })
      ->take_all()
      ->group("Controls");
  bind(cmd, "--contact-prevention", contact_rules_,
       "Keep parts apart, repeatable: hot,cold (every part of the list against every other) or a,b:c,d (group "
       "against group); cells between them are refined down to --contact-floor",
       [this](WrapParams& p) {
         p.contact_prevention.clear();
         for (const auto& s : contact_rules_) p.contact_prevention.push_back(ContactRule::parse(s));
       })
      ->take_all()
      ->group("Controls");
  bind(cmd, "--contact-floor", contact_floor_,
       "Smallest cell contact prevention may use (default: the finest cell / 8)",
       [this](WrapParams& p) { p.contact_floor = Length::parse(contact_floor_); })
      ->group("Controls");
  cmd->add_option("--params", params_file_,
                  "Parameter file (.json, .yaml, .yml) in the form of the API's WrapParameters message "
                  "(proto/vdbwrap/v1/jobs.proto); options on the command line override it")
      ->check(CLI::ExistingFile)
      ->group("Controls");
  bind(cmd, "--presmooth", cli_.presmooth_iterations,
       "Smoothing iterations of the voxel surface before projection (untangles the staircase)",
       [this](WrapParams& p) { p.presmooth_iterations = cli_.presmooth_iterations; })
      ->capture_default_str()
      ->check(CLI::Range(0, 100))
      ->group("Surface fit");
  bind(cmd, "--validity-rounds", cli_.validity_rounds,
       "Rounds of the projection's validity loop; intersections left after them go to the remeshing and the "
       "intersection repair (0: straight there)",
       [this](WrapParams& p) { p.validity_rounds = cli_.validity_rounds; })
      ->capture_default_str()
      ->check(CLI::Range(0, 100000))
      ->group("Surface fit");
  bind(cmd, "--coarsen-tolerance", cli_.coarsen_tolerance,
       "Merge nodes on flat parts while new triangles stay within this fraction of the base size of the input (0: off)",
       [this](WrapParams& p) { p.coarsen_tolerance = cli_.coarsen_tolerance; })
      ->capture_default_str()
      ->check(CLI::Range(0.0, 0.5))
      ->group("Surface fit");
  CLI::Option* nr =
      cmd->add_flag("--no-remesh", no_remesh_,
                    "Do not rebuild the bad regions of the wrap (slivers, tiny triangles, very poor normals); "
                    "the report's quality section still counts them")
          ->group("Surface fit");
  bindings_.push_back({nr, [this](WrapParams& p) { p.remesh = !no_remesh_; }});
  CLI::Option* sr =
      cmd->add_flag("--sliver-removal,!--no-sliver-removal", sliver_removal_,
                    "Remove the triangles with an angle under 10 degrees left after the rebuilds (edge flips, "
                    "collapses, tangential moves and splits of strips' rails, held near the input)")
          ->group("Surface fit");
  bindings_.push_back({sr, [this](WrapParams& p) { p.remove_slivers = sliver_removal_; }});
  CLI::Option* pr =
      cmd->add_flag("--proximity-refinement,!--no-proximity-refinement", proximity_refinement_,
                    "Where the wrap is still over 3/4 of a base cell from the input (nodes held back at coarse "
                    "cells, faces bridging concave corners), move nodes onto the input and split far edges, each "
                    "edit checked")
          ->group("Surface fit");
  bindings_.push_back({pr, [this](WrapParams& p) { p.proximity_refinement = proximity_refinement_; }});
  CLI::Option* ts =
      cmd->add_flag("--two-sided-sheets,!--no-two-sided-sheets", two_sided_sheets_,
                    "Where the volume lies on both sides of an input surface (open sheets, scans with holes), "
                    "move offending nodes farther off the input on their own side before pulling them back")
          ->group("Surface fit");
  bindings_.push_back({ts, [this](WrapParams& p) { p.two_sided_sheets = two_sided_sheets_; }});
  bind(cmd, "--threads", cli_.threads, threads_help, [this](WrapParams& p) { p.threads = cli_.threads; })
      ->capture_default_str()
      ->check(CLI::NonNegativeNumber)
      ->group("Run");
  CLI::Option* nd =
      cmd->add_flag("--no-distances", no_distances_,
                    "Skip the sampled distances of the report (timing runs: they cost as much as a stage)")
          ->group("Output");
  bindings_.push_back({nd, [this](WrapParams& p) { p.compute_distances = !no_distances_; }});
}

std::vector<std::string> WrapOptions::given() const {
  std::vector<std::string> out;
  if (!params_file_.empty()) out.push_back("--params");
  for (const Binding& b : bindings_)
    if (b.option->count() > 0) out.push_back(b.option->get_name());
  return out;
}

WrapParams WrapOptions::resolve() const {
  WrapParams p;
  if (!params_file_.empty()) {
#ifdef VDBWRAP_WITH_REMOTE
    p = api::read_params_file(params_file_);
#else
    throw Error(ErrorKind::InvalidArgument,
                "--params: this vdbwrap was built without the API library (VDBWRAP_BUILD_SERVICE=OFF)");
#endif
  }
  for (const Binding& b : bindings_) {
    if (b.option->count() == 0) continue;
    try {
      b.apply(p);
    } catch (const Error& e) {
      throw Error(e.kind(), b.option->get_name() + ": " + e.what());
    }
  }
  return p;
}

}  // namespace vdbwrap::cli
