// Fine anisotropic tessellations with their vertices jittered (issue 35): needle triangles
// whose folds the intersection repair must clear. Random numbers come from std::mt19937's raw
// output (specified by the standard), not from std distributions (implementation-defined), so a
// seed gives the same mesh with any standard library.
#pragma once
#include <cmath>
#include <cstdint>
#include <random>
#include <string>
#include <vector>

#include "test_meshes.h"
#include "vdbwrap/mesh.h"

namespace vdbwrap::testing {

// The shortest edge of positive length.
inline double shortest_edge_of(const Mesh& m) {
  double best = INFINITY;
  for (const Tri& t : m.triangles)
    for (int k = 0; k < 3; ++k) {
      const Vec3 &a = m.points[t[k]], &b = m.points[t[(k + 1) % 3]];
      const double d =
          std::sqrt((a[0] - b[0]) * (a[0] - b[0]) + (a[1] - b[1]) * (a[1] - b[1]) + (a[2] - b[2]) * (a[2] - b[2]));
      if (d > 0) best = std::min(best, d);
    }
  return best;
}

// Every vertex moved to a uniformly random point of the ball of radius `amount` x the mesh's
// shortest edge around it: past 1, the short edges of the needles fold over.
inline void jitter_vertices(Mesh& m, double amount, uint32_t seed) {
  const double radius = amount * shortest_edge_of(m);
  std::mt19937 rng(seed);
  auto u = [&] { return 2 * (double(rng()) + 0.5) / 4294967296.0 - 1; };  // (-1, 1)
  for (Vec3& p : m.points) {
    Vec3 d;
    do d = {u(), u(), u()};
    while (d[0] * d[0] + d[1] * d[1] + d[2] * d[2] > 1);
    for (int k = 0; k < 3; ++k) p[k] += radius * d[k];
  }
}

// The case: a unit UV sphere of 12 rings of 400 x `scale` segments (needles, fans of
// them at the poles), jittered by `amount` of its shortest edge (the default folds some 100
// pairs of needles, as in the issue).
inline Mesh jittered_anisotropic_sphere(uint32_t seed, int scale = 1, double amount = 1.25) {
  Mesh m = sphere_mesh(1.0, 12, 400 * scale);
  jitter_vertices(m, amount, seed);
  return m;
}

// A CAD-like long thin cylinder (radius 1, height 4): caps are fans of 400 x `scale` needles
// around a hub, the side one ring of quads 4 high and 0.016 / scale wide; jittered.
inline Mesh jittered_cad_cylinder(uint32_t seed, int scale = 1, double amount = 1.1) {
  Mesh m = cylinder_mesh({0, 0, 0}, 1.0, 4.0, 400 * scale);
  jitter_vertices(m, amount, seed);
  return m;
}

// A tube of radius 0.25 along a trefoil knot, 1200 x `scale` rings of 12 sides (thin quads
// along the knot where it bends fast), jittered: the tangled tube.
inline Mesh jittered_trefoil_tube(uint32_t seed, int scale = 1, double amount = 1.1) {
  const int rings = 1200 * scale, sides = 12;
  const double r = 0.25;
  auto curve = [](double t) {
    return Vec3{std::sin(t) + 2 * std::sin(2 * t), std::cos(t) - 2 * std::cos(2 * t), -std::sin(3 * t)};
  };
  auto sub = [](const Vec3& a, const Vec3& b) { return Vec3{a[0] - b[0], a[1] - b[1], a[2] - b[2]}; };
  auto cross = [](const Vec3& a, const Vec3& b) {
    return Vec3{a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
  };
  auto unit = [](const Vec3& a) {
    const double n = std::sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2]);
    return Vec3{a[0] / n, a[1] / n, a[2] / n};
  };
  Mesh m;
  for (int i = 0; i < rings; ++i) {
    const double t = 2 * M_PI * i / rings, h = 1e-4;
    const Vec3 c = curve(t);
    const Vec3 tangent = unit(sub(curve(t + h), curve(t - h)));
    // A frame from a fixed direction: the trefoil's tangent is never parallel to z.
    const Vec3 n = unit(cross(tangent, Vec3{0, 0, 1}));
    const Vec3 b = cross(tangent, n);
    for (int k = 0; k < sides; ++k) {
      const double a = 2 * M_PI * k / sides;
      m.points.push_back({c[0] + r * (std::cos(a) * n[0] + std::sin(a) * b[0]),
                          c[1] + r * (std::cos(a) * n[1] + std::sin(a) * b[1]),
                          c[2] + r * (std::cos(a) * n[2] + std::sin(a) * b[2])});
    }
  }
  auto at = [&](int i, int k) { return uint32_t((i % rings) * sides + (k % sides)); };
  for (int i = 0; i < rings; ++i)
    for (int k = 0; k < sides; ++k) {
      m.triangles.push_back({at(i, k), at(i + 1, k), at(i + 1, k + 1)});
      m.triangles.push_back({at(i, k), at(i + 1, k + 1), at(i, k + 1)});
    }
  jitter_vertices(m, amount, seed);
  return m;
}

// The generated cases by name: anisotropic_sphere, cad_cylinder, trefoil_tube; `amount` 0: the
// kind's default.
inline const std::vector<std::string>& jittered_kinds() {
  static const std::vector<std::string> kinds = {"anisotropic_sphere", "cad_cylinder", "trefoil_tube"};
  return kinds;
}

inline Mesh jittered_mesh(const std::string& kind, uint32_t seed, int scale = 1, double amount = 0) {
  if (kind == "cad_cylinder")
    return amount > 0 ? jittered_cad_cylinder(seed, scale, amount) : jittered_cad_cylinder(seed, scale);
  if (kind == "trefoil_tube")
    return amount > 0 ? jittered_trefoil_tube(seed, scale, amount) : jittered_trefoil_tube(seed, scale);
  return amount > 0 ? jittered_anisotropic_sphere(seed, scale, amount) : jittered_anisotropic_sphere(seed, scale);
}

}  // namespace vdbwrap::testing
