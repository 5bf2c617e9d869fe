// Stage 3 feature snapping (spec: chamfered convex edges, concave edges, corners): feature
// curves as polylines, and wrap node chains traced along them and moved onto them.
#pragma once
#include <cstdint>
#include <functional>
#include <utility>
#include <vector>

#include "common/compressed_lists.h"
#include "prep/prepare.h"
#include "vdbwrap/mesh.h"

namespace vdbwrap::fit {

// A chain of feature edges (sharp, boundary, non-manifold or intersection lines) between
// feature points (corners: where curves meet, end, or turn sharply).
struct FeatureCurve {
  std::vector<Vec3> points;
  bool closed = false;
  bool start_corner = false, end_corner = false;
  bool boundary = false;  // along boundary edges (a hole's rim, a sheet's border)
  bool crease = false;    // along sharp edges (not a rim, not where parts cross)
};

// Builds the curves from the prepared input's feature edges and intersection segments.
// A vertex where the curve turns by more than corner_angle_deg is a corner too.
std::vector<FeatureCurve> build_feature_curves(const prep::PreparedInput& input, double corner_angle_deg);

struct SnapStats {
  size_t curves = 0, corners = 0;  // found
  size_t curves_captured = 0, corners_captured = 0;
  size_t pieces = 0, pieces_traced = 0, nodes_snapped = 0;
};

// The wrap as a graph for tracing: every node's neighbours through polygon edges, quad
// diagonals and fan spokes.
struct WrapGraph {
  CompressedLists neighbours;
};

// Traces each curve, in pieces of about piece_length, as a shortest path over the wrap graph
// among nodes within `radius` of it (edge costs grow with the distance to the curve, so the
// path hugs it), and moves the path's nodes onto the curve, `offset` off it toward their
// lattice positions. Marks snapped nodes and returns the traced wrap edges (node pairs).
// A node moves only where reachable(from, to) says the straight way there is clear of the
// input: curves inside the input (intersection lines of parts buried in the assembly)
// never pull the wrap in.
std::vector<std::pair<uint32_t, uint32_t>> snap_to_curves(
    const std::vector<FeatureCurve>& curves, const WrapGraph& graph, const std::vector<Vec3>& lattice,
    std::vector<Vec3>& target, std::vector<uint8_t>& snapped, double radius, double piece_length, double offset,
    SnapStats& stats, const std::function<bool(const Vec3&, const Vec3&)>& reachable);

}  // namespace vdbwrap::fit
