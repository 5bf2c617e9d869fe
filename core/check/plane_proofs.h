// Proofs in the plane. Projected along an axis, triangles that meet only at their shared
// vertices (or not at all) in 2D meet only there in 3D too: a common point would project to a
// common point. Projected along the dominant axis of one triangle's normal, this settles the
// nearly coplanar pairs (flat regions of a wrap, where the exact predicates are slow because
// the points are exactly coplanar) in doubles. Every test keeps a relative margin; anything
// close gives no proof and goes to the exact predicates. Each function answers true only with
// a proof that the triangles are apart (meet at most where they share).
#pragma once
#include <array>
#include <cmath>

#include "check/exact_kernel.h"

namespace vdbwrap::check::pair_search {

using V2 = std::array<double, 2>;
constexpr double kMargin = 1e-9;
inline double cross2(const V2& p, const V2& q) { return p[0] * q[1] - p[1] * q[0]; }
inline double len2(const V2& p) { return std::sqrt(p[0] * p[0] + p[1] * p[1]); }
// The side of p relative to the line along `dir` through the origin: +1 / -1 when clearly off
// it, 0 when too close to tell.
inline int side(const V2& dir, const V2& p, double err) {
  const double ld = len2(dir), lp = len2(p);
  const double c = cross2(dir, p), m = kMargin * ld * lp + err * (ld + lp + err);
  return c > m ? 1 : c < -m ? -1 : 0;
}

// Is q nearly in the plane of (o, a, b)? (Doubles, generous: it only picks which test runs
// first.) The proofs in the plane pay off for nearly coplanar pairs; for the others CGAL's
// filtered predicates decide at once, and the plane tests would be wasted work.
inline bool nearly_coplanar(const P3& o, const P3& a, const P3& b, const P3& q) {
  const double u[3] = {a.x() - o.x(), a.y() - o.y(), a.z() - o.z()};
  const double v[3] = {b.x() - o.x(), b.y() - o.y(), b.z() - o.z()};
  const double w[3] = {q.x() - o.x(), q.y() - o.y(), q.z() - o.z()};
  const double n[3] = {u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]};
  const double d = n[0] * w[0] + n[1] * w[1] + n[2] * w[2];
  const double nn = n[0] * n[0] + n[1] * n[1] + n[2] * n[2], ww = w[0] * w[0] + w[1] * w[1] + w[2] * w[2];
  return d * d <= 1e-12 * nn * ww;
}

// Triangles (s, t, a) and (t, s, b) sharing edge s-t meet only there when a and b lie clearly
// on opposite sides of it.
bool apart_at_shared_edge_2d(const P3& s, const P3& t, const P3& a, const P3& b);

// Triangles with no shared vertex are apart when a line along one of their six edges leaves
// the other triangle clearly on the far side.
bool apart_2d(const std::array<P3, 3>& x, const std::array<P3, 3>& y);

// Fast proof that triangles (c, a, b) and (c, d, e), sharing only vertex c, meet only there
// (false: no proof, run the exact tests). Fans of triangles around one vertex (cylinder caps,
// cone tips) make such pairs by the hundred million, nearly all far apart.
bool apart_at_shared_vertex(const P3& c, const P3& a, const P3& b, const P3& d, const P3& e);

}  // namespace vdbwrap::check::pair_search
