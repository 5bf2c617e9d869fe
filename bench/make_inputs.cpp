// Large dirty inputs for the benchmark (issue 6), written as binary STL.
//
//   make_inputs assembly OUT.stl [--density K] [--seed S]
//     An assembly of overlapping tessellated solids (CAD-like cylinders with long thin
//     triangles, boxes with fan-tessellated faces, UV spheres) on a 6 x 6 x 3 lattice, each
//     turned at random and pushed into its neighbours; dirt added: duplicated triangles,
//     degenerate slivers, small gaps (dropped triangles), some solids inside out.
//     Triangles grow as K^2: K = 1 gives ~150k, K = 2 ~600k, K = 4 ~2.3M (the same scene).
//   make_inputs smooth OUT.stl [--density K]
//     A finely tessellated smooth body (a bumpy torus), ~1M triangles at K = 1.
//
// Deterministic for a given seed, so runs on different machines wrap the same scene.
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <random>
#include <string>

#include "common/vec.h"
#include "vdbwrap/io.h"

using namespace vdbwrap;

namespace {

struct Frame {
  Vec3 origin;
  double r[3][3];
  Vec3 apply(const Vec3& p) const {
    return {origin[0] + r[0][0] * p[0] + r[0][1] * p[1] + r[0][2] * p[2],
            origin[1] + r[1][0] * p[0] + r[1][1] * p[1] + r[1][2] * p[2],
            origin[2] + r[2][0] * p[0] + r[2][1] * p[1] + r[2][2] * p[2]};
  }
};

Frame random_frame(std::mt19937& rng, const Vec3& origin) {
  std::uniform_real_distribution<double> u(0, 2 * M_PI);
  const double a = u(rng), b = u(rng), c = u(rng);
  const double ca = std::cos(a), sa = std::sin(a), cb = std::cos(b), sb = std::sin(b), cc = std::cos(c),
               sc = std::sin(c);
  Frame f;
  f.origin = origin;
  // Rz(a) * Ry(b) * Rx(c)
  const double m[3][3] = {{ca * cb, ca * sb * sc - sa * cc, ca * sb * cc + sa * sc},
                          {sa * cb, sa * sb * sc + ca * cc, sa * sb * cc - ca * sc},
                          {-sb, cb * sc, cb * cc}};
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) f.r[i][j] = m[i][j];
  return f;
}

class Builder {
 public:
  explicit Builder(Mesh& m) : m_(m) {}
  uint32_t point(const Frame& f, const Vec3& p) {
    m_.points.push_back(f.apply(p));
    return uint32_t(m_.points.size() - 1);
  }
  void tri(uint32_t a, uint32_t b, uint32_t c, bool flip) {
    m_.triangles.push_back(flip ? Tri{a, c, b} : Tri{a, b, c});
  }

  // CAD-style cylinder: rings only at the ends (long thin side triangles), fan caps.
  void cylinder(const Frame& f, double r, double h, int segments, bool flip) {
    const uint32_t c0 = point(f, {0, 0, 0}), c1 = point(f, {0, 0, h});
    std::vector<uint32_t> lo, hi;
    for (int j = 0; j < segments; ++j) {
      double a = 2 * M_PI * j / segments;
      lo.push_back(point(f, {r * std::cos(a), r * std::sin(a), 0}));
      hi.push_back(point(f, {r * std::cos(a), r * std::sin(a), h}));
    }
    for (int j = 0; j < segments; ++j) {
      int k = (j + 1) % segments;
      tri(c0, lo[k], lo[j], flip);
      tri(c1, hi[j], hi[k], flip);
      tri(lo[j], lo[k], hi[k], flip);
      tri(lo[j], hi[k], hi[j], flip);
    }
  }

  // Box with each face an n x n grid of quads.
  void box(const Frame& f, const Vec3& size, int n, bool flip) {
    for (int axis = 0; axis < 3; ++axis)
      for (int side = 0; side < 2; ++side) {
        const int u = (axis + 1) % 3, v = (axis + 2) % 3;
        std::vector<uint32_t> grid((n + 1) * (n + 1));
        for (int i = 0; i <= n; ++i)
          for (int j = 0; j <= n; ++j) {
            Vec3 p;
            p[axis] = side ? size[axis] / 2 : -size[axis] / 2;
            p[u] = (double(i) / n - 0.5) * size[u];
            p[v] = (double(j) / n - 0.5) * size[v];
            grid[i * (n + 1) + j] = point(f, p);
          }
        for (int i = 0; i < n; ++i)
          for (int j = 0; j < n; ++j) {
            uint32_t a = grid[i * (n + 1) + j], b = grid[(i + 1) * (n + 1) + j], c = grid[(i + 1) * (n + 1) + j + 1],
                     d = grid[i * (n + 1) + j + 1];
            const bool out = side == 1;  // outward: counter-clockwise seen from outside
            tri(a, out ? b : d, c, flip);
            tri(a, c, out ? d : b, flip);
          }
      }
  }

  void sphere(const Frame& f, double r, int rings, bool flip) {
    const int segments = 2 * rings;
    const uint32_t north = point(f, {0, 0, r});
    std::vector<uint32_t> ring_start;
    for (int i = 1; i < rings; ++i) {
      ring_start.push_back(uint32_t(m_.points.size()));
      double th = M_PI * i / rings;
      for (int j = 0; j < segments; ++j) {
        double ph = 2 * M_PI * j / segments;
        point(f, {r * std::sin(th) * std::cos(ph), r * std::sin(th) * std::sin(ph), r * std::cos(th)});
      }
    }
    const uint32_t south = point(f, {0, 0, -r});
    auto at = [&](int i, int j) { return ring_start[i - 1] + uint32_t(j % segments); };
    for (int j = 0; j < segments; ++j) tri(north, at(1, j), at(1, j + 1), flip);
    for (int i = 1; i + 1 < rings; ++i)
      for (int j = 0; j < segments; ++j) {
        tri(at(i, j), at(i + 1, j), at(i + 1, j + 1), flip);
        tri(at(i, j), at(i + 1, j + 1), at(i, j + 1), flip);
      }
    for (int j = 0; j < segments; ++j) tri(south, at(rings - 1, j + 1), at(rings - 1, j), flip);
  }

 private:
  Mesh& m_;
};

Mesh assembly(int density, unsigned seed) {
  Mesh m;
  Builder b(m);
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> jitter(-0.25, 0.25), size(0.8, 1.4);
  std::uniform_int_distribution<int> kind(0, 2);
  std::bernoulli_distribution inside_out(0.1);
  const int k = density;
  for (int x = 0; x < 6; ++x)
    for (int y = 0; y < 6; ++y)
      for (int z = 0; z < 3; ++z) {
        // Lattice spacing 1.5, solids about 1.2 across: neighbours overlap.
        Frame f = random_frame(rng, {1.5 * x + jitter(rng), 1.5 * y + jitter(rng), 1.5 * z + jitter(rng)});
        const bool flip = inside_out(rng);
        const double s = size(rng);
        switch (kind(rng)) {
          case 0:
            b.cylinder(f, 0.45 * s, 1.6 * s, 250 * k * k, flip);
            break;
          case 1:
            b.box(f, {1.1 * s, 0.9 * s, 0.7 * s}, 12 * k, flip);
            break;
          default:
            b.sphere(f, 0.65 * s, 18 * k, flip);
            break;
        }
      }
  // Dirt: duplicates, slivers, gaps.
  std::uniform_int_distribution<size_t> pick(0, m.triangles.size() - 1);
  const size_t n = m.triangles.size();
  for (size_t i = 0; i < n / 100; ++i) m.triangles.push_back(m.triangles[pick(rng)]);
  for (size_t i = 0; i < n / 1000; ++i) {
    Tri t = m.triangles[pick(rng)];
    m.triangles.push_back({t[0], t[1], t[1]});  // degenerate: a repeated vertex
  }
  for (size_t i = 0; i < n / 2000; ++i)
    m.triangles[pick(rng)] = m.triangles[pick(rng)];  // a dropped triangle (gap), duplicated elsewhere
  return m;
}

Mesh smooth_body(int density) {
  // Bumpy torus: R = 3, r = 1 + 0.15 sin(5u) cos(3v); a (u, v) grid of 1000K x 500K quads.
  Mesh m;
  const int nu = 1000 * density, nv = 500 * density;
  m.points.reserve(size_t(nu) * nv);
  for (int i = 0; i < nu; ++i)
    for (int j = 0; j < nv; ++j) {
      double u = 2 * M_PI * i / nu, v = 2 * M_PI * j / nv;
      double r = 1 + 0.15 * std::sin(5 * u) * std::cos(3 * v);
      m.points.push_back({(3 + r * std::cos(v)) * std::cos(u), (3 + r * std::cos(v)) * std::sin(u), r * std::sin(v)});
    }
  auto at = [&](int i, int j) { return uint32_t((i % nu) * nv + (j % nv)); };
  for (int i = 0; i < nu; ++i)
    for (int j = 0; j < nv; ++j) {
      m.triangles.push_back({at(i, j), at(i + 1, j), at(i + 1, j + 1)});
      m.triangles.push_back({at(i, j), at(i + 1, j + 1), at(i, j + 1)});
    }
  return m;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 3) {
    std::fprintf(stderr, "usage: make_inputs assembly|smooth OUT.stl [--density K] [--seed S]\n");
    return 2;
  }
  const std::string what = argv[1], out = argv[2];
  int density = 1;
  unsigned seed = 7;
  for (int i = 3; i + 1 < argc; i += 2) {
    std::string opt = argv[i];
    if (opt == "--density")
      density = std::atoi(argv[i + 1]);
    else if (opt == "--seed")
      seed = unsigned(std::atoi(argv[i + 1]));
    else {
      std::fprintf(stderr, "unknown option %s\n", opt.c_str());
      return 2;
    }
  }
  if (density < 1 || density > 16) {
    std::fprintf(stderr, "--density must be 1..16\n");
    return 2;
  }
  Mesh m;
  if (what == "assembly")
    m = assembly(density, seed);
  else if (what == "smooth")
    m = smooth_body(density);
  else {
    std::fprintf(stderr, "unknown scene %s (assembly or smooth)\n", what.c_str());
    return 2;
  }
  io::write_mesh(m, out);
  std::printf("%s: %zu triangles\n", out.c_str(), m.triangles.size());
  return 0;
}
