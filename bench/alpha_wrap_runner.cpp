// Runs CGAL's alpha_wrap_3 on a mesh, the reference the benchmark compares vdbwrap with.
// Usage: alpha_wrap_runner INPUT OUTPUT [alpha_fraction=0.01] [offset_fraction=1/3000]
// Prints one JSON line: seconds, triangles, alpha, offset.
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Surface_mesh.h>
#include <CGAL/alpha_wrap_3.h>

#include <chrono>
#include <cstdio>
#include <string>

#include "vdbwrap/io.h"
#include "vdbwrap/errors.h"

using K = CGAL::Exact_predicates_inexact_constructions_kernel;
using Point = K::Point_3;

int main(int argc, char** argv) {
  if (argc < 3) {
    std::fprintf(stderr, "usage: %s INPUT OUTPUT [alpha_fraction] [offset_fraction]\n", argv[0]);
    return 2;
  }
  try {
    vdbwrap::Mesh in = vdbwrap::io::read_mesh(argv[1]);
    const double alpha_fraction = argc > 3 ? std::stod(argv[3]) : 0.01;
    const double offset_fraction = argc > 4 ? std::stod(argv[4]) : 1.0 / 3000.0;
    std::vector<Point> points;
    double lo[3] = {1e300, 1e300, 1e300}, hi[3] = {-1e300, -1e300, -1e300};
    for (const auto& p : in.points) {
      points.emplace_back(p[0], p[1], p[2]);
      for (int k = 0; k < 3; ++k) lo[k] = std::min(lo[k], p[k]), hi[k] = std::max(hi[k], p[k]);
    }
    const double diag = std::sqrt((hi[0] - lo[0]) * (hi[0] - lo[0]) + (hi[1] - lo[1]) * (hi[1] - lo[1]) +
                                  (hi[2] - lo[2]) * (hi[2] - lo[2]));
    std::vector<std::array<std::size_t, 3>> faces;
    for (const auto& t : in.triangles) faces.push_back({t[0], t[1], t[2]});
    CGAL::Surface_mesh<Point> wrap;
    auto t0 = std::chrono::steady_clock::now();
    CGAL::alpha_wrap_3(points, faces, alpha_fraction * diag, offset_fraction * diag, wrap);
    double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    vdbwrap::Mesh out;
    std::vector<uint32_t> index(wrap.number_of_vertices());
    for (auto v : wrap.vertices()) {
      const Point& p = wrap.point(v);
      index[v.idx()] = uint32_t(out.points.size());
      out.points.push_back({p.x(), p.y(), p.z()});
    }
    for (auto f : wrap.faces()) {
      vdbwrap::Tri t;
      int k = 0;
      for (auto v : CGAL::vertices_around_face(wrap.halfedge(f), wrap)) t[k++] = index[v.idx()];
      out.triangles.push_back(t);
    }
    vdbwrap::io::write_mesh(out, argv[2]);
    std::printf("{\"seconds\": %.4f, \"triangles\": %zu, \"alpha\": %.9g, \"offset\": %.9g}\n", seconds,
                out.triangles.size(), alpha_fraction * diag, offset_fraction * diag);
  } catch (const vdbwrap::Error& e) {
    std::fprintf(stderr, "alpha_wrap_runner: %s\n", e.what());
    return vdbwrap::exit_code(e.kind());
  }
  return 0;
}
