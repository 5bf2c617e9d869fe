// Regions of intersecting triangles and the mesh adjacency the repair stages share.
#pragma once
#include <cstdint>
#include <vector>

#include "check/intersections.h"
#include "vdbwrap/mesh.h"

namespace vdbwrap::local_repair {

// A triangle the repair deleted keeps its slot with three equal indices, so triangle ids stay
// stable while the intersection checks (which skip degenerate triangles) ignore it.
inline bool is_dead(const Tri& t) { return t[0] == t[1] && t[1] == t[2]; }
inline Tri dead_triangle() { return {0, 0, 0}; }

// Triangles around each vertex (dead triangles left out), in compressed rows.
struct VertexFaces {
  std::vector<uint32_t> offset, faces;
  size_t size(uint32_t v) const { return offset[v + 1] - offset[v]; }
  const uint32_t* begin(uint32_t v) const { return faces.data() + offset[v]; }
  const uint32_t* end(uint32_t v) const { return faces.data() + offset[v + 1]; }
};
VertexFaces vertex_faces(size_t point_count, const std::vector<Tri>& triangles);

// Live triangles on edge (u, v).
size_t edge_use(const std::vector<Tri>& triangles, const VertexFaces& faces, uint32_t u, uint32_t v);

// Splits `triangles` into regions that share no vertex: two triangles are in one region when
// they share a vertex or form one of `pairs`. Regions and their triangles are sorted.
std::vector<std::vector<uint32_t>> group_regions(const std::vector<Tri>& all, const std::vector<uint32_t>& triangles,
                                                 const std::vector<check::TrianglePair>& pairs);

// Finer groups for planning local operations: two triangles are in one cluster when they share
// an edge or form one of `pairs`. A fan's hub (a pole, a cap's centre) joins all the needles
// around it into one region; folds far apart on the fan are separate clusters, each with moves
// of its own. Clusters and their triangles are sorted.
std::vector<std::vector<uint32_t>> group_clusters(const std::vector<Tri>& all, const std::vector<uint32_t>& triangles,
                                                  const std::vector<check::TrianglePair>& pairs);

// The triangles of the pairs (each once, sorted); (t, t) entries for degenerate ones count.
std::vector<uint32_t> triangles_of(const std::vector<check::TrianglePair>& pairs);

// `set` (sorted) plus every live triangle that shares a vertex with it, sorted.
std::vector<uint32_t> grow_ring(const std::vector<Tri>& all, const VertexFaces& faces,
                                const std::vector<uint32_t>& set);

// `set` (sorted) plus every live triangle around each vertex where the set's border pinches
// (a vertex that two of its border loops pass through), repeated up to `rounds` times: a
// contour of simple loops, grown only where it needed to be. Sorted.
std::vector<uint32_t> close_pinches(const std::vector<Tri>& all, const VertexFaces& faces, std::vector<uint32_t> set,
                                    int rounds = 3);

// The distinct vertices of a triangle set, sorted.
std::vector<uint32_t> vertices_of(const std::vector<Tri>& all, const std::vector<uint32_t>& set);

// Shortest and longest edge of a triangle set.
struct EdgeRange {
  double shortest = 0, longest = 0;
};
EdgeRange edge_range(const std::vector<Vec3>& points, const std::vector<Tri>& all, const std::vector<uint32_t>& set);

}  // namespace vdbwrap::local_repair
