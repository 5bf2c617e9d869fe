// Part 1 of the repair: the two local operations of the paper, vertex shift and triangle
// shift, as pure functions that plan a move (new vertex positions) and measure it.
#pragma once
#include <cstdint>
#include <utility>
#include <vector>

#include "check/intersections.h"
#include "repair/regions.h"
#include "vdbwrap/mesh.h"

namespace vdbwrap::local_repair {

// New positions for some vertices, with what the queue is sorted and filtered by.
struct Move {
  enum class Kind { VertexShift, TriangleShift, Untangle };  // Untangle: untangle.h
  Kind kind = Kind::VertexShift;
  std::vector<std::pair<uint32_t, Vec3>> positions;  // vertex, new position
  double volume_change = 0;                          // |volume swept by the modified triangles|
  double area_ratio = 1;                             // r_S (area_change_ratio) of the modified triangles
  bool primary = true;  // the paper's choice; others are tried after it (see plan_vertex_shifts)
};

// Points where segment (a, b) meets triangle (p, q, r): none, one crossing point, or the two
// ends of the overlap when they are coplanar. Double precision (the exact predicates decide
// whether a pair intersects; these points only place the moves).
std::vector<Vec3> segment_triangle_points(const Vec3& a, const Vec3& b, const Vec3& p, const Vec3& q, const Vec3& r,
                                          bool* coplanar = nullptr);

// An edge of one triangle of an intersecting pair passing through the other triangle.
struct Crossing {
  uint32_t u, v;             // the edge
  uint32_t triangle;         // the triangle it cuts
  std::vector<Vec3> points;  // where (shared vertices left out)
  bool coplanar = false;     // the edge lies in the triangle's plane: points are the overlap's ends
};
std::vector<Crossing> edge_crossings(const std::vector<Vec3>& points, const std::vector<Tri>& triangles,
                                     const std::vector<check::TrianglePair>& pairs);

struct LocalParams {
  double alpha = 0.25, beta = 0.1, delta = 0.5, gamma = 0.001;
  double accuracy = 1e-16;  // model accuracy eps
};

// The paper's t_n: the clearance kept past a crossing, as a fraction of the gap d to the next
// crossing (or to the edge's far end). l, L: shortest and longest edge of the region.
double shift_fraction(double gap, double shortest, double longest, double alpha, double beta);

// Vertex shift: for the region vertex on the most cutting edges (each such vertex on a tie),
// and, marked not primary, for up to `extra` other vertices on cutting edges (by count) —
// when the paper's vertex cannot move, another one often can;
// the average of a'_n = x1 + t_n (x2 - x1) over its cutting edges a-b_n, x1 the crossing
// nearest to a and x2 the next crossing, or b_n when there is one crossing. An edge lying in
// a triangle's plane crosses it where the overlap ends (its end farther from a). The paper prints
// these with the anchor and sign swapped; this follows its stated intent, a clearance of
// t_n |x1 x2| between the new point and the crossing, on the far side of it.
std::vector<Move> plan_vertex_shifts(const std::vector<Vec3>& points, const std::vector<Tri>& triangles,
                                     const std::vector<uint32_t>& region, const std::vector<Crossing>& crossings,
                                     const LocalParams& params, size_t extra = 0);

// eps_move: delta * eps, at least 1e-16, at most gamma * L.
double move_epsilon(double accuracy, double longest, double delta, double gamma);

// Triangle shift: the region triangle in the most pairs moved along its normal n past the
// vertices of the edges that cut it, to d_max + eps_move and to d_min - eps_move (two moves).
std::vector<Move> plan_triangle_shifts(const std::vector<Vec3>& points, const std::vector<Tri>& triangles,
                                       const std::vector<uint32_t>& region,
                                       const std::vector<check::TrianglePair>& pairs,
                                       const std::vector<Crossing>& crossings, const LocalParams& params);

// The paper's r_S, min/max of the modified triangles' area before and after, written as
// 1 - |after - before| / max(before, after), with the area of the same triangles as half-squares
// of their longest edges (`half_squares`) in the denominator when it is larger. Triangles at
// least as fat as a half-square keep the paper's ratio; for needles the change is measured
// against their length: moving a needle's apex sideways by a fraction of its short edge halves
// or doubles its area while the surface moves less than it would on a well-shaped triangle.
double area_change_ratio(double before, double after, double half_squares);

// Fills volume_change and area_ratio from the triangles around the moved vertices.
void measure_move(const std::vector<Vec3>& points, const std::vector<Tri>& triangles, const VertexFaces& faces,
                  Move& move);

// The triangles a move changes: all live triangles around its vertices, sorted.
std::vector<uint32_t> triangles_moved(const VertexFaces& faces, const Move& move);

}  // namespace vdbwrap::local_repair
