// Rounding coordinates to single precision (binary STL stores floats).
#pragma once
#include <cmath>

#include "vdbwrap/mesh.h"

namespace vdbwrap {

// Through a volatile float: GCC 12 at -O2/-O3 folds double(float(x)) away when it vectorizes
// two of the three coordinates (SLP), so the plain idiom leaves x and y unrounded.
inline double round_to_float(double x) {
  volatile float f = static_cast<float>(x);
  return static_cast<double>(f);
}
// The spacing of floats at magnitude m (24-bit significand): 2^(e-24) for 2^(e-1) <= m < 2^e.
inline double float_step(double m) {
  int exponent = 0;
  std::frexp(m, &exponent);
  return std::ldexp(1.0, exponent - 24);
}

inline Vec3 round_to_float(const Vec3& p) { return {round_to_float(p[0]), round_to_float(p[1]), round_to_float(p[2])}; }

}  // namespace vdbwrap
