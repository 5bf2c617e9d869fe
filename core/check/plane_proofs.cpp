// Proofs in the plane (see plane_proofs.h).
#include "check/plane_proofs.h"

#include <algorithm>
#include <initializer_list>
#include <limits>

namespace vdbwrap::check::pair_search {
namespace {

// The plane of a triangle seen along the dominant axis of its normal: the two other axes.
struct Plane2 {
  int u = 0, v = 1;
  double err = 0;  // bound on the rounding of a coordinate difference: the points' magnitude
  Plane2(const P3& a, const P3& b, const P3& c) {
    const double n[3] = {(b.y() - a.y()) * (c.z() - a.z()) - (b.z() - a.z()) * (c.y() - a.y()),
                         (b.z() - a.z()) * (c.x() - a.x()) - (b.x() - a.x()) * (c.z() - a.z()),
                         (b.x() - a.x()) * (c.y() - a.y()) - (b.y() - a.y()) * (c.x() - a.x())};
    int drop = 0;
    for (int k = 1; k < 3; ++k)
      if (std::fabs(n[k]) > std::fabs(n[drop])) drop = k;
    u = (drop + 1) % 3, v = (drop + 2) % 3;
  }
  std::array<double, 2> operator()(const P3& q, const P3& origin) const { return {q[u] - origin[u], q[v] - origin[v]}; }
  void covers(std::initializer_list<const P3*> points) {
    double m = 0;
    for (const P3* q : points) m = std::max({m, std::fabs((*q)[u]), std::fabs((*q)[v])});
    err = 8 * std::numeric_limits<double>::epsilon() * m;
  }
};

// A vector in the plane with its length, for the proofs below that test each vector against
// several lines: each length is taken once (the same answers as side(), with one square root
// per vector instead of two per test).
struct Dir2 {
  V2 v;
  double len;
  explicit Dir2(const V2& p) : v(p), len(len2(p)) {}
};
int side(const Dir2& dir, const Dir2& p, double err) {
  const double c = cross2(dir.v, p.v), m = kMargin * dir.len * p.len + err * (dir.len + p.len + err);
  return c > m ? 1 : c < -m ? -1 : 0;
}

// Triangles (c, a, b) and (c, d, e), sharing only vertex c, meet only there: the two angular
// sectors at c are disjoint when a line through c along one of their four sides leaves the
// other sector strictly on its far side.
bool apart_at_shared_vertex_2d(const P3& c, const P3& a, const P3& b, const P3& d, const P3& e) {
  Plane2 pl(c, a, b);
  pl.covers({&c, &a, &b, &d, &e});
  const Dir2 va(pl(a, c)), vb(pl(b, c)), vd(pl(d, c)), ve(pl(e, c));
  auto separates = [&](const Dir2& side_dir, const Dir2& other, const Dir2& p, const Dir2& q) {
    const int inside = side(side_dir, other, pl.err);
    return inside != 0 && side(side_dir, p, pl.err) == -inside && side(side_dir, q, pl.err) == -inside;
  };
  return separates(va, vb, vd, ve) || separates(vb, va, vd, ve) || separates(vd, ve, va, vb) ||
         separates(ve, vd, va, vb);
}

}  // namespace

bool apart_at_shared_edge_2d(const P3& s, const P3& t, const P3& a, const P3& b) {
  Plane2 pl(s, t, a);
  pl.covers({&s, &t, &a, &b});
  const Dir2 dir(pl(t, s));
  const int sa = side(dir, Dir2(pl(a, s)), pl.err), sb = side(dir, Dir2(pl(b, s)), pl.err);
  return sa != 0 && sb == -sa;
}

bool apart_2d(const std::array<P3, 3>& x, const std::array<P3, 3>& y) {
  Plane2 pl(x[0], x[1], x[2]);
  pl.covers({&x[0], &x[1], &x[2], &y[0], &y[1], &y[2]});
  auto splits = [&](const std::array<P3, 3>& own, const std::array<P3, 3>& other) {
    for (int i = 0; i < 3; ++i) {
      const P3& o = own[i];
      const Dir2 dir(pl(own[(i + 1) % 3], o));
      const int inside = side(dir, Dir2(pl(own[(i + 2) % 3], o)), pl.err);
      if (inside == 0) continue;
      bool all = true;
      for (int k = 0; k < 3 && all; ++k) all = side(dir, Dir2(pl(other[k], o)), pl.err) == -inside;
      if (all) return true;
    }
    return false;
  };
  return splits(x, y) || splits(y, x);
}

bool apart_at_shared_vertex(const P3& c, const P3& a, const P3& b, const P3& d, const P3& e) {
  const bool flat = nearly_coplanar(c, a, b, d) && nearly_coplanar(c, a, b, e);
  if (flat && apart_at_shared_vertex_2d(c, a, b, d, e)) return true;
  // d and e strictly on one side of plane (c, a, b): the second triangle meets that plane at c
  // only (and the same the other way round). Filtered predicates: fast when not coplanar.
  const CGAL::Orientation od = CGAL::orientation(c, a, b, d);
  if (od != CGAL::COPLANAR && od == CGAL::orientation(c, a, b, e)) return true;
  const CGAL::Orientation oa = CGAL::orientation(c, d, e, a);
  if (oa != CGAL::COPLANAR && oa == CGAL::orientation(c, d, e, b)) return true;
  return !flat && apart_at_shared_vertex_2d(c, a, b, d, e);
}

}  // namespace vdbwrap::check::pair_search
