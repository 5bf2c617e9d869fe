#include "prep/prepare.h"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <unordered_map>

#include <tbb/parallel_for.h>
#include <tbb/parallel_sort.h>

#include "check/intersections.h"
#include "common/edge_key.h"
#include "common/edge_triangles.h"
#include "common/exact_weld.h"
#include "common/fill_vector.h"
#include "common/grid_key.h"
#include "common/sorted_point_grid.h"
#include "common/vec.h"
#include "mesh/contact_faces.h"
#include "mesh/orient.h"
#include "mesh/weld.h"
#include "vdbwrap/errors.h"

namespace vdbwrap::prep {

InputIntersections input_intersections(const std::vector<check::TrianglePair>& mesh_pairs,
                                       const std::vector<uint32_t>& input_to_mesh, size_t mesh_triangles) {
  // copies[k]: input triangles that became mesh triangle k (1, or more for duplicates).
  std::vector<uint32_t> copies(mesh_triangles, 0);
  for (uint32_t k : input_to_mesh)
    if (k != UINT32_MAX) ++copies[k];
  InputIntersections counts;
  std::vector<uint8_t> hit(mesh_triangles, 0);
  for (const auto& p : mesh_pairs) {
    counts.pairs += size_t(copies[p.a]) * copies[p.b];
    hit[p.a] = hit[p.b] = 1;
  }
  for (size_t k = 0; k < mesh_triangles; ++k) {
    // Copies of one triangle lie on each other: every two of them make an intersecting pair.
    counts.pairs += copies[k] > 1 ? size_t(copies[k]) * (copies[k] - 1) / 2 : 0;
    if (hit[k] || copies[k] > 1) counts.triangles += copies[k];
  }
  return counts;
}

namespace {

// The longest side of each closed piece's bounding box.
std::vector<float> closed_piece_sizes(const Mesh& m, const std::vector<uint32_t>& closed_piece) {
  std::vector<Vec3> lo, hi;
  for (uint32_t t = 0; t < m.triangles.size(); ++t) {
    const uint32_t p = closed_piece[t];
    if (p == mesh::kOpenPiece) continue;
    if (p >= lo.size())
      lo.resize(p + 1, Vec3{HUGE_VAL, HUGE_VAL, HUGE_VAL}), hi.resize(p + 1, Vec3{-HUGE_VAL, -HUGE_VAL, -HUGE_VAL});
    for (uint32_t v : m.triangles[t])
      for (int a = 0; a < 3; ++a)
        lo[p][a] = std::min(lo[p][a], m.points[v][a]), hi[p][a] = std::max(hi[p][a], m.points[v][a]);
  }
  std::vector<float> size(lo.size());
  for (size_t p = 0; p < lo.size(); ++p)
    size[p] = float(std::max({hi[p][0] - lo[p][0], hi[p][1] - lo[p][1], hi[p][2] - lo[p][2]}));
  return size;
}

// A triangle thinner than this fraction of the diagonal (its height over its longest side) is a
// segment, not a surface.
constexpr double kNeedleHeight = 1e-6;

// Needles that share no side with another triangle are dropped as degenerate: a stray segment
// (a CAD export's sliver between two parts, collinear points rounded to float) would be
// wrapped as a hair-thin tube, both its long sides traced as feature curves on one line, and
// the triangles between the two curves are caps no edit can open (1-1.5 % of the triangles
// on the generated csg_export). A needle inside a surface stays: dropping it would open a
// crack there.
void drop_stray_needles(const std::vector<Tri>& tris, const std::vector<uint8_t>& needle,
                        std::vector<uint8_t>& degenerate) {
  std::unordered_map<uint64_t, uint32_t> uses;  // the needles' sides, by how many triangles have them
  for (size_t t = 0; t < tris.size(); ++t)
    if (needle[t])
      for (int k = 0; k < 3; ++k) uses[edge_key(tris[t][k], tris[t][(k + 1) % 3])] = 0;
  if (uses.empty()) return;
  for (size_t t = 0; t < tris.size(); ++t)
    if (!degenerate[t])
      for (int k = 0; k < 3; ++k) {
        auto it = uses.find(edge_key(tris[t][k], tris[t][(k + 1) % 3]));
        if (it != uses.end()) ++it->second;
      }
  for (size_t t = 0; t < tris.size(); ++t) {
    if (!needle[t]) continue;
    bool alone = true;
    for (int k = 0; k < 3; ++k) alone = alone && uses[edge_key(tris[t][k], tris[t][(k + 1) % 3])] == 1;
    if (alone) degenerate[t] = 1;
  }
}

// Drops the faces where solids touch from the mesh (`inside`, per triangle): the outside wrap
// does without them, and the union they leave is closed where the solids were (one piece to
// orient, no coplanar overlaps to search, no cells refined for their normals). Renumbers the
// input's triangles and lists the edges again, with their contact verdicts by key.
void drop_inside_faces(PreparedInput& out, const std::vector<uint8_t>& inside, EdgeTriangles& edges,
                       std::vector<mesh::ContactEdge>& contact) {
  Mesh& m = out.mesh;
  const size_t kept = size_t(std::count(inside.begin(), inside.end(), 0));
  if (kept == m.triangles.size() || kept == 0) return;
  std::vector<uint32_t> renumber(m.triangles.size(), UINT32_MAX);
  size_t next = 0;
  for (size_t t = 0; t < m.triangles.size(); ++t)
    if (!inside[t]) {
      renumber[t] = uint32_t(next);
      m.triangles[next] = m.triangles[t];
      m.triangle_part[next] = m.triangle_part[t];
      ++next;
    }
  m.triangles.resize(next);
  m.triangle_part.resize(next);
  for (uint32_t& t : out.input_to_mesh)
    if (t != UINT32_MAX) t = renumber[t];
  out.dropped_inside = inside.size() - kept;
  EdgeTriangles listed = edge_triangles(m.triangles);
  std::vector<mesh::ContactEdge> verdicts(listed.edges(), mesh::ContactEdge::NonManifold);
  for (size_t i = 0; i < listed.edges(); ++i)
    if (listed.size(i) > 2) verdicts[i] = contact[edges.find(listed.keys[i])];
  edges = std::move(listed);
  contact = std::move(verdicts);
}

// Whether two triangles on the same corners run them the same way round.
bool same_turn(const Tri& a, const Tri& b) {
  const int k = b[0] == a[0] ? 0 : b[1] == a[0] ? 1 : 2;
  return b[(k + 1) % 3] == a[1];
}

}  // namespace

PreparedInput prepare(const Mesh& input, const PrepareParams& params, ProgressSink* progress,
                      const ExactWeld* input_weld) {
  PreparedInput out;
  if (input.triangles.empty()) throw Error(ErrorKind::InvalidInput, "input contains no triangles");
  for (const Vec3& p : input.points)
    if (!std::isfinite(p[0]) || !std::isfinite(p[1]) || !std::isfinite(p[2]))
      throw Error(ErrorKind::InvalidInput, "input has a vertex with a non-finite coordinate");
  // The extent of the surface, not of the file: stray points that no triangle uses (scans keep
  // them) would otherwise widen every size given in % of the diagonal.
  Box3 box;
  for (const Tri& t : input.triangles)
    for (uint32_t v : t) box.add(input.points[v]);
  out.origin = box.center();
  out.diagonal = box.diagonal();
  if (!(out.diagonal > 0)) throw Error(ErrorKind::InvalidInput, "input has zero extent (all vertices coincide)");

  if (progress) progress->progress("prepare", 0.0, "welding vertices");
  // Points equal in the input stay equal in the local frame, and the weld's distinct points
  // come in the order of first appearance either way: welding the input's distinct points
  // and composing gives what welding all of them would (an STL file repeats each about six
  // times, and their exact weld was half of this step).
  const std::vector<Vec3>& from = input_weld ? input_weld->unique : input.points;
  std::vector<Vec3> local(from.size());
  tbb::parallel_for(tbb::blocked_range<size_t>(0, local.size(), 8192), [&](const tbb::blocked_range<size_t>& r) {
    for (size_t i = r.begin(); i != r.end(); ++i) local[i] = from[i] - out.origin;
  });
  std::vector<Vec3> welded;
  std::vector<uint32_t> remap = mesh::weld_points(local, params.weld_tolerance * out.diagonal, welded);
  if (input_weld) {
    std::vector<uint32_t> composed(input.points.size());
    tbb::parallel_for(tbb::blocked_range<size_t>(0, composed.size(), 8192), [&](const tbb::blocked_range<size_t>& r) {
      for (size_t i = r.begin(); i != r.end(); ++i) composed[i] = remap[input_weld->remap[i]];
    });
    remap.swap(composed);
  }
  out.welded_vertices = input.points.size() - welded.size();

  // Drop triangles with repeated or collinear vertices (normal undefined) and exact duplicates.
  Mesh& m = out.mesh;
  m.points = std::move(welded);
  m.part_names = input.part_names;
  if (m.part_names.empty()) m.part_names.push_back("part0");
  // Per input triangle, in parallel: its welded corners, and whether it is degenerate. Then
  // copies by a parallel sort of the sorted corner triples: the first of each group (in input
  // order) stays, the others map to it. (A hash map of buckets, one heap block per triangle,
  // was a serial tenth of preparing a million triangles.)
  const size_t n = input.triangles.size();
  std::vector<Tri> welded_tris(n);
  std::vector<uint8_t> degenerate(n, 0), needle(n, 0);
  const double needle_height2 = (kNeedleHeight * out.diagonal) * (kNeedleHeight * out.diagonal);
  struct Corners {
    Tri sorted;
    uint32_t t;
    bool operator<(const Corners& o) const { return sorted != o.sorted ? sorted < o.sorted : t < o.t; }
  };
  std::vector<Corners> corners(n);
  tbb::parallel_for(tbb::blocked_range<size_t>(0, n, 4096), [&](const tbb::blocked_range<size_t>& r) {
    for (size_t t = r.begin(); t != r.end(); ++t) {
      const Tri tri{remap[input.triangles[t][0]], remap[input.triangles[t][1]], remap[input.triangles[t][2]]};
      welded_tris[t] = tri;
      const Vec3 &a = m.points[tri[0]], &b = m.points[tri[1]], &c = m.points[tri[2]];
      const double longest2 = std::max({norm2(b - a), norm2(c - b), norm2(a - c)});
      const double twice_area2 = norm2(area_vector(a, b, c));
      degenerate[t] =
          tri[0] == tri[1] || tri[1] == tri[2] || tri[0] == tri[2] || twice_area2 <= 1e-24 * longest2 * longest2;
      needle[t] = !degenerate[t] && twice_area2 <= needle_height2 * longest2;
      Tri sorted = tri;
      std::sort(sorted.begin(), sorted.end());
      corners[t] = {sorted, uint32_t(t)};
    }
  });
  drop_stray_needles(welded_tris, needle, degenerate);
  tbb::parallel_sort(corners.begin(), corners.end());
  std::vector<uint32_t> copy_of(n, UINT32_MAX);  // the first non-degenerate triangle with the same corners
  std::vector<uint8_t> turned(n, 0);             // of those, the ones given again turned: between solids?
  for (size_t k = 0; k < n;) {
    size_t e = k;
    uint32_t first = UINT32_MAX;
    for (; e < n && corners[e].sorted == corners[k].sorted; ++e)
      if (const uint32_t t = corners[e].t; !degenerate[t]) {
        if (first == UINT32_MAX) first = t;
        copy_of[t] = first;
        if (params.contact_faces_inside && !same_turn(welded_tris[t], welded_tris[first]) &&
            (!params.parts_kept_apart || input.part_of(t) == input.part_of(first)))
          turned[first] = 1;
      }
    k = e;
  }
  std::vector<uint8_t> twin;  // per mesh triangle: turned
  out.input_to_mesh.assign(n, UINT32_MAX);
  for (size_t t = 0; t < n; ++t) {
    if (degenerate[t]) {
      ++out.dropped_degenerate;
    } else if (copy_of[t] != t) {
      out.input_to_mesh[t] = out.input_to_mesh[copy_of[t]];  // an earlier triangle: numbered
      ++out.dropped_duplicate;
    } else {
      out.input_to_mesh[t] = uint32_t(m.triangles.size());
      m.triangles.push_back(welded_tris[t]);
      m.triangle_part.push_back(input.part_of(t));
      twin.push_back(turned[t]);
    }
  }
  if (m.triangles.empty())
    throw Error(ErrorKind::InvalidInput,
                "input has no usable triangles: all " + std::to_string(input.triangles.size()) + " are degenerate");
  if (progress && progress->cancelled()) throw Error(ErrorKind::Cancelled, "cancelled");

  if (progress) progress->progress("prepare", 0.3, "orienting connected pieces");
  // One edge listing for orienting and for the feature edges: flips change no triangle's edges.
  EdgeTriangles edges = edge_triangles(m.triangles);
  std::vector<mesh::ContactEdge> contact;  // read in the input's orientation, before orienting
  if (params.contact_faces_inside) {
    mesh::ContactFaces faces =
        mesh::contact_faces(m.points, m.triangles, params.parts_kept_apart ? m.triangle_part : std::vector<int32_t>{},
                            edges, twin, params.feature_angle_deg);
    contact = std::move(faces.edges);
    drop_inside_faces(out, faces.inside, edges, contact);
  }
  out.flipped_triangles = mesh::orient_pieces(m.points, m.triangles, &edges, &out.closed_piece);
  out.closed_piece_size = closed_piece_sizes(m, out.closed_piece);

  out.normals.resize(m.triangles.size());
  tbb::parallel_for(tbb::blocked_range<size_t>(0, m.triangles.size(), 4096), [&](const tbb::blocked_range<size_t>& r) {
    for (size_t t = r.begin(); t != r.end(); ++t) {
      const Tri& tri = m.triangles[t];
      out.normals[t] = normalized(area_vector(m.points[tri[0]], m.points[tri[1]], m.points[tri[2]]));
    }
  });
  if (progress) progress->progress("prepare", 0.5, "finding feature edges");
  out.feature_edges = mesh::find_feature_edges(m.points, m.triangles, out.normals, params.feature_angle_deg, &edges,
                                               params.contact_faces_inside ? &contact : nullptr);

  if (progress) progress->progress("prepare", 0.7, "finding self-intersection lines");
  out.intersecting_pairs = check::find_intersecting_pairs(m.points, m.triangles, check::SoupKind::kInput, &edges);
  for (const auto& seg :
       check::intersection_segments(m.points, m.triangles, out.intersecting_pairs, params.feature_angle_deg))
    out.intersections.push_back({seg.a, seg.b, seg.tri_a, seg.tri_b});
  if (progress) progress->progress("prepare", 1.0, "done");
  return out;
}

}  // namespace vdbwrap::prep
