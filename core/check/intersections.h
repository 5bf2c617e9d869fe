// Intersection tests on triangle sets, on CGAL's exact predicates.
#pragma once
#include <array>
#include <cstdint>
#include <vector>

#include "vdbwrap/mesh.h"

namespace vdbwrap {
struct EdgeTriangles;
}

namespace vdbwrap::check {

struct TrianglePair {
  uint32_t a, b;
};

// What a triangle set is, for the pair search's shortcuts (the answers are the same). An
// input: closed star-shaped parts (convex solids, CAD parts with fan caps) are looked for and
// their triangles' pairs skipped. A wrap: evenly sized triangles of surfaces that are hardly
// ever such parts, so the look, a walk over the whole set, is skipped.
enum class SoupKind { kInput, kWrap };

// Pairs of triangles of an indexed soup that share points other than their common
// vertices and edge (crossing, overlapping, folded onto each other). Triangles with
// repeated or collinear vertices are skipped (count those separately). `edges`: the
// triangles' edges when known (an input's star-shaped parts are found through them).
std::vector<TrianglePair> find_intersecting_pairs(const std::vector<Vec3>& points, const std::vector<Tri>& triangles,
                                                  SoupKind kind = SoupKind::kInput,
                                                  const EdgeTriangles* edges = nullptr);

// Intersecting pairs with at least one triangle in `subset` (the rest of the mesh is only
// tested against the subset). Same rules as find_intersecting_pairs; degenerate triangles
// in the subset are returned as a pair (t, t).
std::vector<TrianglePair> find_intersecting_pairs_with(const std::vector<Vec3>& points,
                                                       const std::vector<Tri>& triangles,
                                                       const std::vector<uint32_t>& subset);

// Per triangle: the number of the piece it belongs to when that piece is closed (up to holes,
// which are closed for the check) and star-shaped around its mean vertex, else UINT32_MAX.
// Two triangles of such a piece meet only at what they share, so the pair search skips their
// pairs; exposed for tests.
std::vector<uint32_t> star_shaped_pieces(const std::vector<Vec3>& points, const std::vector<Tri>& triangles);

// Triangles that intersect another or are degenerate, sorted, each once.
std::vector<uint32_t> intersecting_triangles(const std::vector<Vec3>& points, const std::vector<Tri>& triangles,
                                             SoupKind kind = SoupKind::kInput);

// The exact tests behind the functions above, for one pair / one triangle. use_proofs_2d =
// false skips the fast proofs in doubles that settle most pairs first (for tests: the answer
// must be the same).
bool triangle_pair_intersects(const std::vector<Vec3>& points, const Tri& a, const Tri& b, bool use_proofs_2d = true);
bool triangle_is_degenerate(const std::vector<Vec3>& points, const Tri& t);
// The same tests on corners given apart from a point list (a change being weighed before it is
// made); the indexes still tell which corners two triangles share, and shared ones must be equal.
using Corners = std::array<Vec3, 3>;
bool triangle_pair_intersects(const Corners& a_at, const Tri& a, const Corners& b_at, const Tri& b,
                              bool use_proofs_2d = true);
bool triangle_is_degenerate(const Corners& at, const Tri& t);

// Triangles (c, a, b) round vertex c, given by their corners after c in each one's own order
// (`corners`: (a, b) per triangle). True when they close one fan round c that lies unfolded as
// seen along their mean normal: each covers an angular sector at c turning the same way, and
// the sectors follow one another once round. Then two of them meet only at c and along the
// edge they share, if any: a pair of them needs no intersection test. (Doubles with a margin
// far above their rounding; false whenever that is too close to call.)
bool closed_fan_unfolded(const std::vector<Vec3>& points, uint32_t c, const std::array<uint32_t, 2>* corners,
                         size_t count);

struct Segment {
  Vec3 a, b;
  uint32_t tri_a, tri_b;
};

// The segments along which the given pairs cross (pairs that meet in a point or overlap
// in a plane give no segment). Pairs whose planes meet at `min_angle_deg` or less give none
// either: their surfaces cross without a sharp edge (the feature angle's sense), and nearly
// coplanar overlaps, whose lines are rounding noise, give nothing to construct (the exact
// kernel's slowest case).
std::vector<Segment> intersection_segments(const std::vector<Vec3>& points, const std::vector<Tri>& triangles,
                                           const std::vector<TrianglePair>& pairs, double min_angle_deg = 0);

// Faces of a closed 2-manifold triangle mesh that intersect another face or are
// degenerate, by CGAL::Polygon_mesh_processing::self_intersections (parallel).
// Precondition: the triangles form a valid polygon mesh (manifold).
std::vector<uint32_t> mesh_self_intersecting_faces(const std::vector<Vec3>& points, const std::vector<Tri>& triangles);

// CGAL's own verdicts on a closed manifold mesh: does_self_intersect and is_outward_oriented.
struct CgalVerdict {
  bool valid_polygon_mesh = false, closed = false, self_intersects = true, outward = false;
};
CgalVerdict cgal_verdict(const std::vector<Vec3>& points, const std::vector<Tri>& triangles);

}  // namespace vdbwrap::check
