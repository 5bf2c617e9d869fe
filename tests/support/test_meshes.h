// Meshes built in code for the tests, and helpers that check surfaces with CGAL.
#pragma once
#include <cctype>
#include <cmath>
#include <map>
#include <string>

#include "check/intersections.h"
#include "vdbwrap/mesh.h"
#include "vdbwrap/wrap.h"

#ifndef VDBWRAP_TEST_DATA_DIR
#define VDBWRAP_TEST_DATA_DIR "tests/data"
#endif

namespace vdbwrap::testing {

inline std::string data_path(const std::string& name) { return std::string(VDBWRAP_TEST_DATA_DIR) + "/" + name; }

// A GoogleTest parameter name from a file name (letters and digits only).
inline std::string test_name_of(const std::string& file) {
  std::string n = file;
  for (char& c : n)
    if (!std::isalnum(static_cast<unsigned char>(c))) c = '_';
  return n;
}

// Axis-aligned box, 12 outward triangles, as part `part`.
inline void add_box(Mesh& m, const Vec3& lo, const Vec3& hi, int32_t part = 0) {
  uint32_t base = uint32_t(m.points.size());
  for (int i = 0; i < 8; ++i)
    m.points.push_back({(i & 1) ? hi[0] : lo[0], (i & 2) ? hi[1] : lo[1], (i & 4) ? hi[2] : lo[2]});
  const uint32_t f[12][3] = {{0, 2, 1}, {1, 2, 3}, {4, 5, 6}, {5, 7, 6}, {0, 1, 4}, {1, 5, 4},
                             {2, 6, 3}, {3, 6, 7}, {0, 4, 2}, {2, 4, 6}, {1, 3, 5}, {3, 7, 5}};
  for (auto& t : f) {
    m.triangles.push_back({base + t[0], base + t[1], base + t[2]});
    m.triangle_part.push_back(part);
  }
  while (int32_t(m.part_names.size()) <= part) m.part_names.push_back("part" + std::to_string(m.part_names.size()));
}

inline Mesh box_mesh(const Vec3& lo, const Vec3& hi) {
  Mesh m;
  add_box(m, lo, hi);
  return m;
}

// UV sphere.
inline Mesh sphere_mesh(double r, int rings = 24, int segments = 48) {
  Mesh m;
  m.points.push_back({0, 0, r});
  for (int i = 1; i < rings; ++i) {
    double th = M_PI * i / rings;
    for (int j = 0; j < segments; ++j) {
      double ph = 2 * M_PI * j / segments;
      m.points.push_back({r * std::sin(th) * std::cos(ph), r * std::sin(th) * std::sin(ph), r * std::cos(th)});
    }
  }
  m.points.push_back({0, 0, -r});
  auto ring = [&](int i, int j) { return uint32_t(1 + (i - 1) * segments + (j % segments)); };
  for (int j = 0; j < segments; ++j) m.triangles.push_back({0, ring(1, j), ring(1, j + 1)});
  for (int i = 1; i + 1 < rings; ++i)
    for (int j = 0; j < segments; ++j) {
      m.triangles.push_back({ring(i, j), ring(i + 1, j), ring(i + 1, j + 1)});
      m.triangles.push_back({ring(i, j), ring(i + 1, j + 1), ring(i, j + 1)});
    }
  uint32_t south = uint32_t(m.points.size() - 1);
  for (int j = 0; j < segments; ++j) m.triangles.push_back({south, ring(rings - 1, j + 1), ring(rings - 1, j)});
  return m;
}

// A unit cube of zero-thickness walls, each face a 20 x 20 grid of squares, with a square
// hole of `hole` x `hole` (a multiple of 0.05) in the middle of the top face.
inline Mesh holed_cube(double hole) {
  Mesh m;
  const int n = 20;
  const double w = 1.0 / n;
  std::map<std::array<long, 3>, uint32_t> index;
  auto vid = [&](double x, double y, double z) {
    std::array<long, 3> k{std::lround(x * 1e6), std::lround(y * 1e6), std::lround(z * 1e6)};
    auto [it, added] = index.emplace(k, uint32_t(m.points.size()));
    if (added) m.points.push_back({x, y, z});
    return it->second;
  };
  auto quad = [&](Vec3 a, Vec3 b, Vec3 c, Vec3 d) {
    uint32_t i = vid(a[0], a[1], a[2]), j = vid(b[0], b[1], b[2]), k = vid(c[0], c[1], c[2]), l = vid(d[0], d[1], d[2]);
    m.triangles.push_back({i, j, k});
    m.triangles.push_back({i, k, l});
  };
  const double h0 = 0.5 - hole / 2, h1 = 0.5 + hole / 2;
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j) {
      double u0 = i * w, u1 = (i + 1) * w, v0 = j * w, v1 = (j + 1) * w;
      quad({u0, v0, 0}, {u0, v1, 0}, {u1, v1, 0}, {u1, v0, 0});  // z = 0, normal -z
      bool in_hole = u0 >= h0 - 1e-9 && u1 <= h1 + 1e-9 && v0 >= h0 - 1e-9 && v1 <= h1 + 1e-9;
      if (!in_hole) quad({u0, v0, 1}, {u1, v0, 1}, {u1, v1, 1}, {u0, v1, 1});  // z = 1, normal +z
      quad({u0, 0, v0}, {u1, 0, v0}, {u1, 0, v1}, {u0, 0, v1});                // y = 0
      quad({u0, 1, v0}, {u0, 1, v1}, {u1, 1, v1}, {u1, 1, v0});                // y = 1
      quad({0, u0, v0}, {0, u0, v1}, {0, u1, v1}, {0, u1, v0});                // x = 0
      quad({1, u0, v0}, {1, u1, v0}, {1, u1, v1}, {1, u0, v1});                // x = 1
    }
  return m;
}

// The verdict the product promises, from CGAL's own predicates plus the combinatorial checks.
struct SurfaceVerdict {
  bool ok = false;
  std::string why;
};
inline SurfaceVerdict valid_closed_surface(const Mesh& unwelded) {
  // Files such as binary STL repeat each corner: merge bit-identical points first.
  Mesh m;
  m.triangles = unwelded.triangles;
  {
    std::map<Vec3, uint32_t> index;
    std::vector<uint32_t> remap(unwelded.points.size());
    for (size_t i = 0; i < unwelded.points.size(); ++i) {
      auto [it, added] = index.emplace(unwelded.points[i], uint32_t(m.points.size()));
      if (added) m.points.push_back(unwelded.points[i]);
      remap[i] = it->second;
    }
    for (auto& t : m.triangles)
      for (auto& v : t) v = remap[v];
  }
  MeshDiagnostics d = diagnose(m, false);
  check::CgalVerdict v = check::cgal_verdict(m.points, m.triangles);
  SurfaceVerdict out;
  out.ok = d.closed && d.manifold && d.oriented && d.degenerate_triangles == 0 && v.valid_polygon_mesh && v.closed &&
           !v.self_intersects && v.outward;
  out.why = "closed=" + std::to_string(d.closed) + " manifold=" + std::to_string(d.manifold) +
            " oriented=" + std::to_string(d.oriented) + " degenerate=" + std::to_string(d.degenerate_triangles) +
            " cgal_valid=" + std::to_string(v.valid_polygon_mesh) + " cgal_closed=" + std::to_string(v.closed) +
            " cgal_self_intersects=" + std::to_string(v.self_intersects) + " cgal_outward=" + std::to_string(v.outward);
  return out;
}

// Icosphere (subdivided icosahedron, projected): an isotropic mesh.
inline Mesh icosphere_mesh(double r, int level) {
  const double t = (1 + std::sqrt(5.0)) / 2;
  Mesh m;
  m.points = {{-1, t, 0},  {1, t, 0},  {-1, -t, 0}, {1, -t, 0}, {0, -1, t},  {0, 1, t},
              {0, -1, -t}, {0, 1, -t}, {t, 0, -1},  {t, 0, 1},  {-t, 0, -1}, {-t, 0, 1}};
  m.triangles = {{0, 11, 5},  {0, 5, 1},  {0, 1, 7},  {0, 7, 10}, {0, 10, 11}, {1, 5, 9}, {5, 11, 4},
                 {11, 10, 2}, {10, 7, 6}, {7, 1, 8},  {3, 9, 4},  {3, 4, 2},   {3, 2, 6}, {3, 6, 8},
                 {3, 8, 9},   {4, 9, 5},  {2, 4, 11}, {6, 2, 10}, {8, 6, 7},   {9, 8, 1}};
  for (int l = 0; l < level; ++l) {
    std::map<std::pair<uint32_t, uint32_t>, uint32_t> mid;
    auto middle = [&](uint32_t a, uint32_t b) {
      auto key = std::make_pair(std::min(a, b), std::max(a, b));
      auto it = mid.find(key);
      if (it != mid.end()) return it->second;
      const Vec3 &p = m.points[a], &q = m.points[b];
      m.points.push_back({(p[0] + q[0]) / 2, (p[1] + q[1]) / 2, (p[2] + q[2]) / 2});
      return mid[key] = uint32_t(m.points.size() - 1);
    };
    std::vector<Tri> next;
    for (const Tri& f : m.triangles) {
      uint32_t ab = middle(f[0], f[1]), bc = middle(f[1], f[2]), ca = middle(f[2], f[0]);
      next.push_back({f[0], ab, ca});
      next.push_back({f[1], bc, ab});
      next.push_back({f[2], ca, bc});
      next.push_back({ab, bc, ca});
    }
    m.triangles = std::move(next);
  }
  for (Vec3& p : m.points) {
    double n = std::sqrt(p[0] * p[0] + p[1] * p[1] + p[2] * p[2]);
    for (double& c : p) c *= r / n;
  }
  return m;
}

// An icosphere whose vertices' coordinates are each scaled by 1 +- up to `fraction`, from a
// fixed sequence (the same on every platform), shifted by `centre`: a rough closed scan. At
// level 6 and 4 %, noise as coarse as the faces: they fold over every way and cross their
// neighbours.
inline Mesh jittered_icosphere(int level, double fraction, uint64_t seed = 1, const Vec3& centre = {0, 0, 0}) {
  Mesh m = icosphere_mesh(1.0, level);
  uint64_t state = seed;
  for (Vec3& p : m.points) {
    for (int k = 0; k < 3; ++k) {
      state = state * 6364136223846793005ull + 1442695040888963407ull;
      p[k] = p[k] * (1 + fraction * (2 * (double(state >> 11) / double(1ull << 53)) - 1)) + centre[k];
    }
  }
  return m;
}

// A unit icosphere (level 3) with one node pushed along the sphere past its neighbours: a
// local fold, intersecting triangles that the intersection repair fixes.
inline Mesh folded_icosphere() {
  Mesh m = icosphere_mesh(1.0, 3);
  const Vec3 p = m.points[5];
  const Vec3 a = m.points[m.triangles[0][0]], b = m.points[m.triangles[0][1]];
  const double edge =
      std::sqrt((b[0] - a[0]) * (b[0] - a[0]) + (b[1] - a[1]) * (b[1] - a[1]) + (b[2] - a[2]) * (b[2] - a[2]));
  const Vec3 w{0.3, 0.5, 0.8};  // a tangent direction: w x p, normalized
  Vec3 t{w[1] * p[2] - w[2] * p[1], w[2] * p[0] - w[0] * p[2], w[0] * p[1] - w[1] * p[0]};
  const double tn = std::sqrt(t[0] * t[0] + t[1] * t[1] + t[2] * t[2]);
  Vec3 q{p[0] + t[0] / tn * 1.6 * edge, p[1] + t[1] / tn * 1.6 * edge, p[2] + t[2] / tn * 1.6 * edge};
  const double qn = std::sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2]);
  m.points[5] = {q[0] / qn, q[1] / qn, q[2] / qn};
  return m;
}

// Two open square sheets (two triangles each, parts 0 and 1) crossing at right angles through
// each other's middle, edge to edge: the crossing runs into both sheets' borders, so the
// intersection repair has nothing to cap and leaves it (exit 4).
// `m` with every triangle also split in three at its centre, both kept: one body tessellated
// twice, its faces lying on one another and every edge with four triangles.
inline Mesh tessellated_twice(const Mesh& m) {
  Mesh out = m;
  for (const Tri& t : m.triangles) {
    const uint32_t c = uint32_t(out.points.size());
    Vec3 centre{0, 0, 0};
    for (int k = 0; k < 3; ++k) centre[k] = (m.points[t[0]][k] + m.points[t[1]][k] + m.points[t[2]][k]) / 3;
    out.points.push_back(centre);
    out.triangles.push_back({t[0], t[1], c});
    out.triangles.push_back({t[1], t[2], c});
    out.triangles.push_back({t[2], t[0], c});
  }
  if (!m.triangle_part.empty())
    for (size_t t = 0; t < m.triangles.size(); ++t)
      for (int k = 0; k < 3; ++k) out.triangle_part.push_back(m.triangle_part[t]);
  return out;
}

inline Mesh crossing_sheets() {
  Mesh m;
  m.points = {{-1, -1, 0}, {1, -1, 0}, {1, 1, 0}, {-1, 1, 0}, {-1, 0, -1}, {1, 0, -1}, {1, 0, 1}, {-1, 0, 1}};
  m.triangles = {{0, 1, 2}, {0, 2, 3}, {4, 5, 6}, {4, 6, 7}};
  m.triangle_part = {0, 0, 1, 1};
  m.part_names = {"part0", "part1"};
  return m;
}

// Closed cylinder tessellated like a CAD export: caps are fans of long thin wedges around a
// hub, the side one ring of long thin quads (two triangles each).
inline void add_cylinder(Mesh& m, const Vec3& base, double r, double h, int segments, int32_t part = 0) {
  const uint32_t o = uint32_t(m.points.size());
  m.points.push_back(base);
  m.points.push_back({base[0], base[1], base[2] + h});
  for (int z = 0; z < 2; ++z)
    for (int k = 0; k < segments; ++k) {
      double a = 2 * M_PI * k / segments;
      m.points.push_back({base[0] + r * std::cos(a), base[1] + r * std::sin(a), base[2] + z * h});
    }
  auto b = [&](int k) { return o + 2 + uint32_t(k % segments); };
  auto t = [&](int k) { return o + 2 + uint32_t(segments + k % segments); };
  for (int k = 0; k < segments; ++k) {
    m.triangles.push_back({o, b(k + 1), b(k)});
    m.triangles.push_back({o + 1, t(k), t(k + 1)});
    m.triangles.push_back({b(k), b(k + 1), t(k + 1)});
    m.triangles.push_back({b(k), t(k + 1), t(k)});
  }
  if (part > 0 || !m.triangle_part.empty()) {
    m.triangle_part.resize(m.triangles.size() - 4 * size_t(segments), 0);
    m.triangle_part.resize(m.triangles.size(), part);
    while (int32_t(m.part_names.size()) <= part) m.part_names.push_back("part" + std::to_string(m.part_names.size()));
  }
}

inline Mesh cylinder_mesh(const Vec3& base, double r, double h, int segments) {
  Mesh m;
  add_cylinder(m, base, r, h, segments);
  return m;
}

}  // namespace vdbwrap::testing
