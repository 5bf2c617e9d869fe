// Mesh diagnostics: the combinatorial checks (borders, non-manifold edges and vertices,
// orientation) and the geometric ones (degenerate and intersecting triangles).
#include <algorithm>
#include <numeric>
#include <stdexcept>

#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_reduce.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_sort.h>
#include <tbb/task_group.h>

#include "check/diagnostics.h"
#include "check/intersections.h"
#include "common/compressed_lists.h"
#include "common/exact_weld.h"
#include "common/fill_vector.h"
#include "common/radix_sort.h"
#include "common/union_find.h"
#include "common/vec.h"
#include "vdbwrap/check.h"

namespace vdbwrap {
namespace {

// The edges of a triangle set by how they are used: by one triangle (a border), by more than
// two (non-manifold), or by two that traverse it the same way (misoriented). Counted from a
// sort of the edge uses: a hash map of edges was the serial bulk of diagnosing millions of
// triangles. `vertices`: above every vertex index.
struct EdgeCounts {
  size_t border = 0, nonmanifold = 0, misoriented = 0;
};

EdgeCounts count_edges(const std::vector<Tri>& tris, size_t vertices) {
  // One word per use: (smaller << 33) | (larger << 1) | forward, so that sorting groups the
  // uses of an edge. Vertex indices below 2^31 leave room for the direction bit.
  // Sorted by a radix sort on the smaller vertex, then each vertex's few uses on their own.
  if (vertices > (size_t(1) << 31)) throw std::length_error("diagnose: more than 2^31 vertices");
  constexpr size_t kChunk = 65536;
  std::vector<std::vector<uint64_t>> parts((tris.size() + kChunk - 1) / kChunk);
  tbb::parallel_for(size_t(0), parts.size(), [&](size_t k) {
    const size_t end = std::min(tris.size(), (k + 1) * kChunk);
    parts[k].reserve(3 * (end - k * kChunk));
    for (size_t f = k * kChunk; f < end; ++f)
      for (int e = 0; e < 3; ++e) {
        const uint32_t a = tris[f][e], b = tris[f][(e + 1) % 3];
        if (a != b)
          parts[k].push_back((uint64_t(std::min(a, b)) << 33) | (uint64_t(std::max(a, b)) << 1) | (a < b ? 1 : 0));
      }
  });
  const FillVector<uint64_t> uses = radix_then_sort(
      parts, [](uint64_t u) { return u >> 33; }, bits_for(vertices), std::less<uint64_t>());
  EdgeCounts out;
  for (size_t i = 0; i < uses.size();) {
    const uint64_t edge = uses[i] >> 1;
    uint32_t count = 0, forward = 0;
    for (; i < uses.size() && (uses[i] >> 1) == edge; ++i) ++count, forward += uint32_t(uses[i] & 1);
    if (count == 1) ++out.border;
    if (count > 2) ++out.nonmanifold;
    if (count == 2 && forward != 1) ++out.misoriented;
  }
  return out;
}

// Vertices whose triangles, joined through the manifold edges (used by exactly two
// triangles) at the vertex, do not form a single fan. Per vertex, the triangles are grouped
// by their other vertices (sorting), not compared pairwise: cylinder caps fan thousands of
// triangles around one vertex. Vertices are independent: a parallel sum.
// A group's size is the number of uses of edge (v, w): a triangle with a corners at v and b
// at w lists w b times for each of its a listings around v, and uses the edge a * b times
// (any two corners of a triangle are adjacent). So the group tells, without looking the
// edge up (a binary search per use was half of the diagnosis on big meshes).
size_t count_nonmanifold_vertices(const std::vector<Tri>& tris, size_t vertices) {
  // Triangles around each vertex (a triangle repeating a vertex is listed once per corner).
  const CompressedLists stars = vertex_triangle_lists(vertices, tris);
  struct Scratch {
    std::vector<std::pair<uint32_t, uint32_t>> by_other;  // (other vertex w, position in the list around v)
    UnionFind uf{0};
  };
  tbb::enumerable_thread_specific<Scratch> scratch;
  return tbb::parallel_reduce(
      tbb::blocked_range<size_t>(0, vertices, 1024), size_t(0),
      [&](const tbb::blocked_range<size_t>& r, size_t count) {
        Scratch& s = scratch.local();
        for (size_t v = r.begin(); v != r.end(); ++v) {
          const CompressedLists::Range around = stars[v];
          const uint32_t n = uint32_t(around.size());
          if (n < 2) continue;
          s.by_other.clear();
          for (uint32_t i = 0; i < n; ++i)
            for (uint32_t w : tris[around.begin()[i]])
              if (w != v) s.by_other.push_back({w, i});
          std::sort(s.by_other.begin(), s.by_other.end());
          s.uf.parent.resize(n);
          std::iota(s.uf.parent.begin(), s.uf.parent.end(), 0);
          // Triangles sharing the edge (v, w) are joined when exactly two triangles use it.
          for (size_t i = 0; i < s.by_other.size();) {
            size_t j = i + 1;
            while (j < s.by_other.size() && s.by_other[j].first == s.by_other[i].first) ++j;
            if (j - i == 2) s.uf.unite(s.by_other[i + 1].second, s.by_other[i].second);
            i = j;
          }
          const uint32_t root = s.uf.find(0);
          for (uint32_t i = 1; i < n; ++i)
            if (s.uf.find(i) != root) {
              ++count;
              break;
            }
        }
        return count;
      },
      std::plus<size_t>());
}

}  // namespace

MeshDiagnostics diagnose(const Mesh& mesh, bool find_intersections) {
  return check::diagnose_welded(mesh, exact_weld(mesh.points), find_intersections);
}

MeshDiagnostics check::diagnose_welded(const Mesh& mesh, const ExactWeld& weld, bool find_intersections) {
  MeshDiagnostics d;
  // Exact weld: only bit-identical coordinates merge, so the counts describe the file as it is.
  const std::vector<Vec3>& pts = weld.unique;
  const std::vector<uint32_t>& remap = weld.remap;
  std::vector<Tri> tris(mesh.triangles.size());
  tbb::parallel_for(tbb::blocked_range<size_t>(0, tris.size(), 16384), [&](const tbb::blocked_range<size_t>& r) {
    for (size_t i = r.begin(); i != r.end(); ++i) {
      const Tri& t = mesh.triangles[i];
      tris[i] = {remap[t[0]], remap[t[1]], remap[t[2]]};
    }
  });
  d.triangles = tris.size();
  // The serial sums and the components (a union-find) run beside the parallel edge and
  // vertex counts: alone they would leave the other cores idle.
  tbb::task_group serial_part;
  serial_part.run([&] {
    std::vector<uint8_t> used(pts.size(), 0);
    for (const Tri& t : tris)
      for (uint32_t v : t) used[v] = 1;
    Box3 box;
    for (size_t i = 0; i < pts.size(); ++i)
      if (used[i]) box.add(pts[i]), ++d.vertices;
    if (!box.empty()) {
      d.bbox_min = box.lo;
      d.bbox_max = box.hi;
      d.diagonal = box.diagonal();
    }
    const Vec3 c = box.empty() ? Vec3{0, 0, 0} : box.center();
    for (const Tri& t : tris) {
      if (t[0] == t[1] || t[1] == t[2] || t[0] == t[2] || norm2(area_vector(pts[t[0]], pts[t[1]], pts[t[2]])) == 0.0) {
        ++d.degenerate_triangles;
      }
      d.area += 0.5 * norm(area_vector(pts[t[0]], pts[t[1]], pts[t[2]]));
      d.volume += dot(pts[t[0]] - c, cross(pts[t[1]] - c, pts[t[2]] - c)) / 6.0;
    }
    // Connected components through shared vertices.
    UnionFind uf(pts.size());
    for (const Tri& t : tris) uf.unite(t[0], t[1]), uf.unite(t[1], t[2]);
    for (uint32_t v = 0; v < pts.size(); ++v)
      if (used[v] && uf.find(v) == v) ++d.components;
  });
  {
    std::vector<int32_t> parts(mesh.triangle_part.begin(), mesh.triangle_part.end());
    tbb::parallel_sort(parts.begin(), parts.end());
    d.parts = parts.empty() ? (tris.empty() ? 0 : 1) : size_t(std::unique(parts.begin(), parts.end()) - parts.begin());
  }
  const EdgeCounts edges = count_edges(tris, pts.size());
  const size_t nonmanifold_vertices = count_nonmanifold_vertices(tris, pts.size());
  serial_part.wait();
  d.border_edges = edges.border, d.nonmanifold_edges = edges.nonmanifold, d.misoriented_edges = edges.misoriented;
  d.nonmanifold_vertices = nonmanifold_vertices;

  d.closed = !tris.empty() && d.border_edges == 0 && d.nonmanifold_edges == 0;
  d.manifold = d.nonmanifold_edges == 0 && d.nonmanifold_vertices == 0;
  d.oriented = d.manifold && d.misoriented_edges == 0;
  d.outward = d.closed && d.oriented && d.volume > 0;

  if (find_intersections) {
    auto pairs = check::find_intersecting_pairs(pts, tris);
    d.intersecting_pairs = pairs.size();
    std::vector<uint32_t> hit;
    for (const auto& p : pairs) hit.push_back(p.a), hit.push_back(p.b);
    std::sort(hit.begin(), hit.end());
    d.intersecting_triangles = size_t(std::unique(hit.begin(), hit.end()) - hit.begin());
    d.self_intersecting = !pairs.empty();
  }
  return d;
}

}  // namespace vdbwrap
