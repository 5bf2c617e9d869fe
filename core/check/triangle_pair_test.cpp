// The narrow phase of the pair search (see triangle_pair_test.h) and the public one-pair tests.
#include "check/triangle_pair_test.h"

#include <CGAL/intersections.h>

#include <cstdint>

#include "check/intersections.h"
#include "check/plane_proofs.h"

namespace vdbwrap::check::pair_search {

template <typename Points>
bool triangles_intersect(const Points& p, const Tri& x, const Tri& y, bool use_proofs_2d) {
  // A triangle with a corner twice is a segment: degenerate, a defect of its own wherever it
  // lies, and it meets anything (the shared-corner cases below need three distinct corners).
  auto repeats = [](const Tri& t) { return t[0] == t[1] || t[1] == t[2] || t[0] == t[2]; };
  if (repeats(x) || repeats(y)) return true;
  int shared = 0;
  int xi[3], yi[3];  // positions of shared vertices
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j)
      if (x[i] == y[j]) {
        xi[shared] = i;
        yi[shared] = j;
        ++shared;
      }
  if (shared == 0) {
    const bool flat = nearly_coplanar(p[x[0]], p[x[1]], p[x[2]], p[y[0]]) &&
                      nearly_coplanar(p[x[0]], p[x[1]], p[x[2]], p[y[1]]) &&
                      nearly_coplanar(p[x[0]], p[x[1]], p[x[2]], p[y[2]]);
    if (use_proofs_2d && flat && apart_2d({p[x[0]], p[x[1]], p[x[2]]}, {p[y[0]], p[y[1]], p[y[2]]})) return false;
    return CGAL::do_intersect(T3(p[x[0]], p[x[1]], p[x[2]]), T3(p[y[0]], p[y[1]], p[y[2]]));
  }
  if (shared == 3) return true;  // the same triangle twice
  if (shared == 1) {
    int i = xi[0], j = yi[0];
    const P3 &c = p[x[i]], &a = p[x[(i + 1) % 3]], &b = p[x[(i + 2) % 3]], &d = p[y[(j + 1) % 3]],
             &e = p[y[(j + 2) % 3]];
    if (use_proofs_2d && apart_at_shared_vertex(c, a, b, d, e)) return false;
    // A crossing that starts at the common vertex leaves one triangle through its opposite edge.
    S3 opp_x(a, b);
    S3 opp_y(d, e);
    return CGAL::do_intersect(opp_x, T3(p[y[0]], p[y[1]], p[y[2]])) ||
           CGAL::do_intersect(opp_y, T3(p[x[0]], p[x[1]], p[x[2]]));
  }
  // Common edge: they intersect only when folded flat onto the same side of it.
  const P3& s = p[x[xi[0]]];
  const P3& t = p[x[xi[1]]];
  const P3& a = p[x[3 - xi[0] - xi[1]]];
  const P3& b = p[y[3 - yi[0] - yi[1]]];
  if (use_proofs_2d && nearly_coplanar(s, t, a, b) && apart_at_shared_edge_2d(s, t, a, b)) return false;
  if (!CGAL::coplanar(s, t, a, b)) return false;
  return CGAL::coplanar_orientation(s, t, a, b) == CGAL::POSITIVE;
}

template bool triangles_intersect(const std::vector<P3>&, const Tri&, const Tri&, bool);
template bool triangles_intersect(const std::array<P3, 6>&, const Tri&, const Tri&, bool);

}  // namespace vdbwrap::check::pair_search

namespace vdbwrap::check {
namespace {

using pair_search::P3;
using pair_search::to_point;

// The pair test on corners given by `corner(triangle, k)`: only the six points involved are
// converted, on the stack (this runs for every change weighed, so often that a heap buffer
// each time would cost more than the test); the index map keeps the shared-vertex logic.
template <typename Corner>
bool pair_intersects(const Tri& a, const Tri& b, Corner&& corner, bool use_proofs_2d) {
  std::array<P3, 6> p;
  Tri la, lb;
  std::array<uint32_t, 6> ids;
  size_t count = 0;
  auto local = [&](uint32_t v, const Vec3& at) {
    for (size_t i = 0; i < count; ++i)
      if (ids[i] == v) return uint32_t(i);
    ids[count] = v;
    p[count] = to_point(at);
    return uint32_t(count++);
  };
  for (int k = 0; k < 3; ++k) la[k] = local(a[k], corner(0, k));
  for (int k = 0; k < 3; ++k) lb[k] = local(b[k], corner(1, k));
  return pair_search::triangles_intersect(p, la, lb, use_proofs_2d);
}

}  // namespace

bool triangle_pair_intersects(const std::vector<Vec3>& points, const Tri& a, const Tri& b, bool use_proofs_2d) {
  return pair_intersects(
      a, b, [&](int t, int k) -> const Vec3& { return points[(t == 0 ? a : b)[k]]; }, use_proofs_2d);
}

bool triangle_pair_intersects(const Corners& a_at, const Tri& a, const Corners& b_at, const Tri& b,
                              bool use_proofs_2d) {
  return pair_intersects(
      a, b, [&](int t, int k) -> const Vec3& { return (t == 0 ? a_at : b_at)[k]; }, use_proofs_2d);
}

bool triangle_is_degenerate(const std::vector<Vec3>& points, const Tri& t) {
  return triangle_is_degenerate(Corners{points[t[0]], points[t[1]], points[t[2]]}, t);
}

bool triangle_is_degenerate(const Corners& at, const Tri& t) {
  return t[0] == t[1] || t[1] == t[2] || t[0] == t[2] ||
         CGAL::collinear(to_point(at[0]), to_point(at[1]), to_point(at[2]));
}

}  // namespace vdbwrap::check
