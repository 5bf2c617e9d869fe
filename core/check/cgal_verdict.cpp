// CGAL's own verdicts on a closed manifold mesh (Polygon Mesh Processing), a second opinion
// beside the pair search.
#include <CGAL/Polygon_mesh_processing/orientation.h>
#include <CGAL/Polygon_mesh_processing/self_intersections.h>
#include <CGAL/Surface_mesh.h>

#include <algorithm>
#include <cmath>
#include <iterator>
#include <stdexcept>

#include "check/exact_kernel.h"
#include "check/intersections.h"

namespace vdbwrap::check {
namespace {
using pair_search::to_point;
using SurfaceMesh = CGAL::Surface_mesh<pair_search::P3>;

bool build_surface_mesh(const std::vector<Vec3>& points, const std::vector<Tri>& triangles, SurfaceMesh& mesh) {
  std::vector<SurfaceMesh::Vertex_index> v(points.size());
  for (size_t i = 0; i < points.size(); ++i) v[i] = mesh.add_vertex(to_point(points[i]));
  for (const Tri& t : triangles)
    if (mesh.add_face(v[t[0]], v[t[1]], v[t[2]]) == SurfaceMesh::null_face()) return false;
  return true;
}
}  // namespace

std::vector<uint32_t> mesh_self_intersecting_faces(const std::vector<Vec3>& points, const std::vector<Tri>& triangles) {
  SurfaceMesh mesh;
  if (!build_surface_mesh(points, triangles, mesh))
    throw std::logic_error("mesh_self_intersecting_faces: not a manifold mesh");
  std::vector<std::pair<SurfaceMesh::Face_index, SurfaceMesh::Face_index>> pairs;
  CGAL::Polygon_mesh_processing::self_intersections<CGAL::Parallel_if_available_tag>(mesh, std::back_inserter(pairs));
  std::vector<uint32_t> out;
  out.reserve(pairs.size() * 2);
  for (const auto& [f, g] : pairs) {
    out.push_back(uint32_t(f.idx()));
    out.push_back(uint32_t(g.idx()));
  }
  std::sort(out.begin(), out.end());
  out.erase(std::unique(out.begin(), out.end()), out.end());
  return out;
}

CgalVerdict cgal_verdict(const std::vector<Vec3>& points, const std::vector<Tri>& triangles) {
  CgalVerdict verdict;
  // A non-finite point would reach the exact predicates' rational conversion (SIGFPE): such a
  // surface is invalid without asking CGAL.
  for (const Vec3& p : points)
    if (!std::isfinite(p[0]) || !std::isfinite(p[1]) || !std::isfinite(p[2])) return verdict;
  for (const Tri& t : triangles)
    if (t[0] >= points.size() || t[1] >= points.size() || t[2] >= points.size()) return verdict;
  SurfaceMesh mesh;
  if (!build_surface_mesh(points, triangles, mesh)) return verdict;
  verdict.valid_polygon_mesh = CGAL::is_valid_polygon_mesh(mesh);
  verdict.closed = CGAL::is_closed(mesh);
  if (!verdict.valid_polygon_mesh || !verdict.closed) return verdict;
  verdict.self_intersects = CGAL::Polygon_mesh_processing::does_self_intersect<CGAL::Parallel_if_available_tag>(mesh);
  if (!verdict.self_intersects) verdict.outward = CGAL::Polygon_mesh_processing::is_outward_oriented(mesh);
  return verdict;
}

}  // namespace vdbwrap::check
