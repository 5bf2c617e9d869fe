// The hostile mesh generator (see hostile_meshes.h). Random numbers come from std::mt19937's raw
// output (specified by the standard), not from std distributions (implementation-defined), so a
// seed gives the same files with any standard library.
#include "hostile_meshes.h"

#include <array>
#include <cmath>
#include <cstring>
#include <functional>
#include <map>
#include <random>
#include <stdexcept>

#include "vdbwrap/io.h"
#include "test_meshes.h"

namespace vdbwrap::stress {

namespace {

struct Rng {
  explicit Rng(uint32_t seed) : g(seed) {}
  double u() { return (double(g()) + 0.5) / 4294967296.0; }  // (0, 1)
  double u(double a, double b) { return a + (b - a) * u(); }
  uint32_t below(uint32_t n) { return n == 0 ? 0 : uint32_t(u() * n) % n; }
  bool chance(double p) { return u() < p; }
  std::mt19937 g;
};

Vec3 add(const Vec3& a, const Vec3& b) { return {a[0] + b[0], a[1] + b[1], a[2] + b[2]}; }
Vec3 sub(const Vec3& a, const Vec3& b) { return {a[0] - b[0], a[1] - b[1], a[2] - b[2]}; }
Vec3 mul(const Vec3& a, double s) { return {a[0] * s, a[1] * s, a[2] * s}; }
Vec3 lerp(const Vec3& a, const Vec3& b, double t) { return add(a, mul(sub(b, a), t)); }
double norm(const Vec3& a) { return std::sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2]); }

// A rotation (Rz Ry Rx of random angles) and a translation.
struct Frame {
  double r[3][3] = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  Vec3 origin{0, 0, 0};
  Vec3 apply(const Vec3& p) const {
    return {origin[0] + r[0][0] * p[0] + r[0][1] * p[1] + r[0][2] * p[2],
            origin[1] + r[1][0] * p[0] + r[1][1] * p[1] + r[1][2] * p[2],
            origin[2] + r[2][0] * p[0] + r[2][1] * p[1] + r[2][2] * p[2]};
  }
};

Frame random_frame(Rng& rng, const Vec3& origin) {
  const double a = rng.u(0, 2 * M_PI), b = rng.u(0, 2 * M_PI), c = rng.u(0, 2 * M_PI);
  const double ca = std::cos(a), sa = std::sin(a), cb = std::cos(b), sb = std::sin(b), cc = std::cos(c),
               sc = std::sin(c);
  Frame f;
  const double m[3][3] = {{ca * cb, ca * sb * sc - sa * cc, ca * sb * cc + sa * sc},
                          {sa * cb, sa * sb * sc + ca * cc, sa * sb * cc - ca * sc},
                          {-sb, cb * sc, cb * cc}};
  std::memcpy(f.r, m, sizeof m);
  f.origin = origin;
  return f;
}

// Appends `piece` to `m` as part `name` (a new part unless the name exists).
void append(Mesh& m, const Mesh& piece, const std::string& name, const Frame* frame = nullptr) {
  int32_t part = -1;
  for (size_t i = 0; i < m.part_names.size(); ++i)
    if (m.part_names[i] == name) part = int32_t(i);
  if (part < 0) {
    part = int32_t(m.part_names.size());
    m.part_names.push_back(name);
  }
  const uint32_t base = uint32_t(m.points.size());
  for (const Vec3& p : piece.points) m.points.push_back(frame ? frame->apply(p) : p);
  m.triangle_part.resize(m.triangles.size(), 0);
  for (const Tri& t : piece.triangles) {
    m.triangles.push_back({base + t[0], base + t[1], base + t[2]});
    m.triangle_part.push_back(part);
  }
}

// Points welded by exact coordinates, so separately built faces share their corners.
class Welder {
 public:
  explicit Welder(Mesh& m) : m_(m) {}
  uint32_t operator()(const Vec3& p) {
    auto [it, added] = index_.emplace(p, uint32_t(m_.points.size()));
    if (added) m_.points.push_back(p);
    return it->second;
  }

 private:
  Mesh& m_;
  std::map<Vec3, uint32_t> index_;
};

// Box [lo, hi] whose six faces are grids of res[face] x res[face] quads, outward. With equal
// resolutions the box is conforming; with different ones the shared edges carry T-junctions.
Mesh grid_box(const Vec3& lo, const Vec3& hi, const int res[6]) {
  Mesh m;
  Welder vid(m);
  int face = 0;
  for (int axis = 0; axis < 3; ++axis)
    for (int side = 0; side < 2; ++side, ++face) {
      const int u = (axis + 1) % 3, v = (axis + 2) % 3, n = res[face];
      auto at = [&](int i, int j) {
        Vec3 p;
        p[axis] = side ? hi[axis] : lo[axis];
        p[u] = i == n ? hi[u] : lo[u] + (hi[u] - lo[u]) * i / n;
        p[v] = j == n ? hi[v] : lo[v] + (hi[v] - lo[v]) * j / n;
        return vid(p);
      };
      for (int i = 0; i < n; ++i)
        for (int j = 0; j < n; ++j) {
          uint32_t a = at(i, j), b = at(i + 1, j), c = at(i + 1, j + 1), d = at(i, j + 1);
          // (u, v, axis) is right-handed: counter-clockwise in (u, v) faces +axis.
          if (side) {
            m.triangles.push_back({a, b, c});
            m.triangles.push_back({a, c, d});
          } else {
            m.triangles.push_back({a, c, b});
            m.triangles.push_back({a, d, c});
          }
        }
    }
  return m;
}

Mesh grid_box(const Vec3& lo, const Vec3& hi, int n) {
  const int res[6] = {n, n, n, n, n, n};
  return grid_box(lo, hi, res);
}

// Square sheet in z = 0 over [x0, x1] x [y0, y1], n x n quads, facing +z; `flip_diagonal`
// splits the quads along the other diagonal.
Mesh sheet(double x0, double y0, double x1, double y1, int n, bool flip_diagonal) {
  Mesh m;
  auto at = [&](int i, int j) { return uint32_t(i * (n + 1) + j); };
  for (int i = 0; i <= n; ++i)
    for (int j = 0; j <= n; ++j) m.points.push_back({x0 + (x1 - x0) * i / n, y0 + (y1 - y0) * j / n, 0});
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j) {
      uint32_t a = at(i, j), b = at(i + 1, j), c = at(i + 1, j + 1), d = at(i, j + 1);
      if (flip_diagonal) {
        m.triangles.push_back({a, b, d});
        m.triangles.push_back({b, c, d});
      } else {
        m.triangles.push_back({a, b, c});
        m.triangles.push_back({a, c, d});
      }
    }
  return m;
}

std::string encode(const Mesh& m, const std::string& ext) {
  if (ext == "stl") return binary_stl_bytes(m);
  io::Format f = ext == "obj" ? io::Format::Obj : ext == "off" ? io::Format::Off : io::Format::Ply;
  return io::write_mesh_to_bytes(m, f);
}

HostileMesh finish(const std::string& kind, int scale, uint32_t seed, const Mesh& m, const std::string& ext,
                   const Vec3& seed_point) {
  HostileMesh h;
  h.kind = kind;
  h.file_name = kind + "_s" + std::to_string(scale) + "_" + std::to_string(seed) + "." + ext;
  h.bytes = encode(m, ext);
  h.seed_point = seed_point;
  if (ext != "stl" && ext != "off" && m.part_names.size() > 1) h.parts = m.part_names;
  h.triangles = m.triangles.size();
  return h;
}

// A closed box with a cylinder through it and a degenerate triangle on the crossing: the base
// of the extreme-coordinate kinds, so only the coordinates differ between them.
Mesh small_dirty_solid(int scale) {
  Mesh m = grid_box({0, 0, 0}, {1, 1, 1}, 2 * scale);
  Mesh cyl = vdbwrap::testing::cylinder_mesh({0.5, 0.5, -0.3}, 0.2, 1.6, 24 * scale);
  const uint32_t base = uint32_t(m.points.size());
  for (const Vec3& p : cyl.points) m.points.push_back(p);
  for (const Tri& t : cyl.triangles) m.triangles.push_back({base + t[0], base + t[1], base + t[2]});
  // Collinear, lying on the cylinder's axis where it pierces the box's top.
  const uint32_t a = uint32_t(m.points.size());
  m.points.push_back({0.5, 0.5, 0.9});
  m.points.push_back({0.5, 0.5, 1.0});
  m.points.push_back({0.5, 0.5, 1.1});
  m.triangles.push_back({a, a + 1, a + 2});
  return m;
}

// ---- the kinds ---------------------------------------------------------------------------

HostileMesh degenerate(int scale, uint32_t seed) {
  Rng rng(seed);
  Mesh m = grid_box({0, 0, 0}, {1, 1, 1}, 4 * scale);
  const size_t n = m.triangles.size();
  for (int k = 0; k < 20 * scale; ++k) {
    const Tri t = m.triangles[rng.below(uint32_t(n))];
    m.triangles.push_back({t[0], t[0], t[1]});  // coincident vertices (a repeated index)
    const uint32_t mid = uint32_t(m.points.size());
    m.points.push_back(lerp(m.points[t[0]], m.points[t[1]], rng.u()));
    m.triangles.push_back({t[0], mid, t[1]});  // collinear: a point on the triangle's edge
    const uint32_t same = uint32_t(m.points.size());
    for (int i = 0; i < 3; ++i) m.points.push_back(m.points[t[2]]);  // three copies of one point
    m.triangles.push_back({same, same + 1, same + 2});
  }
  return finish("degenerate", scale, seed, m, "stl", {0.5, 0.5, 0.5});
}

HostileMesh needles_slivers(int scale, uint32_t seed) {
  Rng rng(seed);
  Mesh s = vdbwrap::testing::icosphere_mesh(1.0, scale >= 4 ? 4 : 3);
  Mesh m;
  m.points = s.points;
  const double eps[4] = {1e-4, 1e-7, 1e-10, 0.0};
  for (const Tri& t : s.triangles) {
    if (!rng.chance(0.6)) {
      m.triangles.push_back(t);
      continue;
    }
    const Vec3 &a = m.points[t[0]], &b = m.points[t[1]], &c = m.points[t[2]];
    const double e = eps[rng.below(4)];
    // Sliver: a point just off edge ab (exactly on it for e = 0); needle: just off corner a.
    Vec3 p = rng.chance(0.5) ? lerp(lerp(a, b, 0.5), c, e) : lerp(a, lerp(b, c, 0.5), e);
    const uint32_t pi = uint32_t(m.points.size());
    m.points.push_back(p);
    m.triangles.push_back({t[0], t[1], pi});
    m.triangles.push_back({t[1], t[2], pi});
    m.triangles.push_back({t[2], t[0], pi});
  }
  return finish("needles_slivers", scale, seed, m, "ply", {0, 0, 0});
}

HostileMesh duplicates(int scale, uint32_t seed) {
  Rng rng(seed);
  Mesh shell = vdbwrap::testing::icosphere_mesh(1.0, scale >= 4 ? 3 : 2);
  const size_t n = shell.triangles.size();
  for (size_t i = 0; i < n; ++i) {
    const Tri t = shell.triangles[i];
    shell.triangles.push_back(t);                                        // every triangle twice
    if (rng.chance(0.2)) shell.triangles.push_back(t);                   // some three times
    if (rng.chance(0.1)) shell.triangles.push_back({t[0], t[2], t[1]});  // and reversed
  }
  Mesh pin = vdbwrap::testing::cylinder_mesh({0.6, 0, -0.2}, 0.3, 1.2, 32 * scale);
  Mesh m;
  append(m, shell, "shell");
  append(m, pin, "pin");
  append(m, pin, "pin_copy");  // the same part again, at the same place
  return finish("duplicates", scale, seed, m, "obj", {0, 0, 0});
}

HostileMesh coplanar_overlap(int scale, uint32_t seed) {
  Rng rng(seed);
  Mesh m;
  append(m, grid_box({0, 0, 0}, {1, 1, 1}, 3 * scale), "a");
  // Shares the planes z = 0 and z = 1 with a, overlapping there with other triangles.
  const double shift = rng.u(0.2, 0.4);
  append(m, grid_box({shift, 0.25, 0}, {1 + shift, 0.75, 1}, 2 * scale + 1), "b");
  Frame top;
  top.origin = {0, 0, 1};
  append(m, sheet(0.1, 0.1, 0.9, 0.9, 5 * scale, true), "patch", &top);  // lies on a's top face
  return finish("coplanar_overlap", scale, seed, m, "ply", {0.1, 0.5, 0.5});
}

HostileMesh nonmanifold_fan(int scale, uint32_t seed) {
  Rng rng(seed);
  Mesh m;
  Welder vid(m);
  const int pages = 8 * scale + 8 + int(rng.below(8));
  // Pages of a book: every triangle on the edge (0,0,0)-(0,0,1).
  const uint32_t e0 = vid({0, 0, 0}), e1 = vid({0, 0, 1});
  for (int i = 0; i < pages; ++i) {
    const double a = 2 * M_PI * i / pages;
    m.triangles.push_back({e0, e1, vid({-std::cos(a), std::sin(a), 0.5})});
  }
  // Two cubes on one edge and a third on one corner, sharing those points.
  auto cube = [&](const Vec3& lo) {
    Mesh c = grid_box(lo, add(lo, {1, 1, 1}), scale);
    for (const Tri& t : c.triangles)
      m.triangles.push_back({vid(c.points[t[0]]), vid(c.points[t[1]]), vid(c.points[t[2]])});
  };
  cube({1, 0, 0});
  cube({2, 1, 0});
  cube({3, 2, 1});
  m.triangle_part.assign(size_t(pages), 0);
  m.triangle_part.resize(m.triangles.size() - 12 * size_t(scale) * size_t(scale), 1);  // the last cube: 12 n^2
  m.triangle_part.resize(m.triangles.size(), 2);
  m.part_names = {"fan", "cubes", "corner_cube"};
  return finish("nonmanifold_fan", scale, seed, m, "obj", {1.5, 0.5, 0.5});
}

HostileMesh t_junctions(int scale, uint32_t seed) {
  Rng rng(seed);
  // Neighbouring faces with different grids: their shared edges do not match.
  int res[6];
  for (int& r : res) r = 2 * scale + int(rng.below(3));
  Mesh m = grid_box({0, 0, 0}, {2, 1, 1}, res);
  return finish("t_junctions", scale, seed, m, "off", {1, 0.5, 0.5});
}

HostileMesh inconsistent_orientation(int scale, uint32_t seed) {
  Rng rng(seed);
  Mesh m = vdbwrap::testing::sphere_mesh(1.0, 8 * scale, 16 * scale);
  for (Tri& t : m.triangles)
    if (rng.chance(0.3)) std::swap(t[1], t[2]);
  Mesh box = grid_box({0.5, -0.4, -0.4}, {1.6, 0.4, 0.4}, 2 * scale);
  for (Tri& t : box.triangles) std::swap(t[1], t[2]);  // inside out, through the sphere
  const uint32_t base = uint32_t(m.points.size());
  for (const Vec3& p : box.points) m.points.push_back(p);
  for (const Tri& t : box.triangles) m.triangles.push_back({base + t[0], base + t[1], base + t[2]});
  return finish("inconsistent_orientation", scale, seed, m, "stl", {0, 0, 0});
}

// Boxes and CAD-like cylinders on a lattice, each turned at random and pushed into its
// neighbours: thousands of intersecting pairs, plus degenerate triangles among them.
Mesh csg_scene(int scale, uint32_t seed, Vec3& inside) {
  Rng rng(seed);
  Mesh m;
  const int side = 3 + (scale > 1 ? 1 : 0);
  int solid = 0;
  for (int x = 0; x < side; ++x)
    for (int y = 0; y < side; ++y) {
      const Vec3 at{0.9 * x + rng.u(-0.1, 0.1), 0.9 * y + rng.u(-0.1, 0.1), rng.u(-0.2, 0.2)};
      Frame f = random_frame(rng, at);
      const std::string name = "solid" + std::to_string(solid++);
      if (rng.chance(0.5)) {
        append(m, vdbwrap::testing::cylinder_mesh({0, 0, -0.6}, 0.4, 1.2, 64 * scale), name, &f);
        if (x == 0 && y == 0) inside = f.apply({0, 0, 0});
      } else {
        append(m, grid_box({-0.5, -0.4, -0.35}, {0.5, 0.4, 0.35}, 8 * scale), name, &f);
        if (x == 0 && y == 0) inside = f.apply({0, 0, 0});
      }
    }
  // Degenerate triangles where the solids cross: a repeated index, three collinear points
  // between two solids' centres, and a triangle of one point repeated.
  const size_t n = m.triangles.size();
  for (int k = 0; k < 4 * scale; ++k) {
    const Tri t = m.triangles[rng.below(uint32_t(n))];
    m.triangles.push_back({t[0], t[1], t[1]});
    m.triangle_part.push_back(m.triangle_part[rng.below(uint32_t(n))]);
    const Vec3 a = m.points[m.triangles[rng.below(uint32_t(n))][0]],
               b = m.points[m.triangles[rng.below(uint32_t(n))][0]];
    const uint32_t p = uint32_t(m.points.size());
    m.points.push_back(a);
    m.points.push_back(lerp(a, b, 0.5));
    m.points.push_back(b);
    m.triangles.push_back({p, p + 1, p + 2});
    m.triangle_part.push_back(0);
    m.triangles.push_back({t[2], t[2], t[2]});
    m.triangle_part.push_back(0);
  }
  return m;
}

HostileMesh csg_intersecting(int scale, uint32_t seed) {
  Vec3 inside;
  Mesh m = csg_scene(scale, seed, inside);
  return finish("csg_intersecting", scale, seed, m, "obj", inside);
}

HostileMesh csg_export(int scale, uint32_t seed) {
  Vec3 inside;
  Mesh m = csg_scene(scale, seed, inside);
  return finish("csg_export", scale, seed, m, "stl", inside);  // float32, one solid
}

// Unit sphere with bumps; `holes` caps cut out with jagged rims, and single missing triangles.
HostileMesh open_scan(int scale, uint32_t seed) {
  Rng rng(seed);
  Mesh s = vdbwrap::testing::icosphere_mesh(1.0, scale >= 4 ? 5 : scale >= 2 ? 4 : 3);
  const double f1 = rng.u(3, 7), f2 = rng.u(3, 7);
  for (Vec3& p : s.points) {
    const double r = 1 + 0.06 * std::sin(f1 * p[0] + 1) * std::cos(f2 * p[1]) + 0.02 * std::sin(13 * p[2]);
    p = mul(p, r);
  }
  std::vector<std::pair<Vec3, double>> caps;
  const int holes = 3 + int(rng.below(3));
  for (int i = 0; i < holes; ++i) {
    Vec3 d{rng.u(-1, 1), rng.u(-1, 1), rng.u(-1, 1)};
    d = mul(d, 1 / std::max(norm(d), 1e-9));
    caps.push_back({d, rng.u(0.15, 0.5)});
  }
  Mesh m;
  m.points = s.points;
  for (const Tri& t : s.triangles) {
    Vec3 c = mul(add(add(s.points[t[0]], s.points[t[1]]), s.points[t[2]]), 1.0 / 3);
    c = mul(c, 1 / norm(c));
    bool keep = !rng.chance(0.01);
    for (const auto& [d, radius] : caps) {
      const double angle = std::acos(std::max(-1.0, std::min(1.0, c[0] * d[0] + c[1] * d[1] + c[2] * d[2])));
      if (angle < radius || (angle < 1.4 * radius && rng.chance(0.5))) keep = false;  // jagged rim
    }
    if (keep) m.triangles.push_back(t);
  }
  return finish("open_scan", scale, seed, m, "ply", {0, 0, 0});
}

HostileMesh open_sheet(int scale, uint32_t seed) {
  Rng rng(seed);
  const int n = 30 * scale;
  Mesh s = sheet(0, 0, 1, 1, n, false);
  const double a = rng.u(4, 9), b = rng.u(4, 9);
  for (Vec3& p : s.points) p[2] = 0.08 * std::sin(a * p[0]) * std::cos(b * p[1]) + 0.01 * std::sin(37 * p[0] * p[1]);
  std::vector<std::pair<Vec3, double>> holes;
  for (int i = 0; i < 4; ++i) holes.push_back({{rng.u(0.2, 0.8), rng.u(0.2, 0.8), 0}, rng.u(0.03, 0.12)});
  Mesh m;
  m.points = s.points;
  for (const Tri& t : s.triangles) {
    const Vec3 c = mul(add(add(s.points[t[0]], s.points[t[1]]), s.points[t[2]]), 1.0 / 3);
    bool keep = true;
    for (const auto& [h, r] : holes) {
      const double d = std::hypot(c[0] - h[0], c[1] - h[1]);
      if (d < r || (d < 1.3 * r && rng.chance(0.5))) keep = false;
    }
    const double edge = std::min(std::min(c[0], 1 - c[0]), std::min(c[1], 1 - c[1]));
    if (edge < 0.05 && rng.chance(0.4)) keep = false;  // jagged outer border
    if (keep) m.triangles.push_back(t);
  }
  return finish("open_sheet", scale, seed, m, "obj", {0.5, 0.5, 0.3});
}

HostileMesh single_triangle(int scale, uint32_t seed) {
  Rng rng(seed);
  Mesh m;
  m.points = {{rng.u(-1, 1), rng.u(-1, 1), rng.u(-1, 1)},
              {rng.u(-1, 1), rng.u(-1, 1), rng.u(-1, 1)},
              {rng.u(-1, 1), rng.u(-1, 1), rng.u(-1, 1)}};
  m.triangles = {{0, 1, 2}};
  const Vec3 c = mul(add(add(m.points[0], m.points[1]), m.points[2]), 1.0 / 3);
  return finish("single_triangle", scale, seed, m, "obj", c);
}

HostileMesh point_like(int scale, uint32_t seed) {
  Rng rng(seed);
  Mesh m;
  const Vec3 p{rng.u(-5, 5), rng.u(-5, 5), rng.u(-5, 5)};
  for (int i = 0; i < 4 * scale; ++i) {
    const uint32_t b = uint32_t(m.points.size());
    for (int k = 0; k < 3; ++k) m.points.push_back(p);
    m.triangles.push_back({b, b + 1, b + 2});
  }
  return finish("point_like", scale, seed, m, "stl", p);
}

HostileMesh all_degenerate(int scale, uint32_t seed) {
  Rng rng(seed);
  // Every triangle on one line: collinear points, no area anywhere.
  Mesh m;
  const Vec3 dir{rng.u(0.1, 1), rng.u(0.1, 1), rng.u(0.1, 1)};
  for (int i = 0; i < 10 * scale; ++i) {
    const uint32_t b = uint32_t(m.points.size());
    m.points.push_back(mul(dir, i));
    m.points.push_back(mul(dir, i + rng.u(0.1, 0.9)));
    m.points.push_back(mul(dir, i + 1));
    m.triangles.push_back({b, b + 1, b + 2});
  }
  return finish("all_degenerate", scale, seed, m, "off", mul(dir, 0.5));
}

HostileMesh flat(int scale, uint32_t seed) {
  Rng rng(seed);
  // A zero-thickness plane with holes, and a second tessellation of part of it on top.
  Mesh s = sheet(0, 0, 1, 1, 16 * scale, false);
  Mesh m;
  m.points = s.points;
  for (const Tri& t : s.triangles)
    if (!rng.chance(0.05)) m.triangles.push_back(t);
  Mesh over = sheet(0.2, 0.3, 0.7, 0.9, 7 * scale, true);
  const uint32_t base = uint32_t(m.points.size());
  for (const Vec3& p : over.points) m.points.push_back(p);
  for (const Tri& t : over.triangles) m.triangles.push_back({base + t[0], base + t[2], base + t[1]});  // facing -z
  return finish("flat", scale, seed, m, "off", {0.5, 0.5, 0});
}

HostileMesh long_thin(int scale, uint32_t seed) {
  Rng rng(seed);
  // A rod 1000 long and 1 thick, along a random direction.
  Frame f = random_frame(rng, {rng.u(-10, 10), rng.u(-10, 10), rng.u(-10, 10)});
  Mesh rod = vdbwrap::testing::cylinder_mesh({0, 0, -500}, 0.5, 1000, 12 * scale);
  Mesh m;
  for (const Vec3& p : rod.points) m.points.push_back(f.apply(p));
  m.triangles = rod.triangles;
  return finish("long_thin", scale, seed, m, "stl", f.apply({0, 0, 0}));
}

// A slender profiled bar, as CAD exports one: the profile (a star of `teeth` teeth, every tip
// and root a sharp corner, the flanks curved in `flank` segments) swept along z from z0 to z1
// through `stations` rings, turning by `twist` radians from one ring to the next, and capped by
// fans; with `bore` > 0, a round bore of that radius runs through it (a tube: not star-shaped,
// its caps are rings). Few rings on a long bar: the side triangles are needles hundreds of times
// longer than wide, and with the twist their boxes run diagonally across the bar.
Mesh profiled_bar(double radius, double bore, int teeth, int flank, int stations, double z0, double z1, double twist) {
  std::vector<std::array<double, 2>> outer, inner;  // counter-clockwise, at the same angles
  const int per_tooth = 2 * flank;
  for (int k = 0; k < teeth * per_tooth; ++k) {
    const double s = double(k % per_tooth) / flank;  // 0 at a tip, 1 at a root, 2 at the next tip
    const double depth = s <= 1 ? s : 2 - s;
    const double r = radius * (1 - 0.35 * depth * (2 - depth));  // flanks bulge outward
    const double a = 2 * M_PI * k / (teeth * per_tooth);
    outer.push_back({r * std::cos(a), r * std::sin(a)});
    inner.push_back({bore * std::cos(a), bore * std::sin(a)});
  }
  const uint32_t n = uint32_t(outer.size());
  Mesh m;
  // Points: the outer ring of each station, then (with a bore) the inner ring of each.
  auto ring = [&](const std::vector<std::array<double, 2>>& profile) {
    for (int j = 0; j < stations; ++j) {
      const double z = z0 + (z1 - z0) * j / (stations - 1), c = std::cos(twist * j), sn = std::sin(twist * j);
      for (const auto& [x, y] : profile) m.points.push_back({c * x - sn * y, sn * x + c * y, z});
    }
  };
  ring(outer);
  if (bore > 0) ring(inner);
  const uint32_t in = stations * n;  // first inner point
  for (int j = 0; j + 1 < stations; ++j)
    for (uint32_t k = 0; k < n; ++k) {
      const uint32_t a = j * n + k, b = j * n + (k + 1) % n, c = a + n, d = b + n;
      m.triangles.push_back({a, b, d});
      m.triangles.push_back({a, d, c});
      if (bore > 0) {  // the bore's wall faces its axis
        m.triangles.push_back({in + a, in + d, in + b});
        m.triangles.push_back({in + a, in + c, in + d});
      }
    }
  const uint32_t last = (stations - 1) * n;
  if (bore > 0) {
    for (uint32_t k = 0; k < n; ++k) {
      const uint32_t k1 = (k + 1) % n;
      m.triangles.push_back({in + k, k1, k});
      m.triangles.push_back({in + k, in + k1, k1});
      m.triangles.push_back({in + last + k, last + k, last + k1});
      m.triangles.push_back({in + last + k, last + k1, in + last + k1});
    }
    return m;
  }
  const uint32_t bottom = uint32_t(m.points.size()), top = bottom + 1;
  m.points.push_back({0, 0, z0});
  m.points.push_back({0, 0, z1});
  for (uint32_t k = 0; k < n; ++k) {
    m.triangles.push_back({bottom, (k + 1) % n, k});
    m.triangles.push_back({top, last + k, last + (k + 1) % n});
  }
  return m;
}

HostileMesh thin_pieces(int scale, uint32_t seed) {
  Rng rng(seed);
  // A long, thin assembly of 12 profiled bars (every other one a tube), 1000 long and a few
  // percent of that across, in three lanes: five and six bars laid end to end, nearly meeting
  // at their ends, and one bar the whole length in one span (needles a thousand long). Bars of
  // neighbouring lanes lie a hair apart where their teeth face each other, and one thicker bar
  // reaches into the next lanes (their teeth's tips cross its roots). Thousands of sharp edges run along the bars
  // (every tooth's tip and root) and round their caps.
  Mesh m;
  const double lane_radius = 6;  // the lanes' axes are two of these apart
  const int bars_in_lane[3] = {5, 6, 1};
  Vec3 inside{0, 0, 0};
  int bar_number = 0;
  for (int lane = 0; lane < 3; ++lane) {
    const double angle = 2 * M_PI * lane / 3, axis = 2 * lane_radius / std::sqrt(3.0);
    const int bars = bars_in_lane[lane];
    double z = -500;
    for (int k = 0; k < bars; ++k, ++bar_number) {
      const bool last = k + 1 == bars;
      const double radius = lane_radius * (lane == 0 && k == 1 ? 1.6 : 1 - rng.u(0.001, 0.03));
      const double length = last ? 500 - z : rng.u(0.8, 1.2) * 1000 / bars;
      const double gap = last ? 0 : rng.u(0.05, 0.5);  // to the next bar of the lane
      const int teeth = (6 + int(rng.below(5))) * scale, stations = bars == 1 ? 2 : 2 + int(rng.below(3));
      const double bore = bar_number % 2 ? 0.4 * radius : 0;
      const Mesh bar = profiled_bar(radius, bore, teeth, 3, stations, 0, length - gap, rng.u(-0.1, 0.1));
      Frame f;
      f.origin = {axis * std::cos(angle), axis * std::sin(angle), z};
      if (bar_number == 0) inside = add(f.origin, {0, 0, 0.5 * length});  // a solid one
      append(m, bar, "bar" + std::to_string(bar_number), &f);
      z += length;
    }
  }
  // The whole assembly tilted, so the bars cross the axes.
  const Frame tilt = random_frame(rng, {rng.u(-50, 50), rng.u(-50, 50), rng.u(-50, 50)});
  for (Vec3& p : m.points) p = tilt.apply(p);
  return finish("thin_pieces", scale, seed, m, "stl", tilt.apply(inside));
}

HostileMesh tiny_parts(int scale, uint32_t seed) {
  Rng rng(seed);
  // Many separate tetrahedra, 1/1000 of the scene across, some overlapping.
  Mesh m;
  const int count = 150 * scale;
  Vec3 first{0, 0, 0};
  for (int i = 0; i < count; ++i) {
    const Vec3 c{rng.u(0, 1), rng.u(0, 1), rng.u(0, 1)};
    if (i == 0) first = c;
    const double s = rng.u(0.5e-3, 2e-3);
    Mesh tet;
    tet.points = {add(c, {s, s, s}), add(c, {s, -s, -s}), add(c, {-s, s, -s}), add(c, {-s, -s, s})};
    tet.triangles = {{0, 1, 2}, {0, 3, 1}, {0, 2, 3}, {1, 3, 2}};
    append(m, tet, "p" + std::to_string(i));
  }
  return finish("tiny_parts", scale, seed, m, "obj", first);
}

HostileMesh anisotropic_sphere(int scale, uint32_t seed) {
  (void)seed;
  // 12 rings of 400 segments: needles at the poles.
  Mesh m = vdbwrap::testing::sphere_mesh(1.0, 12, 400 * scale);
  return finish("anisotropic_sphere", scale, seed, m, "stl", {0, 0, 0});
}

HostileMesh scaled(const std::string& kind, int scale, uint32_t seed, double factor, const Vec3& offset,
                   const std::string& ext) {
  Mesh m = small_dirty_solid(scale);
  for (Vec3& p : m.points) p = add(mul(p, factor), offset);
  return finish(kind, scale, seed, m, ext, add(mul(Vec3{0.25, 0.25, 0.5}, factor), offset));
}

// The dirty solid written as a soup whose corners miss each other by up to a thousandth of its
// size: gaps of an exporter's tolerance along every edge, the faces tilted by as much.
HostileMesh gapped_soup(int scale, uint32_t seed) {
  Rng rng(seed);
  const Mesh s = small_dirty_solid(scale);
  Mesh m;
  for (const Tri& t : s.triangles) {
    const uint32_t first = uint32_t(m.points.size());
    for (uint32_t v : t)
      m.points.push_back(add(s.points[v], {rng.u(-2e-3, 2e-3), rng.u(-2e-3, 2e-3), rng.u(-2e-3, 2e-3)}));
    m.triangles.push_back({first, first + 1, first + 2});
  }
  return finish("gapped_soup", scale, seed, m, "stl", {0.25, 0.25, 0.5});
}

// Three closed shells one inside the other (a hollow print's walls exported twice, a scan's
// inner and outer surfaces).
HostileMesh nested_shells(int scale, uint32_t seed) {
  (void)seed;
  Mesh m;
  for (double r : {1.0, 0.8, 0.6}) append(m, vdbwrap::testing::icosphere_mesh(r, scale >= 4 ? 4 : 3), "shell");
  return finish("nested_shells", scale, seed, m, "stl", {0.9, 0, 0});
}

// The dirty solid and one tiny triangle a thousand times its size away (a stray vertex of an
// export): the box, and so the base size, is the outlier's.
HostileMesh far_outlier(int scale, uint32_t seed) {
  Rng rng(seed);
  Mesh m = small_dirty_solid(scale);
  const Vec3 far{rng.u(900, 1100), rng.u(-100, 100), rng.u(-100, 100)};
  const uint32_t a = uint32_t(m.points.size());
  m.points.push_back(far);
  m.points.push_back(add(far, {1e-3, 0, 0}));
  m.points.push_back(add(far, {0, 1e-3, 0}));
  m.triangles.push_back({a, a + 1, a + 2});
  return finish("far_outlier", scale, seed, m, "stl", {0.25, 0.25, 0.5});
}

HostileMesh unreferenced_vertices(int scale, uint32_t seed) {
  Rng rng(seed);
  Mesh m = grid_box({0, 0, 0}, {1, 1, 1}, 3 * scale);
  // Vertices no triangle uses: inside the box, and far outside it.
  for (int i = 0; i < 5000 * scale; ++i) m.points.push_back({rng.u(0, 1), rng.u(0, 1), rng.u(0, 1)});
  for (int i = 0; i < 20; ++i) m.points.push_back({rng.u(-1e4, 1e4), rng.u(-1e4, 1e4), rng.u(-1e4, 1e4)});
  return finish("unreferenced_vertices", scale, seed, m, seed % 2 ? "ply" : "obj", {0.5, 0.5, 0.5});
}

HostileMesh refused(const std::string& kind, int scale, uint32_t seed, const std::string& ext, std::string bytes,
                    const std::string& word) {
  HostileMesh h;
  h.kind = kind;
  h.file_name = kind + "_s" + std::to_string(scale) + "_" + std::to_string(seed) + "." + ext;
  h.bytes = std::move(bytes);
  h.must_be_refused = true;
  h.refusal_word = word;
  return h;
}

HostileMesh nan_coordinates(int scale, uint32_t seed) {
  Rng rng(seed);
  Mesh m = grid_box({0, 0, 0}, {1, 1, 1}, 2 * scale);
  // Binary STL: one coordinate of one facet in the middle of the file is a NaN.
  std::string bytes = binary_stl_bytes(m);
  const size_t facet = rng.below(uint32_t(m.triangles.size()));
  const float nan = std::nanf("");
  std::memcpy(&bytes[84 + facet * 50 + 12 + 4 * rng.below(9)], &nan, 4);
  return refused("nan_coordinates", scale, seed, "stl", bytes, "non-finite");
}

HostileMesh inf_coordinates(int scale, uint32_t seed) {
  Mesh m = grid_box({0, 0, 0}, {1, 1, 1}, 2 * scale);
  std::string text = io::write_mesh_to_bytes(m, io::Format::Obj);
  // The last vertex line gets an infinite coordinate.
  const size_t f = text.find("\nf ");
  const size_t line = text.rfind("\nv ", f);
  text.replace(line, text.find('\n', line + 1) - line, "\nv 0.5 " + std::string(seed % 2 ? "inf" : "-inf") + " 0.5");
  return refused("inf_coordinates", scale, seed, "obj", text, "non-finite");
}

HostileMesh empty_file(int scale, uint32_t seed) { return refused("empty_file", scale, seed, "stl", "", "empty"); }

HostileMesh no_triangles(int scale, uint32_t seed) {
  Rng rng(seed);
  std::string text;
  for (int i = 0; i < 100 * scale; ++i)
    text += "v " + std::to_string(rng.u()) + " " + std::to_string(rng.u()) + " " + std::to_string(rng.u()) + "\n";
  return refused("no_triangles", scale, seed, "obj", text, "no triangles");
}

using Maker = std::function<HostileMesh(int, uint32_t)>;

const std::vector<std::pair<std::string, Maker>>& makers() {
  static const std::vector<std::pair<std::string, Maker>> list = {
      {"degenerate", degenerate},
      {"needles_slivers", needles_slivers},
      {"duplicates", duplicates},
      {"coplanar_overlap", coplanar_overlap},
      {"nonmanifold_fan", nonmanifold_fan},
      {"t_junctions", t_junctions},
      {"inconsistent_orientation", inconsistent_orientation},
      {"csg_intersecting", csg_intersecting},
      {"csg_export", csg_export},
      {"open_scan", open_scan},
      {"open_sheet", open_sheet},
      {"single_triangle", single_triangle},
      {"point_like", point_like},
      {"all_degenerate", all_degenerate},
      {"flat", flat},
      {"long_thin", long_thin},
      {"tiny_parts", tiny_parts},
      {"thin_pieces", thin_pieces},
      {"anisotropic_sphere", anisotropic_sphere},
      {"tiny_coordinates",
       [](int s, uint32_t seed) {
         return scaled("tiny_coordinates", s, seed, 1e-9, {0, 0, 0}, "obj");
       }},
      {"huge_coordinates",
       [](int s, uint32_t seed) {
         return scaled("huge_coordinates", s, seed, 1e9, {0, 0, 0}, "ply");
       }},
      {"far_offset",
       [](int s, uint32_t seed) {
         return scaled("far_offset", s, seed, 1.0, {1e7, 1e7, 1e7}, "obj");
       }},
      // The same in binary STL: float32 has a resolution of 1 at 1e7, the unit solid collapses.
      {"far_offset_float",
       [](int s, uint32_t seed) {
         return scaled("far_offset_float", s, seed, 1.0, {1e7, 1e7, 1e7}, "stl");
       }},
      {"unreferenced_vertices", unreferenced_vertices},
      {"nan_coordinates", nan_coordinates},
      {"inf_coordinates", inf_coordinates},
      {"empty_file", empty_file},
      {"no_triangles", no_triangles},
      {"gapped_soup", gapped_soup},
      {"nested_shells", nested_shells},
      {"far_outlier", far_outlier},
  };
  return list;
}

}  // namespace

std::string binary_stl_bytes(const Mesh& m) {
  std::string s(80, ' ');
  s.replace(0, 20, "vdbwrap hostile mesh");
  const uint32_t n = uint32_t(m.triangles.size());
  s.append(reinterpret_cast<const char*>(&n), 4);
  for (const Tri& t : m.triangles) {
    float v[12] = {0, 0, 0};  // the normal: readers ignore it
    for (int k = 0; k < 3; ++k)
      for (int c = 0; c < 3; ++c) v[3 + 3 * k + c] = float(m.points[t[k]][c]);
    s.append(reinterpret_cast<const char*>(v), 48);
    s.append(2, '\0');
  }
  return s;
}

const std::vector<std::string>& hostile_kinds() {
  static const std::vector<std::string> kinds = [] {
    std::vector<std::string> k;
    for (const auto& [name, maker] : makers()) k.push_back(name);
    return k;
  }();
  return kinds;
}

HostileMesh make_hostile(const std::string& kind, int scale, uint32_t seed) {
  if (scale < 1 || scale > 16) throw std::invalid_argument("scale must be 1..16");
  for (const auto& [name, maker] : makers())
    if (name == kind) return maker(scale, seed);
  throw std::invalid_argument("unknown hostile mesh kind: " + kind);
}

}  // namespace vdbwrap::stress
