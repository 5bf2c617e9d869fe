// The repair's CGAL translation unit: hole filling, refinement and fairing of one region.
#include "repair/refill.h"

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Polygon_mesh_processing/fair.h>
#include <CGAL/Polygon_mesh_processing/triangulate_hole.h>
#include <CGAL/Surface_mesh.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <unordered_map>
#include <unordered_set>

#include "check/intersections.h"
#include "common/edge_key.h"
#include "common/float_round.h"
#include "common/vec.h"
#include "fit/surface_index.h"

namespace vdbwrap::local_repair {
namespace {

using K = CGAL::Exact_predicates_inexact_constructions_kernel;
using SurfaceMesh = CGAL::Surface_mesh<K::Point_3>;
namespace PMP = CGAL::Polygon_mesh_processing;

Refill fail(const std::string& why) {
  Refill r;
  r.why = why;
  return r;
}

// Live triangles on edge (u, v).
size_t edge_use(const std::vector<Tri>& triangles, const VertexFaces& faces, uint32_t u, uint32_t v) {
  size_t n = 0;
  for (const uint32_t* f = faces.begin(u); f != faces.end(u); ++f) {
    const Tri& t = triangles[*f];
    n += (t[0] == v || t[1] == v || t[2] == v) ? 1 : 0;
  }
  return n;
}

// Points spread over a triangle set: a barycentric grid of 15 per triangle (corners, edges
// in quarters, inside).
std::vector<Vec3> samples_on(const std::vector<Vec3>& p, const std::vector<Tri>& tris) {
  constexpr int n = 4;
  std::vector<Vec3> out;
  out.reserve(tris.size() * 15);
  for (const Tri& t : tris)
    for (int i = 0; i <= n; ++i)
      for (int j = 0; i + j <= n; ++j) {
        double u = double(i) / n, v = double(j) / n;
        out.push_back(p[t[0]] * u + p[t[1]] * v + p[t[2]] * (1 - u - v));
      }
  return out;
}

double area_of(const std::vector<Vec3>& p, const std::vector<Tri>& tris) {
  double a = 0;
  for (const Tri& t : tris) a += 0.5 * norm(area_vector(p[t[0]], p[t[1]], p[t[2]]));
  return a;
}

}  // namespace

Refill refill_region(const std::vector<Vec3>& points, const std::vector<Tri>& triangles, const VertexFaces& faces,
                     const std::vector<uint32_t>& region, const RefillParams& params, const fit::SurfaceIndex* original) {
  if (region.empty()) return fail("empty region");
  auto in_region = [&](uint32_t t) { return std::binary_search(region.begin(), region.end(), t); };

  // 1. The contour: region edges used once in the region, each with one triangle outside it
  //    or none (the mesh's own border, kept as it is); a non-manifold edge stops the refill.
  std::unordered_map<uint64_t, int> used;
  std::unordered_map<uint64_t, std::pair<uint32_t, uint32_t>> directed;
  for (uint32_t t : region) {
    const Tri& tri = triangles[t];
    for (int k = 0; k < 3; ++k) {
      uint32_t u = tri[k], v = tri[(k + 1) % 3];
      if (u == v) return fail("degenerate triangle (repeated vertex) in the region");
      ++used[edge_key(u, v)];
      directed[edge_key(u, v)] = {u, v};
    }
  }
  std::unordered_map<uint32_t, uint32_t> next;  // contour, in the region's orientation
  bool open = false;                             // part of the contour is the mesh's border
  for (const auto& [key, count] : used) {
    uint32_t u = uint32_t(key >> 32), v = uint32_t(key & 0xffffffffu);
    size_t total = edge_use(triangles, faces, u, v);
    if (count > 2) return fail("non-manifold edge inside the region");
    if (count == 2 && total != 2) return fail("region edge shared with triangles outside it");
    if (count == 1) {
      if (total > 2) return fail("non-manifold edge on the contour");
      open |= total == 1;
      auto [a, b] = directed[key];
      if (!next.emplace(a, b).second) return fail("contour is not a simple loop");
    }
  }
  if (next.size() < 3) return fail("no contour");
  std::vector<uint32_t> loop{next.begin()->first};
  while (loop.size() <= next.size()) {
    auto it = next.find(loop.back());
    if (it == next.end()) return fail("contour is not closed");
    if (it->second == loop.front()) break;
    loop.push_back(it->second);
  }
  if (loop.size() != next.size()) return fail("contour is more than one loop");
  // Vertices inside the region must go with it.
  std::unordered_set<uint32_t> on_contour(loop.begin(), loop.end());
  for (uint32_t v : vertices_of(triangles, region)) {
    if (on_contour.count(v)) continue;
    for (const uint32_t* f = faces.begin(v); f != faces.end(v); ++f)
      if (!in_region(*f)) return fail("region vertex used outside the region");
  }

  // 5. Checks: the same for every way of filling.
  //    Non-degenerate; its border is the contour, same orientation; no edge that already
  //    exists elsewhere; area change; distance to the surface it replaces.
  auto finish = [&](Refill out) -> Refill {
    const uint32_t base = uint32_t(points.size());
    // The patch on its own points (contour vertices and new ones), to measure it.
    std::vector<Vec3> patch_points;
    std::vector<Tri> patch;
    {
      std::unordered_map<uint32_t, uint32_t> at;
      for (const Tri& t : out.triangles) {
        Tri l;
        for (int k = 0; k < 3; ++k) {
          auto [it, added] = at.emplace(t[k], uint32_t(patch_points.size()));
          if (added) patch_points.push_back(t[k] < base ? points[t[k]] : out.new_points[t[k] - base]);
          l[k] = it->second;
        }
        patch.push_back(l);
      }
    }
    for (const Tri& t : patch)
      if (check::triangle_is_degenerate(patch_points, t)) return fail("refill has a degenerate triangle");
    std::unordered_map<uint64_t, std::pair<int, int>> patch_edges;  // count, net direction
    for (const Tri& t : out.triangles)
      for (int k = 0; k < 3; ++k) {
        uint32_t u = t[k], v = t[(k + 1) % 3];
        auto& e = patch_edges[edge_key(u, v)];
        ++e.first;
        e.second += u < v ? 1 : -1;
      }
    size_t border = 0;
    for (const auto& [key, e] : patch_edges) {
      uint32_t u = uint32_t(key >> 32), v = uint32_t(key & 0xffffffffu);
      if (e.first > 2) return fail("refill has a non-manifold edge");
      if (e.first == 2) {
        if (e.second != 0) return fail("refill is not consistently oriented");
        if (u < base && v < base && used.count(key) == 0 && edge_use(triangles, faces, u, v) > 0)
          return fail("refill would make a non-manifold edge");
        if (u < base && v < base) {
          // A chord between contour vertices that is also a contour edge would close the hole wrongly.
          auto it = used.find(key);
          if (it != used.end() && it->second == 1) return fail("refill reuses a contour edge inside");
        }
        continue;
      }
      // Free edge of the patch: must be a contour edge, in the region's direction.
      auto it = used.find(key);
      if (it == used.end() || it->second != 1) return fail("refill leaves a free edge");
      auto [a, b] = directed[key];
      if ((a < b ? 1 : -1) != e.second) return fail("refill is oriented against the mesh");
      ++border;
    }
    if (border != loop.size()) return fail("refill border differs from the contour");

    std::vector<Tri> removed;
    for (uint32_t t : region) removed.push_back(triangles[t]);
    const double area_before = area_of(points, removed), area_after = area_of(patch_points, patch);
    const double hi = std::max(area_before, area_after);
    if (hi <= 0 || std::min(area_before, area_after) / hi < params.area_ratio) return fail("area change too large");

    if (params.max_deviation > 0) {
      const double bound2 = params.max_deviation * params.max_deviation;
      // Refill -> input (or the removed surface when no input is given).
      std::vector<Vec3> from_patch = samples_on(patch_points, patch);
      if (original) {
        for (const Vec3& s : from_patch)
          if (original->squared_distance(s) > bound2) return fail("refill too far from the input");
      } else {
        fit::SurfaceIndex removed_index(points, removed);
        for (const Vec3& s : from_patch)
          if (removed_index.squared_distance(s) > bound2) return fail("refill too far from the removed surface");
      }
      // Removed surface -> refill.
      fit::SurfaceIndex patch_index(patch_points, patch);
      for (const Vec3& s : samples_on(points, removed))
        if (patch_index.squared_distance(s) > bound2) return fail("removed surface too far from the refill");
    }

    // Each new triangle replaces the removed one nearest to it (its part goes on).
    for (const Tri& t : patch) {
      Vec3 c = (patch_points[t[0]] + patch_points[t[1]] + patch_points[t[2]]) * (1.0 / 3);
      uint32_t best = region[0];
      double best_d = INFINITY;
      for (uint32_t r : region) {
        const Tri& x = triangles[r];
        double d = norm2((points[x[0]] + points[x[1]] + points[x[2]]) * (1.0 / 3) - c);
        if (d < best_d) best_d = d, best = r;
      }
      out.replaces.push_back(best);
    }
    out.ok = true;
    return out;
  };

  // Along the mesh's border there is no ring to fair against: the contour alone is
  // triangulated (minimal area, Liepa), tried both ways round.
  if (open) {
    std::vector<K::Point_3> polyline;
    for (uint32_t g : loop) polyline.emplace_back(points[g][0], points[g][1], points[g][2]);
    std::vector<CGAL::Triple<int, int, int>> tris;
    PMP::triangulate_hole_polyline(polyline, std::back_inserter(tris));
    if (tris.empty()) return fail("hole filling found no triangulation");
    std::string why;
    for (bool flip : {false, true}) {
      Refill out;
      for (const auto& t : tris) {
        Tri tri{loop[size_t(t.first)], loop[size_t(t.second)], loop[size_t(t.third)]};
        if (flip) std::swap(tri[1], tri[2]);
        out.triangles.push_back(tri);
      }
      Refill r = finish(std::move(out));
      if (r.ok) return r;
      why = r.why;
    }
    return fail(why);
  }

  // 2.-5. Fill, then check; a smooth refill first, then flatter ones (CAD regions: fairing
  //        rounds sharp edges, the plain triangulation keeps planar pieces planar).
  enum class Mode { RefineAndFair, Refine, Triangulate };
  auto attempt = [&](Mode mode) -> Refill {
    // 2. A local mesh: the ring of triangles around the hole gives the fairing its context.
    SurfaceMesh sm;
    std::unordered_map<uint32_t, SurfaceMesh::Vertex_index> local;
    std::vector<uint32_t> global_of;  // local vertex index -> global id
    auto vertex = [&](uint32_t g) {
      auto it = local.find(g);
      if (it != local.end()) return it->second;
      auto v = sm.add_vertex(K::Point_3(points[g][0], points[g][1], points[g][2]));
      local.emplace(g, v);
      global_of.resize(std::max<size_t>(global_of.size(), v.idx() + 1));
      global_of[v.idx()] = g;
      return v;
    };
    std::vector<uint32_t> context;
    for (uint32_t t : grow_ring(triangles, faces, region))
      if (!in_region(t)) context.push_back(t);
    for (uint32_t t : context) {
      const Tri& tri = triangles[t];
      if (tri[0] == tri[1] || tri[1] == tri[2] || tri[0] == tri[2]) continue;
      if (sm.add_face(vertex(tri[0]), vertex(tri[1]), vertex(tri[2])) == SurfaceMesh::null_face())
        return fail("the ring around the region is not manifold");
    }
    for (uint32_t g : loop)
      if (!local.count(g)) return fail("contour vertex without a triangle outside the region");
    // The border halfedge of the hole runs like the removed triangles: loop[0] -> loop[1].
    auto h = sm.halfedge(local[loop[0]], local[loop[1]]);
    if (h == SurfaceMesh::null_halfedge() || !sm.is_border(h)) return fail("hole not found in the local mesh");
    {
      size_t n = 0;
      for (auto g : CGAL::halfedges_around_face(h, sm)) {
        (void)g;
        if (++n > loop.size()) break;
      }
      if (n != loop.size()) return fail("hole border differs from the contour (pinched ring)");
    }

    // 3. Fill (Liepa), refine, fair.
    std::vector<SurfaceMesh::Face_index> patch_faces;
    std::vector<SurfaceMesh::Vertex_index> patch_vertices;
    if (mode == Mode::Triangulate)
      PMP::triangulate_hole(sm, h, std::back_inserter(patch_faces), CGAL::parameters::use_delaunay_triangulation(true));
    else
      PMP::triangulate_and_refine_hole(sm, h, std::back_inserter(patch_faces), std::back_inserter(patch_vertices),
                                       CGAL::parameters::use_delaunay_triangulation(true));
    if (patch_faces.empty()) return fail("hole filling found no triangulation");
    Refill out;
    if (mode == Mode::RefineAndFair && !patch_vertices.empty())
      out.faired = PMP::fair(sm, patch_vertices, CGAL::parameters::fairing_continuity(1));
    if (mode == Mode::RefineAndFair && !out.faired) return fail("fairing failed");

    // 4. Back to global indices: contour vertices keep theirs, new ones follow points.
    const uint32_t base = uint32_t(points.size());
    std::unordered_map<uint32_t, uint32_t> new_index;  // local index -> global-or-new index
    for (auto v : patch_vertices) {
      const auto& p = sm.point(v);
      Vec3 q{p.x(), p.y(), p.z()};
      if (params.float_coordinates) q = round_to_float(q);
      if (!std::isfinite(q[0]) || !std::isfinite(q[1]) || !std::isfinite(q[2])) return fail("refill point not finite");
      new_index[v.idx()] = base + uint32_t(out.new_points.size());
      out.new_points.push_back(q);
    }
    for (auto f : patch_faces) {
      Tri t;
      int k = 0;
      for (auto v : CGAL::vertices_around_face(sm.halfedge(f), sm)) {
        if (k == 3) return fail("refill face is not a triangle");
        auto it = new_index.find(v.idx());
        if (it != new_index.end()) t[k++] = it->second;
        else {
          uint32_t g = global_of[v.idx()];
          if (!on_contour.count(g)) return fail("refill uses a vertex off the contour");
          t[k++] = g;
        }
      }
      if (k != 3) return fail("refill face is not a triangle");
      out.triangles.push_back(t);
    }

    return finish(std::move(out));
  };

  std::string why;
  for (Mode mode : {Mode::RefineAndFair, Mode::Refine, Mode::Triangulate}) {
    if (mode == Mode::RefineAndFair && !params.fair) continue;
    Refill r = attempt(mode);
    if (r.ok) return r;
    if (why.find(r.why) == std::string::npos) why += (why.empty() ? "" : "; ") + r.why;
  }
  return fail(why);
}

}  // namespace vdbwrap::local_repair
