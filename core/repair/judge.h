// Keep or undo: the rule every change of the repair passes. Changes (one per region) are
// applied together as trials, then judged one by one against the intersecting pairs.
#pragma once
#include <cstddef>
#include <cstdint>
#include <functional>
#include <unordered_set>
#include <vector>

#include "check/intersections.h"
#include "repair/work.h"

namespace vdbwrap::local_repair {

// One trial: a change per region applied at once, judged per region.
struct Trial {
  std::vector<uint32_t> watched;                  // triangles whose pairs decide (region + changed)
  std::vector<uint32_t> changed;                  // triangles the change made or moved
  std::vector<uint32_t> gone;                     // triangles it deleted (their old pairs go with them)
  std::unordered_set<uint32_t> partners_allowed;  // refill: the outside triangles it may still meet
  bool refill = false;
  bool accepted = true;
};

// Judges every trial: the intersecting pairs around its triangles must drop in number, none
// may be new (refills: new triangles may only meet what the region met before), and no
// triangle may become degenerate. Returns the pairs found around the accepted trials'
// changed triangles. `undo(i)` takes trial i back; rejected trials are undone here.
std::vector<check::TrianglePair> judge(Work& w, std::vector<Trial>& trials,
                                       const std::unordered_set<uint32_t>& degenerate_before,
                                       const std::function<void(size_t)>& undo);

}  // namespace vdbwrap::local_repair
