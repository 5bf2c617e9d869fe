// Stage 2a, user sizing: control volumes, per-part cell sizes and contact prevention, turned
// into the grid level each asks for (level l has cells of base / 2^l).
#pragma once
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "vdbwrap/mesh.h"
#include "vdbwrap/params.h"

namespace vdbwrap::grid {

// Deepest level the grid may have: beyond it the fine lattice overflows and memory explodes.
inline constexpr int kMaxGridLevels = 10;

struct SizeControls {
  struct Region {
    ControlVolume shape;  // in the local frame
    int level = 0;
  };
  std::vector<Region> regions;
  std::vector<int> part_level;  // per part of the input: level wanted where it passes (0: none)

  // Contact prevention: parts that must stay apart, refined down to contact_level.
  std::vector<std::vector<uint8_t>> conflict;  // part x part
  std::vector<uint8_t> part_in_contact_rule;   // per part
  int contact_level = 0;
  double contact_floor = 0;

  int criteria_levels = 0;  // the user's --levels: depth of the refinement criteria
  int max_level = 0;        // depth of the grid: the deepest level anything asks for

  std::vector<std::pair<std::string, double>> described;  // what applies, with its size in model units

  bool contact() const { return contact_level > 0 && !part_in_contact_rule.empty(); }
  bool conflicting(int32_t p, int32_t q) const { return conflict[size_t(p)][size_t(q)] != 0; }
};

// Level whose cells are at most `size` (base / 2^level <= size), at least 0.
int level_for_size(double base, double size);

// Resolves the parameters against the input: sizes to levels, part names to part indices,
// control volumes moved into the local frame (local = world - origin). Throws
// Error(InvalidArgument) for unknown part names or sizes needing more than kMaxGridLevels.
struct SizeRequests {
  int levels = 1;  // the refinement criteria's depth below the base size
  std::vector<ControlVolume> control_volumes;
  std::vector<PartSize> part_sizes;
  std::vector<ContactRule> contact_prevention;
  std::optional<Length> contact_floor;  // default: the finest cell / 8
};
SizeControls make_size_controls(const SizeRequests& params, const Mesh& local_mesh, const Vec3& origin, double diagonal,
                                double base);

// Signed distance from p to a control volume's solid (negative or zero inside).
double control_volume_distance(const ControlVolume& cv, const Vec3& p);

// Deepest level any control region asks for in the cell [lo, lo + h]^3.
int region_level(const SizeControls& controls, const Vec3& lo, double h);

}  // namespace vdbwrap::grid
