#include "grid/adaptive_grid.h"

#include <mutex>

namespace vdbwrap::grid {

namespace {
std::once_flag vdb_init;
}

AdaptiveGrid::AdaptiveGrid(const Vec3& origin, double base_size, int levels, const Coord& dims0)
    : origin_(origin), base_size_(base_size), levels_(levels), dims0_(dims0) {
  std::call_once(vdb_init, [] { openvdb::initialize(); });
  for (int l = 0; l <= levels; ++l)
    grids_.push_back(openvdb::Int32Grid::create(l == 0 ? int32_t(kFree) : int32_t(kAbsent)));
}

int32_t AdaptiveGrid::get(int level, const Coord& c) const { return grids_[level]->tree().getValue(c); }

void AdaptiveGrid::set(int level, const Coord& c, int32_t value) { grids_[level]->tree().setValue(c, value); }

}  // namespace vdbwrap::grid
