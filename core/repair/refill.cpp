// The repair's CGAL translation unit: hole filling, refinement and fairing of one region.
#include "repair/refill.h"

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Polygon_mesh_processing/fair.h>
#include <CGAL/Polygon_mesh_processing/triangulate_hole.h>
#include <CGAL/Surface_mesh.h>

#include <algorithm>
#include <functional>
#include <cmath>
#include <map>
#include <unordered_map>
#include <unordered_set>

#include "check/intersections.h"
#include "common/edge_key.h"
#include "common/float_round.h"
#include "common/vec.h"
#include "mesh/surface_index.h"

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

// The local mesh a closed loop is filled in: the ring of triangles around the region gives the
// fairing its context, and each loop of the contour is a hole in it.
struct LocalMesh {
  SurfaceMesh sm;
  std::unordered_map<uint32_t, SurfaceMesh::Vertex_index> local;
  std::vector<uint32_t> global_of;  // local vertex index -> global id

  SurfaceMesh::Vertex_index vertex(const std::vector<Vec3>& points, uint32_t g) {
    auto it = local.find(g);
    if (it != local.end()) return it->second;
    auto v = sm.add_vertex(K::Point_3(points[g][0], points[g][1], points[g][2]));
    local.emplace(g, v);
    global_of.resize(std::max<size_t>(global_of.size(), v.idx() + 1));
    global_of[v.idx()] = g;
    return v;
  }
};

enum class Mode { RefineAndFair, Refine, Triangulate };

// Fills the hole of `loop` in the local mesh; the patch's faces and new vertices are appended.
std::string fill_closed_loop(LocalMesh& lm, const std::vector<uint32_t>& loop, Mode mode,
                             std::vector<SurfaceMesh::Face_index>& faces,
                             std::vector<SurfaceMesh::Vertex_index>& vertices, bool& faired) {
  for (uint32_t g : loop)
    if (!lm.local.count(g)) return "contour vertex without a triangle outside the region";
  // The border halfedge of the hole runs like the removed triangles: loop[0] -> loop[1].
  auto h = lm.sm.halfedge(lm.local[loop[0]], lm.local[loop[1]]);
  if (h == SurfaceMesh::null_halfedge() || !lm.sm.is_border(h)) return "hole not found in the local mesh";
  size_t n = 0;
  for (auto g : CGAL::halfedges_around_face(h, lm.sm)) {
    (void)g;
    if (++n > loop.size()) break;
  }
  if (n != loop.size()) return "hole border differs from the contour (pinched ring)";
  std::vector<SurfaceMesh::Face_index> f;
  std::vector<SurfaceMesh::Vertex_index> v;
  if (mode == Mode::Triangulate)
    PMP::triangulate_hole(lm.sm, h, std::back_inserter(f), CGAL::parameters::use_delaunay_triangulation(true));
  else
    PMP::triangulate_and_refine_hole(lm.sm, h, std::back_inserter(f), std::back_inserter(v),
                                     CGAL::parameters::use_delaunay_triangulation(true));
  if (f.empty()) return "hole filling found no triangulation";
  if (mode == Mode::RefineAndFair && !v.empty()) {
    if (!PMP::fair(lm.sm, v, CGAL::parameters::fairing_continuity(1))) return "fairing failed";
    faired = true;
  }
  faces.insert(faces.end(), f.begin(), f.end());
  vertices.insert(vertices.end(), v.begin(), v.end());
  return {};
}

// A loop along the mesh's border has no ring to fair against: the contour alone is
// triangulated (minimal area, Liepa), turned to run loop[0] -> loop[1] like the region.
std::string fill_open_loop(const std::vector<Vec3>& points, const std::vector<uint32_t>& loop, std::vector<Tri>& out) {
  std::vector<K::Point_3> polyline;
  for (uint32_t g : loop) polyline.emplace_back(points[g][0], points[g][1], points[g][2]);
  std::vector<CGAL::Triple<int, int, int>> tris;
  PMP::triangulate_hole_polyline(polyline, std::back_inserter(tris));
  if (tris.empty()) return "hole filling found no triangulation";
  bool flip = false;
  for (const auto& t : tris) {
    const int c[3] = {t.first, t.second, t.third};
    for (int k = 0; k < 3; ++k) {
      if (c[k] == 0 && c[(k + 1) % 3] == 1) flip = false;
      if (c[k] == 1 && c[(k + 1) % 3] == 0) flip = true;
    }
  }
  for (const auto& t : tris) {
    Tri tri{loop[size_t(t.first)], loop[size_t(t.second)], loop[size_t(t.third)]};
    if (flip) std::swap(tri[1], tri[2]);
    out.push_back(tri);
  }
  return {};
}

// A component of the mesh outside the region, reached from the contour through shared
// vertices; `large` when the flood stopped at its limit before the component ended.
struct Piece {
  std::vector<uint32_t> triangles;
  std::vector<size_t> loops;
  bool large = false;
};

std::vector<Piece> pieces_beyond(const std::vector<Tri>& triangles, const VertexFaces& faces,
                                 const std::function<bool(uint32_t)>& in_region,
                                 const std::vector<std::vector<uint32_t>>& loops, size_t limit) {
  std::vector<Piece> pieces;
  std::unordered_map<uint32_t, size_t> piece_of;  // triangle -> piece
  for (size_t i = 0; i < loops.size(); ++i) {
    size_t found = SIZE_MAX;
    uint32_t seed = UINT32_MAX;
    for (uint32_t v : loops[i]) {
      for (const uint32_t* f = faces.begin(v); f != faces.end(v) && found == SIZE_MAX; ++f) {
        if (in_region(*f)) continue;
        auto it = piece_of.find(*f);
        if (it != piece_of.end())
          found = it->second;
        else if (seed == UINT32_MAX)
          seed = *f;
      }
      if (found != SIZE_MAX) break;
    }
    if (found == SIZE_MAX && seed == UINT32_MAX) continue;  // only border edges: no piece beyond
    if (found == SIZE_MAX) {
      found = pieces.size();
      pieces.emplace_back();
      Piece& p = pieces.back();
      std::vector<uint32_t> stack{seed};
      piece_of[seed] = found;
      while (!stack.empty() && !p.large) {
        uint32_t t = stack.back();
        stack.pop_back();
        p.triangles.push_back(t);
        for (uint32_t v : triangles[t])
          for (const uint32_t* f = faces.begin(v); f != faces.end(v); ++f)
            if (!in_region(*f) && piece_of.emplace(*f, found).second) stack.push_back(*f);
        p.large = p.triangles.size() + stack.size() > limit;
      }
    }
    pieces[found].loops.push_back(i);
  }
  return pieces;
}

}  // namespace

std::vector<std::vector<uint32_t>> contour_loops(const std::vector<std::pair<uint32_t, uint32_t>>& edges,
                                                 std::string& why) {
  std::unordered_map<uint32_t, uint32_t> next;
  for (const auto& [a, b] : edges)
    if (!next.emplace(a, b).second) {
      why = "contour is not a simple loop";
      return {};
    }
  std::vector<uint32_t> starts;
  for (const auto& [a, b] : edges) starts.push_back(a);
  std::sort(starts.begin(), starts.end());  // the same loops in the same order on every run
  std::unordered_set<uint32_t> seen;
  std::vector<std::vector<uint32_t>> loops;
  for (uint32_t s : starts) {
    if (seen.count(s)) continue;
    std::vector<uint32_t> loop;
    uint32_t v = s;
    do {
      if (!seen.insert(v).second) {
        why = "contour is not a simple loop";
        return {};
      }
      loop.push_back(v);
      auto it = next.find(v);
      if (it == next.end()) {
        why = "contour is not closed";
        return {};
      }
      v = it->second;
    } while (v != s);
    if (loop.size() < 3) {
      why = "contour loop of fewer than 3 edges";
      return {};
    }
    loops.push_back(std::move(loop));
  }
  if (loops.empty()) why = "no contour";
  return loops;
}

Refill refill_region(const std::vector<Vec3>& points, const std::vector<Tri>& triangles, const VertexFaces& faces,
                     const std::vector<uint32_t>& region, const RefillParams& params,
                     const mesh::SurfaceIndex* original) {
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
  std::vector<std::pair<uint32_t, uint32_t>> contour;  // in the region's orientation
  std::unordered_set<uint64_t> border_edges;           // contour edges on the mesh's border
  for (const auto& [key, count] : used) {
    uint32_t u = uint32_t(key >> 32), v = uint32_t(key & 0xffffffffu);
    size_t total = edge_use(triangles, faces, u, v);
    if (count > 2) return fail("non-manifold edge inside the region");
    if (count == 2 && total != 2) return fail("region edge shared with triangles outside it");
    if (count == 1) {
      if (total > 2) return fail("non-manifold edge on the contour");
      if (total == 1) border_edges.insert(key);
      contour.push_back(directed[key]);
    }
  }
  std::string why;
  const std::vector<std::vector<uint32_t>> loops = contour_loops(contour, why);
  if (loops.empty()) return fail(why);
  std::vector<uint8_t> open(loops.size(), 0);  // part of the loop is the mesh's border
  for (size_t i = 0; i < loops.size(); ++i)
    for (size_t k = 0; k < loops[i].size(); ++k)
      open[i] |= border_edges.count(edge_key(loops[i][k], loops[i][(k + 1) % loops[i].size()])) ? 1 : 0;
  // Vertices inside the region must go with it.
  std::unordered_set<uint32_t> on_contour;
  for (const auto& l : loops) on_contour.insert(l.begin(), l.end());
  for (uint32_t v : vertices_of(triangles, region)) {
    if (on_contour.count(v)) continue;
    for (const uint32_t* f = faces.begin(v); f != faces.end(v); ++f)
      if (!in_region(*f)) return fail("region vertex used outside the region");
  }

  // 2. What lies beyond each loop. A loop whose piece is large (or that has no piece: border
  //    only) is always filled; a small piece may instead go with the region (step 4).
  const std::vector<Piece> pieces =
      loops.size() > 1 && params.max_deviation > 0
          ? pieces_beyond(triangles, faces, in_region, loops, std::max<size_t>(64, 4 * region.size()))
          : std::vector<Piece>{};
  // Only a piece bounded by closed loops may go: a loop along the mesh's border can run
  // between several components, and deleting one would leave the others' edges free.
  std::unordered_set<uint32_t> on_open;
  for (size_t i = 0; i < loops.size(); ++i)
    if (open[i]) on_open.insert(loops[i].begin(), loops[i].end());
  auto pinned = [&](const Piece& p) {
    for (size_t i : p.loops)
      if (open[i]) return true;
    for (uint32_t t : p.triangles)
      for (uint32_t v : triangles[t])
        if (on_open.count(v)) return true;
    return false;
  };
  std::vector<size_t> small;  // pieces that may be deleted, largest (by area) first
  std::vector<uint8_t> always(loops.size(), 1);
  for (size_t p = 0; p < pieces.size(); ++p)
    if (!pieces[p].large && !pinned(pieces[p])) {
      small.push_back(p);
      for (size_t i : pieces[p].loops) always[i] = 0;
    }
  std::vector<double> piece_area(pieces.size(), 0.0);
  for (size_t p : small)
    for (uint32_t t : pieces[p].triangles) piece_area[p] += area_of(points, {triangles[t]});
  std::stable_sort(small.begin(), small.end(), [&](size_t a, size_t b) { return piece_area[a] > piece_area[b]; });
  if (std::none_of(always.begin(), always.end(), [](uint8_t a) { return a != 0; }) && !small.empty()) {
    for (size_t i : pieces[small.front()].loops) always[i] = 1;  // the largest piece stays
    small.erase(small.begin());
  }

  // 5. Checks: the same for every way of filling.
  //    Non-degenerate; its border is the filled loops, same orientation; no edge that already
  //    exists elsewhere; area change; distance to the surface it replaces.
  auto finish = [&](Refill out, const std::vector<size_t>& filled, const std::vector<size_t>& loop_of,
                    const std::vector<uint32_t>& deleted) -> Refill {
    const uint32_t base = uint32_t(points.size());
    std::vector<uint32_t> removed_ids = region;
    removed_ids.insert(removed_ids.end(), deleted.begin(), deleted.end());
    std::unordered_map<uint64_t, int> removed_edges = used;
    for (uint32_t t : deleted)
      for (int k = 0; k < 3; ++k) ++removed_edges[edge_key(triangles[t][k], triangles[t][(k + 1) % 3])];
    std::unordered_map<uint64_t, std::pair<uint32_t, uint32_t>> loop_edges;  // filled loops, directed
    size_t loop_length = 0;
    for (size_t i : filled) {
      const auto& l = loops[i];
      loop_length += l.size();
      for (size_t k = 0; k < l.size(); ++k)
        loop_edges[edge_key(l[k], l[(k + 1) % l.size()])] = {l[k], l[(k + 1) % l.size()]};
    }
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
        if (u < base && v < base && removed_edges.count(key) == 0 && edge_use(triangles, faces, u, v) > 0)
          return fail("refill would make a non-manifold edge");
        // A chord between contour vertices that is also a contour edge would close the hole wrongly.
        if (u < base && v < base && loop_edges.count(key)) return fail("refill reuses a contour edge inside");
        continue;
      }
      // Free edge of the patch: must be an edge of a filled loop, in the region's direction.
      auto it = loop_edges.find(key);
      if (it == loop_edges.end()) return fail("refill leaves a free edge");
      auto [a, b] = it->second;
      if ((a < b ? 1 : -1) != e.second) return fail("refill is oriented against the mesh");
      ++border;
    }
    if (border != loop_length) return fail("refill border differs from the contour");

    std::vector<Tri> removed;
    for (uint32_t t : removed_ids) removed.push_back(triangles[t]);
    // The area criterion compares the region with its fill; a deleted piece changes the area
    // on purpose (the buried end of a pin), and the deviation bound below holds it.
    if (deleted.empty()) {
      const double area_before = area_of(points, removed), area_after = area_of(patch_points, patch);
      const double hi = std::max(area_before, area_after);
      if (hi <= 0 || std::min(area_before, area_after) / hi < params.area_ratio) return fail("area change too large");
    }

    if (params.max_deviation > 0) {
      const double bound2 = params.max_deviation * params.max_deviation;
      // Refill -> input (or the removed surface when no input is given).
      std::vector<Vec3> from_patch = samples_on(patch_points, patch);
      if (original) {
        for (const Vec3& s : from_patch)
          if (original->squared_distance(s) > bound2) return fail("refill too far from the input");
      } else {
        mesh::SurfaceIndex removed_index(points, removed);
        for (const Vec3& s : from_patch)
          if (removed_index.squared_distance(s) > bound2) return fail("refill too far from the removed surface");
      }
      // Removed surface -> refill.
      mesh::SurfaceIndex patch_index(patch_points, patch);
      for (const Vec3& s : samples_on(points, removed))
        if (patch_index.squared_distance(s) > bound2) return fail("removed surface too far from the refill");
    }

    // Each new triangle replaces the nearest region triangle along its own loop (its part
    // goes on: a cap on a pin takes the pin's part, not the plate's under it).
    std::vector<std::vector<uint32_t>> along(loops.size());
    for (uint32_t r : region) {
      const Tri& x = triangles[r];
      for (int k = 0; k < 3; ++k) {
        auto it = loop_edges.find(edge_key(x[k], x[(k + 1) % 3]));
        if (it == loop_edges.end()) continue;
        for (size_t i : filled)
          if (std::find(loops[i].begin(), loops[i].end(), x[k]) != loops[i].end()) along[i].push_back(r);
      }
    }
    for (size_t q = 0; q < patch.size(); ++q) {
      const Tri& t = patch[q];
      Vec3 c = (patch_points[t[0]] + patch_points[t[1]] + patch_points[t[2]]) * (1.0 / 3);
      const std::vector<uint32_t>& candidates = along[loop_of[q]].empty() ? region : along[loop_of[q]];
      uint32_t best = candidates[0];
      double best_d = INFINITY;
      for (uint32_t r : candidates) {
        const Tri& x = triangles[r];
        double d = norm2((points[x[0]] + points[x[1]] + points[x[2]]) * (1.0 / 3) - c);
        if (d < best_d) best_d = d, best = r;
      }
      out.replaces.push_back(best);
    }
    out.also_removed = deleted;
    std::sort(out.also_removed.begin(), out.also_removed.end());
    out.loops = filled.size();
    out.ok = true;
    return out;
  };

  // 3. Fill, then check; a smooth refill first, then flatter ones (CAD regions: fairing
  //    rounds sharp edges, the plain triangulation keeps planar pieces planar). Loops along
  //    the border are triangulated from the contour alone whatever the mode.
  auto attempt = [&](Mode mode) -> Refill {
    LocalMesh lm;
    if (std::any_of(open.begin(), open.end(), [](uint8_t o) { return o == 0; })) {
      for (uint32_t t : grow_ring(triangles, faces, region)) {
        if (in_region(t)) continue;
        const Tri& tri = triangles[t];
        if (tri[0] == tri[1] || tri[1] == tri[2] || tri[0] == tri[2]) continue;
        if (lm.sm.add_face(lm.vertex(points, tri[0]), lm.vertex(points, tri[1]), lm.vertex(points, tri[2])) ==
            SurfaceMesh::null_face())
          return fail("the ring around the region is not manifold");
      }
    }
    std::vector<SurfaceMesh::Face_index> patch_faces;
    std::vector<SurfaceMesh::Vertex_index> patch_vertices;
    std::vector<size_t> face_loop;  // per patch face: its loop
    std::vector<Tri> open_tris;
    std::vector<size_t> open_loop;
    std::vector<size_t> filled;
    Refill out;
    auto fill = [&](size_t i) -> std::string {
      std::string e;
      if (open[i]) {
        const size_t before = open_tris.size();
        e = fill_open_loop(points, loops[i], open_tris);
        open_loop.resize(open_tris.size(), i);
        (void)before;
      } else {
        e = fill_closed_loop(lm, loops[i], mode, patch_faces, patch_vertices, out.faired);
        face_loop.resize(patch_faces.size(), i);
      }
      if (e.empty()) filled.push_back(i);
      return e;
    };
    // 4. Back to global indices: contour vertices keep theirs, new ones follow points.
    auto to_global = [&](Refill& r, std::vector<size_t>& loop_of) -> std::string {
      const uint32_t base = uint32_t(points.size());
      r.new_points.clear();
      r.triangles = open_tris;
      loop_of = open_loop;
      std::unordered_map<uint32_t, uint32_t> new_index;  // local index -> global-or-new index
      for (auto v : patch_vertices) {
        const auto& p = lm.sm.point(v);
        Vec3 q{p.x(), p.y(), p.z()};
        if (params.float_coordinates) q = round_to_float(q);
        if (!std::isfinite(q[0]) || !std::isfinite(q[1]) || !std::isfinite(q[2])) return "refill point not finite";
        new_index[v.idx()] = base + uint32_t(r.new_points.size());
        r.new_points.push_back(q);
      }
      for (size_t q = 0; q < patch_faces.size(); ++q) {
        Tri t;
        int k = 0;
        for (auto v : CGAL::vertices_around_face(lm.sm.halfedge(patch_faces[q]), lm.sm)) {
          if (k == 3) return "refill face is not a triangle";
          auto it = new_index.find(v.idx());
          if (it != new_index.end())
            t[k++] = it->second;
          else {
            uint32_t g = lm.global_of[v.idx()];
            if (!on_contour.count(g)) return "refill uses a vertex off the contour";
            t[k++] = g;
          }
        }
        if (k != 3) return "refill face is not a triangle";
        r.triangles.push_back(t);
        loop_of.push_back(face_loop[q]);
      }
      return {};
    };
    for (size_t i = 0; i < loops.size(); ++i)
      if (always[i])
        if (std::string e = fill(i); !e.empty()) return fail(e);
    // A small piece goes with the region when all of it lies within the bound of the fill so
    // far (e.g. the end of a pin buried in a plate, under the plate's refilled top); otherwise
    // its loops are filled too.
    std::vector<uint32_t> deleted;
    std::vector<size_t> loop_of;
    for (size_t p : small) {
      bool near = false;
      if (std::string e = to_global(out, loop_of); !e.empty()) return fail(e);
      if (!out.triangles.empty()) {
        std::vector<Vec3> pts = points;
        pts.insert(pts.end(), out.new_points.begin(), out.new_points.end());
        mesh::SurfaceIndex so_far(pts, out.triangles);
        std::vector<Tri> piece;
        for (uint32_t t : pieces[p].triangles) piece.push_back(triangles[t]);
        near = true;
        for (const Vec3& s : samples_on(points, piece))
          if (!(near = so_far.within(s, params.max_deviation))) break;
      }
      if (near) {
        deleted.insert(deleted.end(), pieces[p].triangles.begin(), pieces[p].triangles.end());
        continue;
      }
      for (size_t i : pieces[p].loops)
        if (std::string e = fill(i); !e.empty()) return fail(e);
    }
    if (std::string e = to_global(out, loop_of); !e.empty()) return fail(e);
    if (out.triangles.empty()) return fail("hole filling found no triangulation");
    return finish(std::move(out), filled, loop_of, deleted);
  };

  for (Mode mode : {Mode::RefineAndFair, Mode::Refine, Mode::Triangulate}) {
    if (mode == Mode::RefineAndFair && !params.fair) continue;
    Refill r = attempt(mode);
    if (r.ok) return r;
    if (why.find(r.why) == std::string::npos) why += (why.empty() ? "" : "; ") + r.why;
    // A contour along the border only is triangulated the same way in every mode.
    if (std::all_of(open.begin(), open.end(), [](uint8_t o) { return o != 0; })) break;
  }
  return fail(why);
}

}  // namespace vdbwrap::local_repair
