#include "report/display_mesh.h"

#include <tbb/parallel_sort.h>

#include <algorithm>
#include <array>
#include <cmath>

#include "common/exact_weld.h"
#include "common/vec.h"

namespace vdbwrap::report {
namespace {

void copy_points(const Mesh& mesh, const Vec3& origin, DisplayMesh& d) {
  d.positions.resize(3 * mesh.points.size());
  for (size_t i = 0; i < mesh.points.size(); ++i)
    for (int k = 0; k < 3; ++k) d.positions[3 * i + k] = float(mesh.points[i][k] - origin[k]);
  d.vertex_of.resize(mesh.points.size());
  for (size_t i = 0; i < d.vertex_of.size(); ++i) d.vertex_of[i] = uint32_t(i);
}

// One clustering pass at cell h over the distinct points (mesh.points welded exactly): false
// when the grid would be too fine to key. d.vertex_of is per distinct point.
bool cluster(const Mesh& mesh, const Box3& box, const Vec3& origin, double h, DisplayMesh& d) {
  const uint64_t kMaxCells = uint64_t(1) << 21;
  for (int k = 0; k < 3; ++k)
    if ((box.hi[k] - box.lo[k]) / h >= double(kMaxCells - 1)) return false;
  struct Keyed {
    uint64_t key;
    uint32_t point;
    bool operator<(const Keyed& o) const { return key != o.key ? key < o.key : point < o.point; }
  };
  std::vector<Keyed> keyed(mesh.points.size());
  for (size_t i = 0; i < mesh.points.size(); ++i) {
    uint64_t key = 0;
    for (int k = 0; k < 3; ++k) {
      const double c = std::floor((mesh.points[i][k] - box.lo[k]) / h);  // NaN: cell 0
      key = (key << 21) | uint64_t(c > 0 ? std::min(c, double(kMaxCells - 1)) : 0.0);
    }
    keyed[i] = {key, uint32_t(i)};
  }
  tbb::parallel_sort(keyed.begin(), keyed.end());
  d.vertex_of.assign(mesh.points.size(), 0);
  std::vector<Vec3> sum;
  std::vector<uint32_t> count;
  for (size_t i = 0; i < keyed.size(); ++i) {
    if (i == 0 || keyed[i].key != keyed[i - 1].key) sum.push_back({0, 0, 0}), count.push_back(0);
    d.vertex_of[keyed[i].point] = uint32_t(sum.size() - 1);
    sum.back() = sum.back() + mesh.points[keyed[i].point];
    ++count.back();
  }
  d.positions.resize(3 * sum.size());
  for (size_t c = 0; c < sum.size(); ++c)
    for (int k = 0; k < 3; ++k) d.positions[3 * c + k] = float(sum[c][k] / count[c] - origin[k]);
  // Triangles whose corners fell into one cluster vanish; of triangles that became the same,
  // the first stays (two would fight for the same pixels).
  struct Kept {
    std::array<uint32_t, 3> sorted;
    uint32_t triangle;
    bool operator<(const Kept& o) const { return sorted != o.sorted ? sorted < o.sorted : triangle < o.triangle; }
  };
  std::vector<Kept> kept;
  for (size_t t = 0; t < mesh.triangles.size(); ++t) {
    std::array<uint32_t, 3> v{d.vertex_of[mesh.triangles[t][0]], d.vertex_of[mesh.triangles[t][1]],
                              d.vertex_of[mesh.triangles[t][2]]};
    if (v[0] == v[1] || v[1] == v[2] || v[0] == v[2]) continue;
    std::sort(v.begin(), v.end());
    kept.push_back({v, uint32_t(t)});
  }
  tbb::parallel_sort(kept.begin(), kept.end());
  std::vector<uint32_t> chosen;
  for (size_t i = 0; i < kept.size(); ++i)
    if (i == 0 || kept[i].sorted != kept[i - 1].sorted) chosen.push_back(kept[i].triangle);
  std::sort(chosen.begin(), chosen.end());
  d.source_triangle = std::move(chosen);
  d.triangles.resize(3 * d.source_triangle.size());
  for (size_t i = 0; i < d.source_triangle.size(); ++i)
    for (int k = 0; k < 3; ++k) d.triangles[3 * i + k] = d.vertex_of[mesh.triangles[d.source_triangle[i]][k]];
  return true;
}

}  // namespace

DisplayMesh display_mesh(const Mesh& mesh, const Vec3& origin, size_t max_triangles, const ExactWeld* known_weld) {
  DisplayMesh d;
  d.mesh_triangles = mesh.triangles.size();
  if (mesh.triangles.size() <= max_triangles || max_triangles == 0) {
    copy_points(mesh, origin, d);
    d.triangles.reserve(3 * mesh.triangles.size());
    d.source_triangle.resize(mesh.triangles.size());
    for (size_t t = 0; t < mesh.triangles.size(); ++t) {
      for (uint32_t v : mesh.triangles[t]) d.triangles.push_back(v);
      d.source_triangle[t] = uint32_t(t);
    }
    return d;
  }
  Box3 box;
  double area = 0;
  for (const Tri& t : mesh.triangles) {
    for (uint32_t v : t) box.add(mesh.points[v]);
    area += 0.5 * norm(area_vector(mesh.points[t[0]], mesh.points[t[1]], mesh.points[t[2]]));
  }
  // An STL repeats every point about six times: clustering sorts the distinct ones.
  ExactWeld made;
  if (!known_weld) made = exact_weld(mesh.points);
  const ExactWeld& weld = known_weld ? *known_weld : made;
  Mesh distinct;
  distinct.points = weld.unique;
  distinct.triangles.resize(mesh.triangles.size());
  for (size_t t = 0; t < mesh.triangles.size(); ++t)
    for (int k = 0; k < 3; ++k) distinct.triangles[t][k] = weld.remap[mesh.triangles[t][k]];
  // A surface crosses about 1.5 cells per h^2 of its area (more when tilted against the
  // grid), and there are about two triangles per cluster.
  double h = std::sqrt(3 * area / double(max_triangles));
  if (!(h > 0)) h = std::max(box.diagonal(), 1e-30) * 1e-3;
  d.clustered = true;
  for (int round = 0; round < 60; ++round, h *= 1.2) {
    if (!cluster(distinct, box, origin, h, d)) continue;
    d.cluster_size = h;
    if (d.source_triangle.size() <= max_triangles) break;
  }
  std::vector<uint32_t> vertex_of(weld.remap.size());
  for (size_t i = 0; i < vertex_of.size(); ++i) vertex_of[i] = d.vertex_of[weld.remap[i]];
  d.vertex_of = std::move(vertex_of);
  return d;
}

std::vector<float> display_values(const DisplayMesh& display, const std::vector<double>& per_point) {
  std::vector<float> out(display.positions.size() / 3, 0.0f);
  std::vector<uint8_t> seen(out.size(), 0);
  for (size_t i = 0; i < per_point.size() && i < display.vertex_of.size(); ++i) {
    const uint32_t v = display.vertex_of[i];
    const float value = float(per_point[i]);
    if (!seen[v] || std::fabs(value) > std::fabs(out[v])) out[v] = value, seen[v] = 1;
  }
  return out;
}

}  // namespace vdbwrap::report
