// The narrow phase of the pair search: do two triangles share points other than their common
// vertices and edge? The proofs in the plane settle most pairs in doubles; the exact
// predicates decide the rest.
#pragma once
#include <array>
#include <vector>

#include "check/exact_kernel.h"

namespace vdbwrap::check::pair_search {

// Triangles intersect when they share points other than their common vertices/edge; a
// triangle with a corner twice (degenerate) meets anything.
// `p`: any container of points indexed by the triangles' vertices.
template <typename Points>
bool triangles_intersect(const Points& p, const Tri& x, const Tri& y, bool use_proofs_2d = true);

extern template bool triangles_intersect(const std::vector<P3>&, const Tri&, const Tri&, bool);
extern template bool triangles_intersect(const std::array<P3, 6>&, const Tri&, const Tri&, bool);

}  // namespace vdbwrap::check::pair_search
