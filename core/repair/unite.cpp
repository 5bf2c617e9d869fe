// The repair's exact-construction translation unit: the union of closed bodies (CGAL
// corefinement) and inside tests against the united solid.
#include "repair/unite.h"

#include <CGAL/Exact_predicates_exact_constructions_kernel.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Polygon_mesh_processing/corefinement.h>
#include <CGAL/Polygon_mesh_processing/orientation.h>
#include <CGAL/Polygon_mesh_processing/self_intersections.h>
#include <CGAL/Side_of_triangle_mesh.h>
#include <CGAL/Surface_mesh.h>

#include <cstdio>
#include <cstdlib>
#include <algorithm>
#include <map>

#include "common/debug_switch.h"
#include "common/float_round.h"

namespace vdbwrap::local_repair {
namespace {

using EK = CGAL::Exact_predicates_exact_constructions_kernel;
using EMesh = CGAL::Surface_mesh<EK::Point_3>;
using IK = CGAL::Exact_predicates_inexact_constructions_kernel;
using IMesh = CGAL::Surface_mesh<IK::Point_3>;
namespace PMP = CGAL::Polygon_mesh_processing;

template <typename SM, typename P>
bool build(const std::vector<Vec3>& points, const std::vector<Tri>& tris, SM& m) {
  std::map<uint32_t, typename SM::Vertex_index> local;
  auto vertex = [&](uint32_t g) {
    auto it = local.find(g);
    if (it != local.end()) return it->second;
    auto v = m.add_vertex(P(points[g][0], points[g][1], points[g][2]));
    local.emplace(g, v);
    return v;
  };
  for (const Tri& t : tris)
    if (m.add_face(vertex(t[0]), vertex(t[1]), vertex(t[2])) == SM::null_face()) return false;
  return true;
}

}  // namespace

Union unite_bodies(const std::vector<Vec3>& points, const std::vector<std::vector<Tri>>& bodies,
                   bool float_coordinates) {
  Union out;
  auto fail = [&](const std::string& why) {
    out.ok = false;
    out.why = why;
    return out;
  };
  if (bodies.size() < 2) return fail("fewer than two bodies");
  std::vector<EMesh> meshes(bodies.size());
  for (size_t i = 0; i < bodies.size(); ++i) {
    EMesh& m = meshes[i];
    if (!build<EMesh, EK::Point_3>(points, bodies[i], m)) return fail("a body is not a manifold surface");
    if (!CGAL::is_closed(m)) return fail("a body is not closed");
    if (PMP::does_self_intersect(m)) return fail("a body cuts itself");
    if (!PMP::does_bound_a_volume(m)) return fail("a body does not bound a volume");
  }
  // Body by body; one whose union with the bodies so far would not be manifold (touching
  // them only along an edge or at a corner) waits until others have joined.
  EMesh acc = std::move(meshes[0]);
  std::vector<size_t> waiting;
  for (size_t i = 1; i < meshes.size(); ++i) waiting.push_back(i);
  while (!waiting.empty()) {
    std::vector<size_t> still;
    for (size_t i : waiting) {
      EMesh a = acc, b = meshes[i], result;
      if (PMP::corefine_and_compute_union(a, b, result)) {
        acc = std::move(result);
      } else {
        if (debug::setting("VDBWRAP_REPAIR_DEBUG")) std::fprintf(stderr, "[repair] unite: body %zu waits\n", i);
        still.push_back(i);
      }
    }
    if (still.size() == waiting.size()) return fail("the union is not a closed manifold surface");
    waiting = std::move(still);
  }
  std::map<EMesh::Vertex_index, uint32_t> index;
  for (auto v : acc.vertices()) {
    const auto& p = acc.point(v);
    Vec3 q{CGAL::to_double(p.x()), CGAL::to_double(p.y()), CGAL::to_double(p.z())};
    if (float_coordinates) q = round_to_float(q);
    index.emplace(v, uint32_t(out.points.size()));
    out.points.push_back(q);
  }
  for (auto f : acc.faces()) {
    Tri t;
    int k = 0;
    for (auto v : CGAL::vertices_around_face(acc.halfedge(f), acc)) {
      if (k == 3) return fail("the union has a face that is not a triangle");
      t[k++] = index.at(v);
    }
    if (k != 3) return fail("the union has a face that is not a triangle");
    out.triangles.push_back(t);
  }
  // CGAL's output order follows its internal containers, which can follow memory addresses:
  // points sorted by coordinates, each triangle from its smallest index, triangles sorted, so
  // the same bodies give the same union on every run and thread count.
  std::vector<uint32_t> order(out.points.size());
  for (uint32_t i = 0; i < order.size(); ++i) order[i] = i;
  std::stable_sort(order.begin(), order.end(), [&](uint32_t a, uint32_t b) { return out.points[a] < out.points[b]; });
  std::vector<uint32_t> rank(order.size());
  std::vector<Vec3> sorted(order.size());
  for (uint32_t i = 0; i < order.size(); ++i) rank[order[i]] = i, sorted[i] = out.points[order[i]];
  out.points = std::move(sorted);
  for (Tri& t : out.triangles) {
    for (uint32_t& v : t) v = rank[v];
    while (t[0] > t[1] || t[0] > t[2]) t = {t[1], t[2], t[0]};
  }
  std::sort(out.triangles.begin(), out.triangles.end());
  out.ok = true;
  return out;
}

bool coplanar_pair(const std::vector<Vec3>& points, const Tri& a, const Tri& b) {
  auto P = [&](uint32_t v) { return IK::Point_3(points[v][0], points[v][1], points[v][2]); };
  for (uint32_t v : b)
    if (!CGAL::coplanar(P(a[0]), P(a[1]), P(a[2]), P(v))) return false;
  return true;
}

struct SolidTest::Impl {
  IMesh mesh;
  std::unique_ptr<CGAL::Side_of_triangle_mesh<IMesh, IK>> side;
};

SolidTest::SolidTest(const std::vector<Vec3>& points, const std::vector<Tri>& triangles) : impl_(new Impl) {
  if (build<IMesh, IK::Point_3>(points, triangles, impl_->mesh) && CGAL::is_closed(impl_->mesh))
    impl_->side.reset(new CGAL::Side_of_triangle_mesh<IMesh, IK>(impl_->mesh));
}

SolidTest::~SolidTest() = default;

bool SolidTest::inside(const Vec3& q) const {
  return impl_->side && (*impl_->side)(IK::Point_3(q[0], q[1], q[2])) == CGAL::ON_BOUNDED_SIDE;
}

bool SolidTest::outside(const Vec3& q) const {
  return !impl_->side || (*impl_->side)(IK::Point_3(q[0], q[1], q[2])) == CGAL::ON_UNBOUNDED_SIDE;
}

}  // namespace vdbwrap::local_repair
