// The mesh the repair works on and the small helpers every step shares. Triangle ids stay
// valid from the first step to the last: a deleted triangle keeps its slot
// (local_repair::dead_triangle), new triangles are appended.
#pragma once
#include <cstdint>
#include <string>
#include <unordered_set>
#include <vector>

#include "check/intersections.h"
#include "repair/regions.h"
#include "vdbwrap/mesh.h"
#include "vdbwrap/progress.h"

namespace vdbwrap::local_repair {

inline bool touches(const check::TrianglePair& p, const std::unordered_set<uint32_t>& set) {
  return set.count(p.a) || set.count(p.b);
}

// The mesh being repaired. Deleted triangles keep their slot (local_repair::dead_triangle).
struct Work {
  std::vector<Vec3> points, origin;  // origin: where each vertex started (new ones: where made)
  std::vector<Tri> tris;
  std::vector<int32_t> part;               // per triangle
  std::vector<int32_t> region_of;          // per triangle: the input region it belongs to, or -1
  std::vector<uint8_t> touched;            // per triangle: changed by the repair
  std::vector<check::TrianglePair> pairs;  // current intersecting pairs (a < b), sorted

  // Sets the pairs, sorted, without the (t, t) entries of degenerate triangles.
  void set_pairs(std::vector<check::TrianglePair> p);
  // Replaces the pairs touching `changed` by `found` (the pairs found again around them).
  void update_pairs(const std::unordered_set<uint32_t>& changed, const std::vector<check::TrianglePair>& found);
};

// Exact weld (bit-identical points merge), parts per triangle.
Work make_work(const Mesh& input, bool float_coordinates);

// The shortest edge of positive length (0 when there is none).
double shortest_edge(const Work& w);

// The triangles still there (not dead).
std::vector<Tri> live_triangles(const Work& w);

// The live triangles and the points they use, points in their order (an untouched welded
// mesh comes out as it went in).
Mesh compact(const Work& w, const Mesh& input);

// The pairs with a triangle of input region `only` (all pairs when it is negative).
std::vector<check::TrianglePair> pairs_of_region(const Work& w, int32_t only);

// Per input region (w.region_of): 1 when none of its triangles is in an intersecting pair.
std::vector<uint8_t> clean_regions(const Work& w, size_t regions_found);

// Splits edge (u, v) at new point m in every live triangle on it: each keeps its slot as the
// half at u and appends the half at v (same orientation, part and region). `vf` (triangles
// per vertex) follows; the triangles cut and appended are added to `changed`, in pairs.
void split_edge(Work& w, std::vector<std::vector<uint32_t>>& vf, uint32_t u, uint32_t v, uint32_t m,
                std::vector<uint32_t>& changed);

// Throws Error(Cancelled) when the caller asked to stop: every step checks between rounds.
void check_cancel(ProgressSink* progress);
// Before each round of a repeated step: cancellation, then the progress (round of rounds and
// the intersecting pairs left).
void start_round(ProgressSink* progress, const std::string& step, int round, int rounds, size_t pairs_left);

// The repair's trace on stderr (VDBWRAP_REPAIR_DEBUG, only in a build with
// VDBWRAP_DEBUG_DUMPS: common/debug_switch.h).
bool debug_enabled();

}  // namespace vdbwrap::local_repair
