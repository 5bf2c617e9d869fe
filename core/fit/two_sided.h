// Two-sided sheets: where the chosen volume lies on both sides of an input surface (an open
// sheet, a scan whose holes let the outside in), the wrap has two sheets that project onto the
// same input, each to its own side, a small offset off it. Wrap triangles are chords of the
// input, so on a curved or creased sheet one sheet's chords dip through the other sheet when
// the offset is small; pulling those nodes back toward the lattice (the validity loop's way)
// leaves a voxel staircase. Raising their offset instead, a few times, keeps them on the input.
#pragma once
#include <cmath>
#include <cstdint>
#include <unordered_map>
#include <vector>

#include <tbb/parallel_for.h>

#include "common/grid_key.h"
#include "common/vec.h"
#include "vdbwrap/mesh.h"

namespace vdbwrap::fit {

struct TwoSidedParams {
  double cell = 1;          // the finest cell: feet of both sides this near make a place two-sided
  double offset = 0;        // the projection's offset off the input
  double raise_factor = 2;  // each raise multiplies the offset by this
  int max_raises = 6;       // then the node is pulled back toward the lattice as before
  // A node's side is clear when its way off the input is at least this cosine off the plane of
  // the input triangle it projects to (around convex edges and sheet borders it may not be).
  double clear_side_cos = 0.5;
};

struct TwoSidedStats {
  size_t nodes = 0;         // wrap nodes on a two-sided place
  size_t nodes_raised = 0;  // of those, nodes whose offset was raised to keep the wrap valid
  // Per input triangle: bit 1, a node projects to it from the side its normal points to; bit 2,
  // from the other side. Grown to the largest triangle hit.
  std::vector<uint8_t> triangle_sides;
  // Per cell of the feet, the ways off the input of the nodes of each side, summed.
  struct Ways {
    Vec3 off[2] = {{0, 0, 0}, {0, 0, 0}};
  };
  std::unordered_map<GridKey, Ways, GridKeyHash> cell_ways;
  double inv_cell = 1;

  // Whether the feet within a cell of p (the 27 cells around) come from both sides, their
  // ways off the input opposed. The side is judged against the normal of the triangle a node
  // projects to; where noise folds a closed surface's triangles over, nodes all outside
  // project to faces turned either way, but their ways off stay one way.
  bool opposed_near(const Vec3& p) const {
    Vec3 a{0, 0, 0}, b{0, 0, 0};
    for_each_cell_around(grid_key(p, inv_cell), [&](const GridKey& c) {
      auto it = cell_ways.find(c);
      if (it != cell_ways.end()) a = a + it->second.off[0], b = b + it->second.off[1];
    });
    return dot(a, b) < 0;
  }
};

class TwoSidedSheets {
 public:
  TwoSidedSheets(size_t nodes, const TwoSidedParams& p)
      : p_(p),
        foot_(nodes),
        away_(nodes),
        triangle_(nodes, UINT32_MAX),
        side_(nodes, 0),
        facing_(nodes, 0),
        raises_(nodes, 0),
        two_(nodes, 0) {}

  // Node i projects to `foot` on input triangle `triangle` (unit normal `normal`), its target
  // `away` (unit, on the side of its lattice position) times the offset off it; `facing`: the
  // wrap's normal at the node (its lattice surface's). Per node: thread safe.
  void record(size_t i, const Vec3& foot, uint32_t triangle, const Vec3& normal, const Vec3& away, const Vec3& facing) {
    foot_[i] = foot;
    away_[i] = away;
    triangle_[i] = triangle;
    // Off a triangle's inside the way off is its normal; from an edge or corner it may lean.
    const double s = dot(away, normal);
    side_[i] = s > p_.clear_side_cos ? 1 : s < -p_.clear_side_cos ? 2 : 0;
    const double f = dot(away, facing);
    facing_[i] = f > 0 ? 1 : f < 0 ? 2 : 0;
  }
  // The node keeps no projected target (it stays at its lattice position, or was snapped).
  void forget(size_t i) { triangle_[i] = UINT32_MAX, side_[i] = 0; }

  // Marks the nodes whose foot has a foot of the other side within a cell (the nodes the
  // validity loop may raise), and gathers the report's account. Call once, after every
  // record().
  void classify() {
    stats_.inv_cell = 1.0 / p_.cell;
    for (size_t i = 0; i < foot_.size(); ++i)
      if (side_[i]) sides_[grid_key(foot_[i], stats_.inv_cell)] |= side_[i];
    for (size_t i = 0; i < foot_.size(); ++i)
      if (side_[i]) two_[i] = (sides_near(foot_[i]) & (3 - side_[i])) != 0;
    // The report's account is of second sheets only. A sheet of the wrap faces one way
    // relative to its way off the input on every side (into the chosen volume); a node whose
    // way off is against its sheet's facing lies under the input (a sheet passing through a
    // rough surface's bumps, or between overlapping pieces), where the triangle's side says
    // nothing of a second sheet. (Raising such nodes still helps the validity loop: without
    // it box.STL's p95 rose by a fifth.)
    size_t with = 0, against = 0;
    for (size_t i = 0; i < foot_.size(); ++i)
      if (side_[i]) with += facing_[i] == 1, against += facing_[i] == 2;
    const uint8_t under = with >= against ? 2 : 1;
    auto side_of_sheet = [&](size_t i) { return facing_[i] == under ? 0 : side_[i]; };
    auto& cells = stats_.cell_ways;
    for (size_t i = 0; i < foot_.size(); ++i) {
      const uint8_t side = side_of_sheet(i);
      if (!side) continue;
      Vec3& off = cells[grid_key(foot_[i], stats_.inv_cell)].off[side - 1];
      off = off + away_[i];
      if (triangle_[i] >= stats_.triangle_sides.size()) stats_.triangle_sides.resize(triangle_[i] + 1, 0);
      stats_.triangle_sides[triangle_[i]] |= side;
    }
    for (size_t i = 0; i < foot_.size(); ++i)
      if (side_of_sheet(i)) stats_.nodes += stats_.opposed_near(foot_[i]);
  }
  bool two_sided(size_t i) const { return two_[i] != 0; }
  // Do feet of both sides lie within a cell of most of these points? (After classify().)
  bool two_sided_along(const std::vector<Vec3>& points) const {
    size_t both = 0;
    for (const Vec3& q : points) both += sides_near(q) == 3;
    return 2 * both > points.size();
  }

  // A two-sided node that offends: its next target, farther off its foot, when it has raises
  // left (false: pull it back toward the lattice as usual).
  bool raise(size_t i, Vec3& target) {
    if (!two_[i] || triangle_[i] == UINT32_MAX || raises_[i] >= p_.max_raises) return false;
    if (raises_[i]++ == 0) ++stats_.nodes_raised;
    target = foot_[i] + away_[i] * (p_.offset * std::pow(p_.raise_factor, raises_[i]));
    return true;
  }

  TwoSidedStats take_stats() { return std::move(stats_); }

 private:
  // The sides of the feet in the cells around p.
  uint8_t sides_near(const Vec3& p) const {
    uint8_t bits = 0;
    for_each_cell_around(grid_key(p, stats_.inv_cell), [&](const GridKey& c) {
      auto it = sides_.find(c);
      if (it != sides_.end()) bits |= it->second;
    });
    return bits;
  }

  TwoSidedParams p_;
  std::vector<Vec3> foot_, away_;
  std::vector<uint32_t> triangle_;
  std::vector<uint8_t> side_, facing_, raises_, two_;
  std::unordered_map<GridKey, uint8_t, GridKeyHash> sides_;  // the sides' bits per cell of the feet
  TwoSidedStats stats_;
};

// The share of the input's area wrapped from both sides: triangles that nodes of both sides
// project to, or whose centroid has feet of both sides within a cell, their ways off opposed.
inline double two_sided_area_fraction(const TwoSidedStats& s, const std::vector<Vec3>& points,
                                      const std::vector<Tri>& triangles) {
  // The lookups in parallel (seconds on millions of triangles), the sums in order: the same
  // figure on any number of threads.
  std::vector<uint8_t> both_sides(triangles.size());
  tbb::parallel_for(tbb::blocked_range<size_t>(0, triangles.size(), 4096), [&](const tbb::blocked_range<size_t>& r) {
    for (size_t t = r.begin(); t != r.end(); ++t) {
      const Vec3 &a = points[triangles[t][0]], &b = points[triangles[t][1]], &c = points[triangles[t][2]];
      both_sides[t] =
          (t < s.triangle_sides.size() && s.triangle_sides[t] == 3) || s.opposed_near((a + b + c) * (1.0 / 3.0));
    }
  });
  double both = 0, all = 0;
  for (size_t t = 0; t < triangles.size(); ++t) {
    const Vec3 &a = points[triangles[t][0]], &b = points[triangles[t][1]], &c = points[triangles[t][2]];
    const double area = 0.5 * norm(cross(b - a, c - a));
    all += area;
    if (both_sides[t]) both += area;
  }
  return all > 0 ? both / all : 0.0;
}

}  // namespace vdbwrap::fit
