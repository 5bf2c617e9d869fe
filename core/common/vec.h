// Small 3D vector helpers on vdbwrap::Vec3 (double precision).
#pragma once
#include <algorithm>
#include <cmath>

#include "vdbwrap/mesh.h"

namespace vdbwrap {

inline Vec3 operator+(const Vec3& a, const Vec3& b) { return {a[0] + b[0], a[1] + b[1], a[2] + b[2]}; }
inline Vec3 operator-(const Vec3& a, const Vec3& b) { return {a[0] - b[0], a[1] - b[1], a[2] - b[2]}; }
inline Vec3 operator*(const Vec3& a, double s) { return {a[0] * s, a[1] * s, a[2] * s}; }
inline Vec3 operator*(double s, const Vec3& a) { return a * s; }
inline double dot(const Vec3& a, const Vec3& b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }
inline Vec3 cross(const Vec3& a, const Vec3& b) {
  return {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
}
inline double norm2(const Vec3& a) { return dot(a, a); }
inline double norm(const Vec3& a) { return std::sqrt(dot(a, a)); }
inline Vec3 normalized(const Vec3& a) {
  double n = norm(a);
  return n > 0 ? a * (1.0 / n) : Vec3{0, 0, 0};
}
inline Vec3 lerp(const Vec3& a, const Vec3& b, double t) { return a + (b - a) * t; }

// Twice the area vector of triangle (a, b, c).
inline Vec3 area_vector(const Vec3& a, const Vec3& b, const Vec3& c) { return cross(b - a, c - a); }

struct Box3 {
  Vec3 lo{INFINITY, INFINITY, INFINITY}, hi{-INFINITY, -INFINITY, -INFINITY};
  // Comparisons rather than std::fmin/fmax, which are library calls here; the same result
  // (a NaN coordinate is ignored, as fmin ignores it) since lo and hi are never NaN.
  void add(const Vec3& p) {
    for (int k = 0; k < 3; ++k) {
      lo[k] = p[k] < lo[k] ? p[k] : lo[k];
      hi[k] = p[k] > hi[k] ? p[k] : hi[k];
    }
  }
  void add(const Box3& b) {
    if (!b.empty()) add(b.lo), add(b.hi);
  }
  bool empty() const { return lo[0] > hi[0]; }
  bool overlaps(const Box3& b) const {
    for (int k = 0; k < 3; ++k)
      if (lo[k] > b.hi[k] || b.lo[k] > hi[k]) return false;
    return true;
  }
  // From p to the nearest point of the box (0 inside).
  double squared_distance(const Vec3& p) const {
    double sum = 0;
    for (int k = 0; k < 3; ++k) {
      const double gap = std::max(lo[k] - p[k], p[k] - hi[k]);
      if (gap > 0) sum += gap * gap;
    }
    return sum;
  }
  Vec3 center() const { return (lo + hi) * 0.5; }
  double diagonal() const { return empty() ? 0 : norm(hi - lo); }
};

}  // namespace vdbwrap
