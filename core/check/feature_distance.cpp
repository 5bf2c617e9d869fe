// Distance from the input's sharp edges to a surface: how well a wrap keeps the edges.
#include <cmath>

#include "check/distance_stats.h"
#include "common/edge_triangles.h"
#include "common/vec.h"
#include "mesh/feature_edges.h"
#include "mesh/orient.h"
#include "mesh/weld.h"
#include "vdbwrap/check.h"

namespace vdbwrap {

namespace {
constexpr size_t kMostSamples = 200000;  // far below that, the mean and p95 hardly move
}  // namespace

DistanceStats sharp_edge_distance(const Mesh& input, const Mesh& surface, double angle_deg, double spacing_fraction) {
  DistanceStats s;
  Box3 box;
  for (const auto& p : input.points) box.add(p);
  s.diagonal = box.diagonal();
  if (input.triangles.empty() || surface.triangles.empty()) return s;
  // Sharp edges as the pipeline sees them: welded, degenerate triangles ignored.
  std::vector<Vec3> welded;
  auto remap = mesh::weld_points(input.points, 1e-7 * s.diagonal, welded);
  std::vector<Tri> tris;
  std::vector<Vec3> normals;
  for (const Tri& t : input.triangles) {
    Tri w{remap[t[0]], remap[t[1]], remap[t[2]]};
    Vec3 n = area_vector(welded[w[0]], welded[w[1]], welded[w[2]]);
    if (w[0] == w[1] || w[1] == w[2] || w[0] == w[2] || norm(n) == 0) continue;
    tris.push_back(w);
    normals.push_back(normalized(n));
  }
  // Orientation matters for the dihedral angle: make it consistent first. One edge listing
  // serves both (flips change no triangle's edges), as in prepare.
  const EdgeTriangles listing = edge_triangles(tris);
  // The creases of solids that touch in faces (voxel art) count, as the wrap sees them; read in
  // the input's orientation, before orienting.
  const auto contact =
      mesh::contact_faces(welded, tris, {}, listing, std::vector<uint8_t>(tris.size(), 0), angle_deg).edges;
  mesh::orient_pieces(welded, tris, &listing);
  for (size_t t = 0; t < tris.size(); ++t)
    normals[t] = normalized(area_vector(welded[tris[t][0]], welded[tris[t][1]], welded[tris[t][2]]));
  auto edges = mesh::find_feature_edges(welded, tris, normals, angle_deg, &listing, &contact);
  const double spacing = spacing_fraction * s.diagonal;
  auto steps = [&](const mesh::FeatureEdge& e) {
    return std::max<size_t>(1, size_t(std::ceil(norm(welded[e.b] - welded[e.a]) / spacing)));
  };
  // A rough scan has a million short sharp edges, each sampled at both ends: every stride-th
  // sample keeps the count near kMostSamples, evenly over all of them.
  size_t count = 0;
  for (const auto& e : edges)
    if (e.kind == mesh::FeatureKind::Sharp) count += steps(e) + 1;
  const size_t stride = std::max<size_t>(1, (count + kMostSamples - 1) / kMostSamples);
  std::vector<Vec3> samples;
  size_t at = 0;
  for (const auto& e : edges) {
    if (e.kind != mesh::FeatureKind::Sharp) continue;
    const Vec3 &a = welded[e.a], &b = welded[e.b];
    const size_t k = steps(e);
    for (size_t i = 0; i <= k; ++i, ++at)
      if (at % stride == 0) samples.push_back(lerp(a, b, double(i) / double(k)));
  }
  return check::distances_to(samples, surface, s.diagonal);
}

}  // namespace vdbwrap
