// The segments along which intersecting pairs cross (exact constructions).
#include <CGAL/Exact_predicates_exact_constructions_kernel.h>
#include <CGAL/intersections.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <mutex>

#include "check/exact_kernel.h"
#include "check/intersections.h"
#include "common/vec.h"

namespace vdbwrap::check {

using pair_search::P3;
using pair_search::to_point;

// The segments are constructed in the exact kernel. CGAL's construction in doubles is not safe
// on real inputs: where the line of the two planes runs along an edge of one triangle (a
// vertex on the other's plane, frequent on CAD grids and in CSG exports), or the planes are
// nearly parallel, or the coordinates are large (it raises them to high powers), a constructed
// point comes out non-finite and the filtered predicate that CGAL runs on it next converts it
// to a rational, which raises SIGFPE. A pair that holds a degenerate triangle (listed as a
// pair with itself), and a coplanar pair (duplicates, overlaps: they meet in an area or along
// their own edges), has no intersection line; both are settled by exact predicates first.
std::vector<Segment> intersection_segments(const std::vector<Vec3>& points, const std::vector<Tri>& triangles,
                                           const std::vector<TrianglePair>& pairs, double min_angle_deg) {
  // Planes at min_angle_deg or less: |cos| of the normals' angle at least this (0: none).
  const double shallow_cos = min_angle_deg > 0 ? std::cos(min_angle_deg * M_PI / 180.0) : 2.0;
  auto unit_normal = [&](const Tri& t) { return normalized(area_vector(points[t[0]], points[t[1]], points[t[2]])); };
  using EK = CGAL::Exact_predicates_exact_constructions_kernel;
  auto exact = [&](uint32_t v) { return EK::Point_3(points[v][0], points[v][1], points[v][2]); };
  std::vector<Segment> out;
  std::mutex lock;
  tbb::parallel_for(tbb::blocked_range<size_t>(0, pairs.size(), 64), [&](const tbb::blocked_range<size_t>& r) {
    std::vector<Segment> local;
    for (size_t i = r.begin(); i != r.end(); ++i) {
      if (pairs[i].a == pairs[i].b) continue;
      const Tri& x = triangles[pairs[i].a];
      const Tri& y = triangles[pairs[i].b];
      const P3 px[3] = {to_point(points[x[0]]), to_point(points[x[1]]), to_point(points[x[2]])};
      const P3 py[3] = {to_point(points[y[0]]), to_point(points[y[1]]), to_point(points[y[2]])};
      if (CGAL::collinear(px[0], px[1], px[2]) || CGAL::collinear(py[0], py[1], py[2])) continue;
      if (CGAL::coplanar(px[0], px[1], px[2], py[0]) && CGAL::coplanar(px[0], px[1], px[2], py[1]) &&
          CGAL::coplanar(px[0], px[1], px[2], py[2]))
        continue;
      // Not collinear, so both normals are defined (doubles: only a near tie can go either way).
      if (shallow_cos <= 1.0 && std::abs(dot(unit_normal(x), unit_normal(y))) >= shallow_cos) continue;
      const EK::Triangle_3 tx(exact(x[0]), exact(x[1]), exact(x[2]));
      const EK::Triangle_3 ty(exact(y[0]), exact(y[1]), exact(y[2]));
      const auto result = CGAL::intersection(tx, ty);
      const EK::Segment_3* s = result ? boost::get<EK::Segment_3>(&*result) : nullptr;
      if (!s) continue;  // a point
      const Vec3 a{CGAL::to_double(s->source().x()), CGAL::to_double(s->source().y()),
                   CGAL::to_double(s->source().z())};
      const Vec3 b{CGAL::to_double(s->target().x()), CGAL::to_double(s->target().y()),
                   CGAL::to_double(s->target().z())};
      if (a == b) continue;  // shorter than the doubles can tell apart
      local.push_back({a, b, pairs[i].a, pairs[i].b});
    }
    std::lock_guard<std::mutex> g(lock);
    out.insert(out.end(), local.begin(), local.end());
  });
  std::sort(out.begin(), out.end(), [](const Segment& u, const Segment& v) {
    return u.tri_a != v.tri_a ? u.tri_a < v.tri_a : u.tri_b < v.tri_b;
  });
  return out;
}

}  // namespace vdbwrap::check
