// Stage 2b: the inside/outside flood fill over the whole padded box, and the choice of volume.
#pragma once
#include <functional>
#include <vector>

#include "grid/adaptive_grid.h"
#include "vdbwrap/errors.h"
#include "vdbwrap/params.h"
#include "vdbwrap/progress.h"

namespace vdbwrap::grid {

struct Components {
  int32_t first_label = 1;
  std::vector<double> volume;            // per component (index label - first_label), in fine cells
  std::vector<uint8_t> touches_outside;  // reaches the padded box's boundary
  std::vector<uint8_t> holds_level0;     // has a level-0 (base size) cell
  size_t count() const { return volume.size(); }
};

// Labels the face-connected components of the leaves whose value satisfies `member`,
// writing labels first_label, first_label+1, ... into them. A component that reaches the
// box boundary is labelled first (so with first_label 1 the outside volume gets label 1).
Components label_components(AdaptiveGrid& grid, const std::function<bool(int32_t)>& member, int32_t first_label,
                            ProgressSink* progress = nullptr);

// The label of the largest component that does not reach the box boundary and holds a base
// cell or at least `min_volume` fine cells, or -1.
int32_t largest_enclosed_label(const Components& components, double min_volume = 0);

// Labels the free cells and returns the label of the chosen volume: the outside (1), or the
// largest component that does not reach the boundary. Throws Error(WrapFailed) when the
// input encloses no volume at this cell size and `inside` is asked for.
int32_t choose_volume(AdaptiveGrid& grid, VolumeChoice choice, Components& components, ProgressSink* progress);

}  // namespace vdbwrap::grid
