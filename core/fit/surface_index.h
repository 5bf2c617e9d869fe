// Moved to mesh/surface_index.h (shared by every stage); kept for code written before the move.
#pragma once
#include "mesh/surface_index.h"

namespace vdbwrap::fit {
using mesh::SurfaceIndex;
}  // namespace vdbwrap::fit
