#include "mesh/radial_pairs.h"

#include <algorithm>
#include <array>
#include <cmath>

#include "common/edge_triangles.h"

namespace vdbwrap::mesh {

uint32_t radial_partner(const std::vector<Vec3>& points, const std::vector<Tri>& triangles, uint32_t a, uint32_t b,
                        const uint32_t* around, size_t count, uint32_t t) {
  constexpr uint32_t none = UINT32_MAX;
  constexpr size_t kMost = 16;
  if (count < 4 || count > kMost || count % 2 != 0) return none;
  const Vec3 pa = points[a];
  const Vec3 d = points[b] - pa;
  if (norm2(d) == 0) return none;
  const Vec3 axis = normalized(d);
  // A frame across the edge.
  const Vec3 helper = std::abs(axis[0]) < 0.6 ? Vec3{1, 0, 0} : Vec3{0, 1, 0};
  const Vec3 e1 = normalized(cross(axis, helper)), e2 = cross(axis, e1);
  struct Fin {
    double angle;
    uint32_t triangle;
    bool forward;  // runs a to b
  };
  std::array<Fin, kMost> fins;
  for (size_t i = 0; i < count; ++i) {
    const Tri& tri = triangles[around[i]];
    const int ahead = directed_side(tri, a, b), back = directed_side(tri, b, a);
    if (ahead < 0 && back < 0) return none;  // a repeated corner
    const bool forward = ahead >= 0;
    const uint32_t c = tri[((forward ? ahead : back) + 2) % 3];
    if (c == a || c == b) return none;
    const Vec3 w = points[c] - pa;
    const double x = dot(w, e1), y = dot(w, e2);
    if ((x == 0 && y == 0) || !std::isfinite(x) || !std::isfinite(y)) return none;  // on the edge's line, or no number
    fins[i] = {std::atan2(y, x), around[i], forward};
  }
  std::sort(fins.begin(), fins.begin() + count, [](const Fin& u, const Fin& v) { return u.angle < v.angle; });
  for (size_t i = 0; i < count; ++i) {  // two fins in one half-plane (the last and first across -pi too)
    const double next = i + 1 < count ? fins[i + 1].angle : fins[0].angle + 2 * M_PI;
    if (next - fins[i].angle < 1e-12) return none;
  }
  // A triangle running a to b has its normal along axis x w: its material lies clockwise
  // (towards smaller angles); one running b to a, counter-clockwise. So solid wedges need the
  // fins to alternate, each backward fin followed (counter-clockwise) by a forward one.
  size_t at = count;
  for (size_t i = 0; i < count; ++i) {
    if (fins[i].forward == fins[(i + 1) % count].forward) return none;
    if (fins[i].triangle == t) at = i;
  }
  if (at == count) return none;
  const size_t partner = fins[at].forward ? (at + count - 1) % count : (at + 1) % count;
  return fins[partner].triangle;
}

}  // namespace vdbwrap::mesh
