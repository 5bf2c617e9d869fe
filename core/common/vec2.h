// Small 2-D vector helpers, for polygons and triangles laid into a plane (hole filling,
// ear clipping, the coplanar intersection tests).
#pragma once
#include <array>
#include <cmath>

namespace vdbwrap {

using Vec2 = std::array<double, 2>;

inline Vec2 sub2(const Vec2& a, const Vec2& b) { return {a[0] - b[0], a[1] - b[1]}; }
inline double dot2(const Vec2& a, const Vec2& b) { return a[0] * b[0] + a[1] * b[1]; }
// The z of the 3-D cross product: twice the signed area of (0, a, b).
inline double cross2(const Vec2& a, const Vec2& b) { return a[0] * b[1] - a[1] * b[0]; }
inline double length2(const Vec2& a) { return std::sqrt(dot2(a, a)); }
// Twice the signed area of triangle (a, b, c): positive when counter-clockwise.
inline double orient2(const Vec2& a, const Vec2& b, const Vec2& c) { return cross2(sub2(b, a), sub2(c, a)); }

}  // namespace vdbwrap
