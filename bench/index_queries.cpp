// Nearest-point index micro-benchmark: builds mesh::SurfaceIndex on a mesh file and times
// closest(), within() and touches() on points near the surface (input vertices moved off the
// surface by up to `offset` of the diagonal, in random directions). Prints build time, memory
// growth and the median of several rounds per query kind.
//   index_queries MESH [--queries N] [--rounds R] [--offset F]
#include <sys/resource.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>

#include "mesh/surface_index.h"
#include "common/vec.h"
#include "vdbwrap/io.h"

using namespace vdbwrap;

namespace {
double seconds_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}
long peak_rss_mb() {
  rusage u{};
  getrusage(RUSAGE_SELF, &u);
  return u.ru_maxrss / 1024;
}
double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}
}  // namespace

int main(int argc, char** argv) {
  if (argc < 2) {
    std::fprintf(stderr, "usage: index_queries MESH [--queries N] [--rounds R] [--offset F]\n");
    return 2;
  }
  size_t queries = 200000;
  int rounds = 3;
  double offset = 0.003;
  for (int i = 2; i + 1 < argc; i += 2) {
    if (!std::strcmp(argv[i], "--queries")) queries = std::strtoul(argv[i + 1], nullptr, 10);
    if (!std::strcmp(argv[i], "--rounds")) rounds = std::atoi(argv[i + 1]);
    if (!std::strcmp(argv[i], "--offset")) offset = std::atof(argv[i + 1]);
  }
  const Mesh mesh = io::read_mesh(argv[1]);
  Box3 box;
  for (const Vec3& p : mesh.points) box.add(p);
  const double diag = box.diagonal();
  const long rss_before = peak_rss_mb();
  auto t0 = std::chrono::steady_clock::now();
  mesh::SurfaceIndex index(mesh.points, mesh.triangles);
  const double build = seconds_since(t0);
  const long rss_after = peak_rss_mb();

  // Queries in surface order (consecutive triangles), as the pipeline makes them.
  uint64_t state = 42;
  auto uniform = [&] {
    state = state * 6364136223846793005ull + 1442695040888963407ull;
    return double(state >> 11) / double(1ull << 53) * 2 - 1;
  };
  std::vector<Vec3> q(queries);
  for (size_t k = 0; k < queries; ++k) {
    const Tri& t = mesh.triangles[(k * mesh.triangles.size()) / queries];
    const Vec3 c = (mesh.points[t[0]] + mesh.points[t[1]] + mesh.points[t[2]]) * (1.0 / 3.0);
    q[k] = c + Vec3{uniform(), uniform(), uniform()} * (offset * diag);
  }
  std::vector<double> closest_s, within_s, touches_s;
  double sink = 0;
  for (int r = 0; r < rounds; ++r) {
    t0 = std::chrono::steady_clock::now();
    for (const Vec3& p : q) sink += index.closest(p).squared_distance;
    closest_s.push_back(seconds_since(t0));
    t0 = std::chrono::steady_clock::now();
    for (const Vec3& p : q) sink += index.within(p, 0.5 * offset * diag);
    within_s.push_back(seconds_since(t0));
    t0 = std::chrono::steady_clock::now();
    const double h = 0.002 * diag;
    for (const Vec3& p : q) sink += index.touches(p, p + Vec3{h, 0, 0}, p + Vec3{0, h, h});
    touches_s.push_back(seconds_since(t0));
  }
  std::printf(
      "%s: %zu triangles, build %.2f s, +%ld MB; per query (median of %d): closest %.2f us, within %.2f us, touches "
      "%.2f us (%g)\n",
      argv[1], mesh.triangles.size(), build, rss_after - rss_before, rounds, 1e6 * median(closest_s) / queries,
      1e6 * median(within_s) / queries, 1e6 * median(touches_s) / queries, sink > 0 ? 1.0 : 0.0);
  return 0;
}
