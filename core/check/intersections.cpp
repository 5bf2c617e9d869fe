// The pair search: the broad phase (intersections_broad_phase.h) over slabs of the triangles
// (slab_boxes), cheap proofs that drop most candidates (fans, star-shaped pieces, planes), and
// the narrow phase (triangle_pair_test) for the rest.
#include "check/intersections.h"

#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_invoke.h>

#include <algorithm>

#include "check/exact_kernel.h"
#include "check/fan_proofs.h"
#include "check/intersections_broad_phase.h"
#include "check/plane_bounds.h"
#include "check/slab_boxes.h"
#include "check/star_shaped_pieces.h"
#include "check/triangle_pair_test.h"

namespace vdbwrap::check {

using namespace pair_search;
static_assert(kNoPiece == kNoGroup, "the star-shaped pieces are the broad phase's groups");

std::vector<TrianglePair> find_intersecting_pairs(const std::vector<Vec3>& points, const std::vector<Tri>& triangles,
                                                  SoupKind kind, const EdgeTriangles* edges) {
  const ExactInput in = exact_input(points, triangles);
  const std::vector<P3>& p = in.p;
  const std::vector<uint8_t>& usable = in.usable;
  // The input's star-shaped pieces are found beside the rest: their walk is serial, and the
  // other cores would wait for it.
  SlabBoxes slabs;
  std::vector<uint8_t> fan, closed_fan;
  std::vector<uint32_t> piece;
  std::vector<PlaneBound> planes;
  tbb::parallel_invoke(
      [&] {
        piece = kind == SoupKind::kInput ? pair_search::star_shaped_pieces(p, triangles, usable, edges)
                                         : std::vector<uint32_t>(triangles.size(), kNoPiece);
      },
      [&] {
        slabs = slab_boxes(p, triangles, usable);
        const VertexStars stars = vertex_stars(p.size(), triangles, usable);
        fan = unfolded_fan_vertices(p, triangles, stars);
        if (kind == SoupKind::kWrap) closed_fan = closed_fan_vertices(points, triangles, stars);
        planes = plane_bounds(points, triangles, usable);
      });
  // Exact tests inside the (parallel) candidate callback: fans and long thin CAD triangles give
  // hundreds of millions of overlapping boxes, too many to store as candidates first.
  tbb::enumerable_thread_specific<std::vector<TrianglePair>> found;
  std::vector<uint32_t> box_piece(slabs.boxes.size());
  for (size_t k = 0; k < box_piece.size(); ++k) box_piece[k] = piece[slabs.owner[k]];
  grid_candidate_pairs(slabs.boxes, box_piece, [&](uint32_t box_x, uint32_t box_y) {
    uint32_t x = slabs.owner[box_x], y = slabs.owner[box_y];
    if (x == y) return;                                        // two slabs of one triangle
    if (piece[x] != kNoPiece && piece[x] == piece[y]) return;  // see star_shaped_pieces
    if (x > y) std::swap(x, y), std::swap(box_x, box_y);
    const Tri &tx = triangles[x], &ty = triangles[y];
    int shared = 0;
    uint32_t common = 0;
    bool in_closed_fan = false;
    for (uint32_t a : tx)
      for (uint32_t b : ty)
        if (a == b) ++shared, common = a, in_closed_fan = in_closed_fan || (!closed_fan.empty() && closed_fan[a]);
    if (shared == 1 && fan[common]) return;   // apart: see unfolded_fan_vertices
    if (in_closed_fan && shared < 3) return;  // they meet only where they share: see closed_fan_vertices
    if (shared <= 1 && (clearly_beside(points, planes[x], tx, ty) || clearly_beside(points, planes[y], ty, tx))) return;
    // The cheap proofs above may run once per pair of slabs that meet; the exact test, once.
    if (met_earlier(slabs, p, triangles, x, box_x, y, box_y)) return;
    if (triangles_intersect(p, tx, ty)) found.local().push_back({x, y});
  });
  std::vector<TrianglePair> out;
  for (const auto& local : found) out.insert(out.end(), local.begin(), local.end());
  std::sort(out.begin(), out.end(),
            [](const TrianglePair& u, const TrianglePair& v) { return u.a != v.a ? u.a < v.a : u.b < v.b; });
  return out;
}

std::vector<uint32_t> intersecting_triangles(const std::vector<Vec3>& points, const std::vector<Tri>& triangles,
                                             SoupKind kind) {
  std::vector<uint32_t> out;
  for (const TrianglePair& p : find_intersecting_pairs(points, triangles, kind)) out.push_back(p.a), out.push_back(p.b);
  std::vector<uint8_t> degenerate(triangles.size(), 0);
  tbb::parallel_for(tbb::blocked_range<size_t>(0, triangles.size(), 4096), [&](const tbb::blocked_range<size_t>& r) {
    for (size_t f = r.begin(); f != r.end(); ++f) degenerate[f] = triangle_is_degenerate(points, triangles[f]);
  });
  for (uint32_t f = 0; f < triangles.size(); ++f)
    if (degenerate[f]) out.push_back(f);
  std::sort(out.begin(), out.end());
  out.erase(std::unique(out.begin(), out.end()), out.end());
  return out;
}

std::vector<TrianglePair> find_intersecting_pairs_with(const std::vector<Vec3>& points,
                                                       const std::vector<Tri>& triangles,
                                                       const std::vector<uint32_t>& subset) {
  std::vector<TrianglePair> out;
  if (subset.empty()) return out;
  auto point = [&](uint32_t v) { return to_point(points[v]); };
  auto box_of = [&](uint32_t t) {
    const Tri& tri = triangles[t];
    return point(tri[0]).bbox() + point(tri[1]).bbox() + point(tri[2]).bbox();
  };
  std::vector<Box> all, some;
  all.reserve(triangles.size());
  for (uint32_t t = 0; t < triangles.size(); ++t) all.emplace_back(box_of(t), t);
  std::vector<P3> p;  // only the points the tests touch are converted, lazily through a copy
  p.reserve(points.size());
  for (const Vec3& v : points) p.push_back(to_point(v));
  for (uint32_t t : subset) {
    if (is_degenerate(p, triangles[t])) {
      out.push_back({t, t});
      continue;
    }
    some.emplace_back(box_of(t), t);
  }
  tbb::enumerable_thread_specific<std::vector<TrianglePair>> found;
  CGAL::box_intersection_d<CGAL::Parallel_if_available_tag>(
      some.begin(), some.end(), all.begin(), all.end(), [&](const Box& a, const Box& b) {
        const uint32_t x = uint32_t(a.handle()), y = uint32_t(b.handle());
        if (x == y || is_degenerate(p, triangles[y])) return;
        if (triangles_intersect(p, triangles[x], triangles[y]))
          found.local().push_back({std::min(x, y), std::max(x, y)});
      });
  for (const auto& local : found) out.insert(out.end(), local.begin(), local.end());
  std::sort(out.begin(), out.end(),
            [](const TrianglePair& u, const TrianglePair& v) { return u.a != v.a ? u.a < v.a : u.b < v.b; });
  out.erase(std::unique(out.begin(), out.end(),
                        [](const TrianglePair& u, const TrianglePair& v) { return u.a == v.a && u.b == v.b; }),
            out.end());
  return out;
}

}  // namespace vdbwrap::check
