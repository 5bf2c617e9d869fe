// The figures of the repair report read off the finished repair: which step fixed each input
// region, the regions left, and how far output and input lie apart.
#pragma once
#include <cstdint>
#include <memory>
#include <vector>

#include "repair/unite.h"
#include "repair/work.h"
#include "vdbwrap/repair.h"

namespace vdbwrap::local_repair {

// Counts each input region once: fixed by the union (`by_union`), by part 1 (clean after it),
// by part 2 (clean at the end) or left unfixed.
void count_fixed_regions(const Work& w, const std::vector<uint8_t>& by_union,
                         const std::vector<uint8_t>& clean_after_local, RepairReport& report);

// The regions still intersecting: their size and where they are.
std::vector<RepairRegion> describe_regions(const Work& w);

// The two-sided sampled distance between the input (`input_tris` on w.origin) and the
// output, and the deviation as a share of the diagonal. Input surface inside one of
// `solids` (bodies united) is not measured.
void measure_deviation(const Work& w, const std::vector<Tri>& input_tris,
                       const std::vector<std::unique_ptr<SolidTest>>& solids, RepairReport& report);

}  // namespace vdbwrap::local_repair
