// The rebuild with the input (spec stage 4, first way), in the one translation unit that
// includes CGAL's 2D triangulation headers. The substrate (the input triangles under the
// region) is split into nearly flat patches at its creases (edges whose triangles' normals
// differ by more than the flat angle). The region is projected to its plane, where a
// constrained Delaunay triangulation takes the contour, the kept feature edges and the
// creases as constraints, and interior nodes on a triangular lattice at the characteristic
// spacing. Every node is mapped back onto the patch under it, the wrap's small offset off
// the input kept: the patches' shared edges (the creases) come out as edges of the new
// triangles, and each patch's triangles lie on it. The paper shrinks the contour patch by
// patch; one plane with the creases as constraints gives the same triangles per patch, with
// matching nodes along the creases, in one triangulation.
#include <CGAL/Constrained_Delaunay_triangulation_2.h>
#include <CGAL/Constrained_triangulation_face_base_2.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Triangulation_face_base_with_info_2.h>
#include <CGAL/Triangulation_vertex_base_with_info_2.h>

#include <algorithm>
#include <cmath>
#include <deque>
#include <map>
#include <unordered_map>

#include "common/closest_point.h"
#include "common/edge_key.h"
#include "common/vec.h"
#include "common/vec2.h"
#include "post/region_fill.h"

namespace vdbwrap::post {
namespace {

using K = CGAL::Exact_predicates_inexact_constructions_kernel;
using Vb = CGAL::Triangulation_vertex_base_with_info_2<uint32_t, K>;
using Fbi = CGAL::Triangulation_face_base_with_info_2<int, K>;  // -1 unknown, 0 outside, 1 inside
using Fb = CGAL::Constrained_triangulation_face_base_2<K, Fbi>;
using Tds = CGAL::Triangulation_data_structure_2<Vb, Fb>;
using CDT = CGAL::Constrained_Delaunay_triangulation_2<K, Tds, CGAL::No_constraint_intersection_tag>;

using P2 = Vec2;

double segment_distance(const P2& p, const P2& a, const P2& b) {
  const P2 ab = sub2(b, a), ap = sub2(p, a);
  const double l2 = dot2(ab, ab);
  const double t = l2 > 0 ? std::clamp(dot2(ap, ab) / l2, 0.0, 1.0) : 0.0;
  const P2 d{ap[0] - t * ab[0], ap[1] - t * ab[1]};
  return std::sqrt(dot2(d, d));
}

bool inside_polygon(const P2& p, const std::vector<P2>& poly) {
  bool in = false;
  for (size_t i = 0, j = poly.size() - 1; i < poly.size(); j = i++)
    if ((poly[i][1] > p[1]) != (poly[j][1] > p[1]) &&
        p[0] < (poly[j][0] - poly[i][0]) * (p[1] - poly[i][1]) / (poly[j][1] - poly[i][1]) + poly[i][0])
      in = !in;
  return in;
}

double boundary_distance(const P2& p, const std::vector<P2>& poly) {
  double d = INFINITY;
  for (size_t i = 0; i < poly.size(); ++i) d = std::min(d, segment_distance(p, poly[i], poly[(i + 1) % poly.size()]));
  return d;
}

bool segments_cross(const P2& a, const P2& b, const P2& c, const P2& d) {
  auto o = [](const P2& p, const P2& q, const P2& r) { return cross2(sub2(q, p), sub2(r, p)); };
  const double o1 = o(a, b, c), o2 = o(a, b, d), o3 = o(c, d, a), o4 = o(c, d, b);
  return ((o1 > 0) != (o2 > 0)) && ((o3 > 0) != (o4 > 0));
}

}  // namespace

RegionFill fill_on_substrate(const RegionProblem& pr, const Substrate& sub) {
  RegionFill out;
  auto fail = [&](const std::string& why) {
    out = RegionFill{};
    out.why = why;
    return out;
  };
  const uint32_t nc = uint32_t(pr.contour.size()), nf = uint32_t(pr.fixed.size()), base = nc + nf;
  if (nc < 3) return fail("contour has fewer than 3 nodes");
  if (sub.triangles.empty()) return fail("no input under the region");
  if (!(pr.target > 0)) return fail("no characteristic length");
  const double L = pr.target;
  const PlaneFrame frame = plane_frame(pr);

  std::vector<P2> polygon;
  for (const Vec3& p : pr.contour) polygon.push_back(frame.to_2d(p));
  if (signed_area2(polygon) <= 0) return fail("contour not counter-clockwise in the region's plane");
  if (!is_simple(polygon)) return fail("contour overlaps itself in the region's plane");
  std::vector<P2> fixed2;
  for (const Vec3& p : pr.fixed) {
    fixed2.push_back(frame.to_2d(p));
    if (!inside_polygon(fixed2.back(), polygon))
      return fail("a kept node lies outside the contour in the region's plane");
  }
  auto node2 = [&](uint32_t i) { return i < nc ? polygon[i] : fixed2[i - nc]; };

  // Substrate normals and creases.
  std::vector<Vec3> normal(sub.triangles.size());
  for (size_t t = 0; t < sub.triangles.size(); ++t) {
    const Tri& s = sub.triangles[t];
    normal[t] = normalized(area_vector(sub.points[s[0]], sub.points[s[1]], sub.points[s[2]]));
  }
  std::unordered_map<uint64_t, std::vector<uint32_t>> edge_tris;
  for (uint32_t t = 0; t < sub.triangles.size(); ++t)
    for (int k = 0; k < 3; ++k) edge_tris[edge_key(sub.triangles[t][k], sub.triangles[t][(k + 1) % 3])].push_back(t);
  const double cos_flat = std::cos(sub.flat_angle_deg * M_PI / 180.0);
  struct Crease {
    Vec3 a, b, normal;
  };
  std::vector<Crease> creases;
  for (const auto& [key, tris] : edge_tris) {
    if (tris.size() != 2 || norm2(normal[tris[0]]) == 0 || norm2(normal[tris[1]]) == 0) continue;
    if (dot(normal[tris[0]], normal[tris[1]]) >= cos_flat) continue;
    creases.push_back({sub.points[uint32_t(key >> 32)], sub.points[uint32_t(key & 0xffffffffu)],
                       normalized(normal[tris[0]] + normal[tris[1]])});
  }
  // Creases are the sorted edge map's: iteration order must not depend on the hash.
  std::sort(creases.begin(), creases.end(),
            [](const Crease& x, const Crease& y) { return x.a != y.a ? x.a < y.a : x.b < y.b; });

  // The side of the substrate the wrap is on (the surface replaced tells), and the point of
  // the replaced surface over a plane point (its height there), for the mapping back.
  std::vector<P2> old2;
  for (const Vec3& p : pr.old_points) old2.push_back(frame.to_2d(p));
  double mean_height = 0;
  for (const Vec3& p : pr.contour) mean_height += frame.height(p);
  mean_height /= double(nc);
  auto old_surface_at = [&](const P2& q) {
    for (const Tri& t : pr.old_triangles) {
      const P2 &a = old2[t[0]], &b = old2[t[1]], &c = old2[t[2]];
      const double area = cross2(sub2(b, a), sub2(c, a));
      if (area <= 0) continue;
      const double u = cross2(sub2(b, q), sub2(c, q)) / area, v = cross2(sub2(c, q), sub2(a, q)) / area, w = 1 - u - v;
      if (u >= -1e-9 && v >= -1e-9 && w >= -1e-9)
        return pr.old_points[t[0]] * u + pr.old_points[t[1]] * v + pr.old_points[t[2]] * w;
    }
    return frame.to_3d(q, mean_height);
  };
  struct Foot {
    Vec3 point, normal;
    double side;  // >0: the point is on the normal's side
  };
  auto foot_of = [&](const Vec3& p) {
    Foot best{{0, 0, 0}, {0, 0, 0}, 0};
    double best_d = INFINITY;
    for (size_t t = 0; t < sub.triangles.size(); ++t) {
      if (norm2(normal[t]) == 0) continue;
      const Tri& s = sub.triangles[t];
      const Vec3 c = closest_on_triangle(p, sub.points[s[0]], sub.points[s[1]], sub.points[s[2]]);
      const double d = norm2(p - c);
      if (d < best_d) best_d = d, best = {c, normal[t], dot(p - c, normal[t])};
    }
    return best;
  };
  double region_side = 0;
  for (const Vec3& p : pr.old_points) {
    const Foot f = foot_of(p);
    if (std::fabs(f.side) > 0.5 * sub.offset) region_side += f.side > 0 ? 1 : -1;
  }
  auto off_the_input = [&](const Vec3& on, const Vec3& n, const Vec3& above) {
    double side = dot(above - on, n);
    if (std::fabs(side) <= 0.5 * sub.offset) side = region_side != 0 ? region_side : dot(pr.normal, n);
    return on + n * (side >= 0 ? sub.offset : -sub.offset);
  };

  // Points of the triangulation beyond the contour and the kept nodes: along the creases,
  // then on a triangular lattice inside.
  std::vector<P2> extra2;
  std::vector<Vec3> extra3;
  std::vector<std::pair<uint32_t, uint32_t>> constraints;  // fill node numbers
  auto clear_of_fixed = [&](const P2& q, double gap) {
    for (const P2& f : fixed2)
      if (std::sqrt(dot2(sub2(q, f), sub2(q, f))) < gap) return false;
    for (const auto& [u, v] : pr.fixed_edges)
      if (segment_distance(q, node2(u), node2(v)) < gap) return false;
    return true;
  };
  std::map<std::array<double, 3>, uint32_t> crease_node;  // shared crease ends become one node
  for (const Crease& c : creases) {
    const size_t k = std::max<size_t>(1, size_t(std::ceil(norm(c.b - c.a) / (0.75 * L))));
    long previous = -1;
    for (size_t i = 0; i <= k; ++i) {
      const Vec3 x = lerp(c.a, c.b, double(i) / double(k));
      const P2 q = frame.to_2d(x);
      if (!inside_polygon(q, polygon) || boundary_distance(q, polygon) < 0.3 * L || !clear_of_fixed(q, 0.3 * L)) {
        previous = -1;
        continue;
      }
      auto [it, added] = crease_node.emplace(x, base + uint32_t(extra2.size()));
      if (added) {
        extra2.push_back(q);
        extra3.push_back(off_the_input(x, c.normal, old_surface_at(q)));
      }
      const uint32_t id = it->second;
      if (previous >= 0 && uint32_t(previous) != id) {
        bool crosses = false;
        const P2& from = extra2[size_t(previous) - base];
        for (size_t e = 0; e < polygon.size() && !crosses; ++e)
          crosses = segments_cross(from, q, polygon[e], polygon[(e + 1) % polygon.size()]);
        if (!crosses) constraints.push_back({uint32_t(previous), id});
      }
      previous = long(id);
    }
  }
  const size_t crease_points = extra2.size();
  {
    double lo[2] = {INFINITY, INFINITY}, hi[2] = {-INFINITY, -INFINITY};
    for (const P2& q : polygon)
      for (int k = 0; k < 2; ++k) lo[k] = std::min(lo[k], q[k]), hi[k] = std::max(hi[k], q[k]);
    const double dy = L * std::sqrt(3.0) / 2;
    for (int j = 0; lo[1] + j * dy <= hi[1]; ++j)
      for (int i = 0; lo[0] + (i + 0.5 * (j % 2)) * L <= hi[0]; ++i) {
        const P2 q{lo[0] + (i + 0.5 * (j % 2)) * L, lo[1] + j * dy};
        if (!inside_polygon(q, polygon) || boundary_distance(q, polygon) < 0.5 * L || !clear_of_fixed(q, 0.5 * L))
          continue;
        bool clear = true;
        for (size_t e = 0; e < crease_points && clear; ++e)
          clear = std::sqrt(dot2(sub2(q, extra2[e]), sub2(q, extra2[e]))) >= 0.5 * L;
        for (const auto& [u, v] : constraints)
          if (clear && u >= base && v >= base)
            clear = segment_distance(q, extra2[u - base], extra2[v - base]) >= 0.4 * L;
        if (!clear) continue;
        const Vec3 above = old_surface_at(q);
        const Foot f = foot_of(above);
        if (std::fabs(dot(f.normal, frame.n)) < 0.17)
          return fail("the input under the region is steeper than 80 degrees to its plane");
        extra2.push_back(q);
        extra3.push_back(off_the_input(f.point, f.normal, above));
      }
  }

  // The triangulation.
  CDT cdt;
  std::vector<CDT::Vertex_handle> handle;
  const size_t total = base + extra2.size();
  try {
    for (uint32_t i = 0; i < total; ++i) {
      const P2 q = i < base ? node2(i) : extra2[i - base];
      auto v = cdt.insert(K::Point_2(q[0], q[1]));
      v->info() = i;
      handle.push_back(v);
    }
    if (cdt.number_of_vertices() != total) return fail("two nodes fall on one point in the region's plane");
    for (uint32_t i = 0; i < nc; ++i) cdt.insert_constraint(handle[i], handle[(i + 1) % nc]);
    for (const auto& [u, v] : pr.fixed_edges)
      if (!(u < nc && v < nc && (v == (u + 1) % nc || u == (v + 1) % nc))) cdt.insert_constraint(handle[u], handle[v]);
    for (const auto& [u, v] : constraints) cdt.insert_constraint(handle[u], handle[v]);
  } catch (const std::exception&) {
    return fail("constraints cross in the region's plane");
  }
  if (cdt.number_of_vertices() != total) return fail("constraints cross in the region's plane");

  // Inside the contour: across a contour edge the side flips, across other constraints not.
  auto is_contour = [&](uint32_t a, uint32_t b) {
    return (a < nc && b < nc) && ((a + 1) % nc == b || (b + 1) % nc == a);
  };
  for (auto f = cdt.all_faces_begin(); f != cdt.all_faces_end(); ++f) f->info() = -1;
  std::deque<CDT::Face_handle> queue;
  cdt.infinite_face()->info() = 0;
  queue.push_back(cdt.infinite_face());
  while (!queue.empty()) {
    CDT::Face_handle f = queue.front();
    queue.pop_front();
    for (int i = 0; i < 3; ++i) {
      CDT::Face_handle g = f->neighbor(i);
      const bool contour_edge = !cdt.is_infinite(f->vertex(CDT::cw(i))) && !cdt.is_infinite(f->vertex(CDT::ccw(i))) &&
                                f->is_constrained(i) &&
                                is_contour(f->vertex(CDT::cw(i))->info(), f->vertex(CDT::ccw(i))->info());
      const int state = contour_edge ? 1 - f->info() : f->info();
      if (g->info() == -1) {
        g->info() = state;
        queue.push_back(g);
      } else if (g->info() != state) {
        return fail("the contour does not bound one region in its plane");
      }
    }
  }
  for (auto f = cdt.finite_faces_begin(); f != cdt.finite_faces_end(); ++f) {
    if (f->info() != 1) continue;
    out.triangles.push_back({f->vertex(0)->info(), f->vertex(1)->info(), f->vertex(2)->info()});
  }
  // A disc with nc boundary nodes and the rest inside has 2 (inside) + nc - 2 triangles.
  if (out.triangles.size() != 2 * (total - nc) + nc - 2) return fail("nodes outside the contour in the region's plane");
  out.new_points = std::move(extra3);
  out.ok = true;
  return out;
}

}  // namespace vdbwrap::post
