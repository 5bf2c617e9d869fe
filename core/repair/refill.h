// Part 2 of the repair: remove a region and fill its hole from the contour vertices (Liepa
// 2003: minimal-area triangulation, then refinement), fair the new vertices (bi-Laplacian,
// Botsch & Sorkine 2008), and check the result. A pure function: the mesh is not touched.
// The contour may be several loops (a band cut out of two crossing bodies): each loop is
// filled on its own, and a small piece the region cuts off (the buried end of a pin, a patch
// of a face under it) is deleted instead when it lies within max_deviation of the fill.
#pragma once
#include <cstdint>
#include <string>
#include <vector>

#include "repair/regions.h"
#include "vdbwrap/mesh.h"

namespace vdbwrap::mesh {
class SurfaceIndex;
}

namespace vdbwrap::local_repair {

struct RefillParams {
  double area_ratio = 0.5;   // min/max of the region's and the refill's area must reach this
  double max_deviation = 0;  // model units; 0: no bound
  bool fair = true;
  bool float_coordinates = false;
};

struct Refill {
  bool ok = false;
  std::string why;               // when not ok
  std::vector<Vec3> new_points;  // to append to the mesh's points
  // New triangles: an index below points.size() is a contour vertex, one at or above it is
  // new_points[index - points.size()].
  std::vector<Tri> triangles;
  std::vector<uint32_t> replaces;      // per new triangle, the nearest removed triangle (for its part)
  std::vector<uint32_t> also_removed;  // pieces cut off by the region and deleted with it (sorted)
  size_t loops = 0;                    // contour loops filled
  bool faired = false;
};

// The refill of `region` (sorted live triangle ids). `original`, when given, is the input
// surface: new points must stay within max_deviation of it, as the removed surface must
// stay within max_deviation of the refill.
// A contour as directed edges (vertex -> next vertex) split into simple loops; empty with
// `why` set when it is not closed or a vertex lies on two loops.
std::vector<std::vector<uint32_t>> contour_loops(const std::vector<std::pair<uint32_t, uint32_t>>& edges,
                                                 std::string& why);

Refill refill_region(const std::vector<Vec3>& points, const std::vector<Tri>& triangles, const VertexFaces& faces,
                     const std::vector<uint32_t>& region, const RefillParams& params,
                     const mesh::SurfaceIndex* original = nullptr);

}  // namespace vdbwrap::local_repair
