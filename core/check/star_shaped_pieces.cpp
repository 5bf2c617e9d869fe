// Star-shaped pieces: the triangles of each such piece get its number, the others none. Two
// triangles of such a piece meet only at their common vertices and edge, so their pairs need
// no test. A CAD assembly is mostly such pieces (cylinders, pins, boxes, spheres), and their
// long thin side triangles are what makes the pair search slow: the boxes of a tilted
// cylinder's sides nearly all overlap.
//
// The proof: take a point O (the piece's mean vertex) and project the piece from O onto a
// sphere around it. If that projection is one-to-one near every point of a closed piece, it
// is a covering of the sphere, and a connected covering of a sphere is one-to-one: no two
// points of the piece lie on one ray from O, so no two triangles meet but at what they share.
// Checked, on the piece with its holes closed (below):
// - closed and connected: every side of every triangle has exactly one neighbour, which runs
//   it the other way;
// - every triangle sees O strictly from the same side (CGAL's exact orientation predicate):
//   each projects one-to-one, and two triangles across an edge project to opposite sides of
//   it (their far corners lie on opposite sides of the plane through O and the edge);
// - around every vertex, the projected triangles turn once round, not twice (a sum of angles
//   in doubles: it is a whole number of turns, so a loose bound decides).
// Holes (an STL's dropped triangles) are closed first by a fan around each hole's centroid,
// for these checks only: if the closed-up piece is one-to-one, so is any part of it. Anything
// unclear leaves the piece unlabelled, and its pairs are tested as before.
#include "check/star_shaped_pieces.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>

#include "check/fan_proofs.h"
#include "check/intersections.h"
#include "common/edge_triangles.h"
#include "common/vec.h"

namespace vdbwrap::check::pair_search {
namespace {

// Per triangle side (3 t + e, from corner e to corner e + 1): the triangle across it when the
// edge has exactly these two usable triangles and they run it opposite ways, and whether it is
// open (the edge's only usable triangle).
struct SideLinks {
  std::vector<uint32_t> across;
  std::vector<uint8_t> open;
};

// `known`: the edges of all the triangles, used when all are usable (the same listing).
SideLinks side_links(const std::vector<Tri>& triangles, const std::vector<uint8_t>& usable,
                     const EdgeTriangles* known) {
  EdgeTriangles made;
  const bool all_usable = std::all_of(usable.begin(), usable.end(), [](uint8_t u) { return u != 0; });
  const EdgeTriangles& edges = known && all_usable ? *known : (made = edge_triangles(triangles, &usable));
  SideLinks out{std::vector<uint32_t>(3 * triangles.size(), kNoPiece), std::vector<uint8_t>(3 * triangles.size(), 0)};
  tbb::parallel_for(tbb::blocked_range<size_t>(0, edges.edges(), 4096), [&](const tbb::blocked_range<size_t>& r) {
    for (size_t i = r.begin(); i != r.end(); ++i) {
      const uint32_t x = edges.begin(i)[0];
      uint32_t a = uint32_t(edges.keys[i] >> 32), b = uint32_t(edges.keys[i] & 0xffffffffu);
      int ex = directed_side(triangles[x], a, b);
      if (ex < 0) std::swap(a, b), ex = directed_side(triangles[x], a, b);
      if (ex < 0) continue;  // a repeated corner
      if (edges.size(i) == 1) {
        out.open[3 * x + ex] = 1;
        continue;
      }
      if (edges.size(i) != 2) continue;
      const uint32_t y = edges.begin(i)[1];
      const int ey = directed_side(triangles[y], b, a);
      if (ey < 0) continue;  // both run it the same way
      out.across[3 * x + ex] = y;
      out.across[3 * y + ey] = x;
    }
  });
  return out;
}

// The usable triangles with every hole closed by a fan of triangles around its centroid (a
// new point). A hole is followed side by side, turning round each corner through the
// triangles there. Holes that cannot be followed (non-manifold edges on the way) stay open.
// Their side links follow from the walk: a fan triangle's first side lies across the open
// side it closes, its other two across its neighbours in the fan (no second edge sort).
struct ClosedUp {
  std::vector<P3> points;
  std::vector<Tri> triangles;  // the given ones first, at their own indexes
  std::vector<uint8_t> usable;
  std::vector<uint32_t> across;  // as SideLinks::across, for all of them
};

ClosedUp close_holes(const std::vector<P3>& p, const std::vector<Tri>& triangles, const std::vector<uint8_t>& usable,
                     const EdgeTriangles* edges) {
  ClosedUp out{p, triangles, usable, {}};
  SideLinks links = side_links(triangles, usable, edges);
  // The open side after side (t, e), which runs a -> b with a = t[e]: the hole runs b -> a and
  // goes on from a along the next open side met turning round a.
  constexpr uint32_t none = UINT32_MAX;
  auto next_open = [&](uint32_t t, int e) -> uint32_t {
    const uint32_t a = triangles[t][e];
    for (int guard = 0; guard < 1 << 20; ++guard) {
      const int s = (e + 2) % 3;  // t's side that ends at a
      if (links.open[3 * t + s]) return 3 * t + uint32_t(s);
      const uint32_t nb = links.across[3 * t + s];
      if (nb == kNoPiece) return none;
      e = directed_side(triangles[nb], a, triangles[t][s]);
      t = nb;
    }
    return none;
  };
  // A hole side: its first corner, and the open triangle side it runs back along.
  struct HoleSide {
    uint32_t corner, open_side;
  };
  std::vector<uint32_t>& across = links.across;  // grows with the fans
  auto close_with_fan = [&](const HoleSide* sides, size_t count) {
    if (count < 3) return;
    double m[3] = {0, 0, 0};
    for (size_t k = 0; k < count; ++k)
      for (int i = 0; i < 3; ++i) m[i] += p[sides[k].corner][i] / double(count);
    const uint32_t centre = uint32_t(out.points.size());
    out.points.emplace_back(m[0], m[1], m[2]);
    const uint32_t first = uint32_t(out.triangles.size());
    for (size_t k = 0; k < count; ++k) {
      const uint32_t f = first + uint32_t(k), next = first + uint32_t((k + 1) % count),
                     prev = first + uint32_t((k + count - 1) % count);
      out.triangles.push_back({sides[k].corner, sides[(k + 1) % count].corner, centre});
      out.usable.push_back(1);
      across.insert(across.end(), {sides[k].open_side / 3, next, prev});
      across[sides[k].open_side] = f;
    }
  };
  std::vector<uint8_t> visited(links.open.size(), 0);
  std::vector<HoleSide> loop, stack;  // a walk round holes, in order
  std::vector<uint32_t> stack_at(p.size(), none);
  for (uint32_t start = 0; start < links.open.size(); ++start) {
    if (!links.open[start] || visited[start]) continue;
    loop.clear();
    uint32_t side = start;
    while (side != none && !visited[side]) {
      visited[side] = 1;
      loop.push_back({triangles[side / 3][(side % 3 + 1) % 3], side});  // the hole side's first corner, b
      side = next_open(side / 3, int(side % 3));
    }
    if (side != start) continue;  // not followed back round to its start
    // Where the walk comes back to a corner it passed (a cap's centre between two of its
    // dropped triangles), the stretch since then is a hole of its own: the walk turns into the
    // next hole at that corner, because a hole cannot be crossed to find its own other side.
    for (const HoleSide& h : loop) {
      const uint32_t w = h.corner;
      if (stack_at[w] == none) {
        stack_at[w] = uint32_t(stack.size());
        stack.push_back(h);
        continue;
      }
      close_with_fan(stack.data() + stack_at[w], stack.size() - stack_at[w]);
      for (size_t k = stack_at[w] + 1; k < stack.size(); ++k) stack_at[stack[k].corner] = none;
      stack.resize(stack_at[w]);
      stack.push_back(h);  // w goes on, now with the side leaving it
    }
    close_with_fan(stack.data(), stack.size());
    for (const HoleSide& h : stack) stack_at[h.corner] = none;
    stack.clear();
  }
  out.across = std::move(across);
  return out;
}

// Seen from `o`, do the triangles around vertex c turn once round it? (Their orientation
// towards o is checked exactly elsewhere; here only the number of turns.) Each angle must be
// well clear of 0 and of a half turn, so that its rounding cannot matter; a nearly edge-on
// view (a flat piece seen from its own plane) gives no answer.
bool turns_once(const std::vector<P3>& p, const std::vector<Tri>& triangles, const VertexStars& stars, uint32_t c,
                const P3& o) {
  const Vec3 w = normalized(Vec3{p[c].x() - o.x(), p[c].y() - o.y(), p[c].z() - o.z()});
  auto flat = [&](const P3& q) {  // q - c, with its part along the ray from o taken out
    const Vec3 d{q.x() - p[c].x(), q.y() - p[c].y(), q.z() - p[c].z()};
    return d - w * dot(d, w);
  };
  constexpr double clear = 1e-7;  // sine of the smallest angle trusted
  double turn = 0;
  for (uint32_t k = stars.first[c]; k < stars.first[c + 1]; ++k) {
    const Tri& t = triangles[stars.items[k]];
    int i = 0;
    while (t[i] != c) ++i;
    const Vec3 a = flat(p[t[(i + 1) % 3]]), b = flat(p[t[(i + 2) % 3]]);
    const double sine = dot(cross(a, b), w), scale = norm(a) * norm(b);
    if (!(std::fabs(sine) > clear * scale)) return false;
    turn += std::fabs(std::atan2(sine, dot(a, b)));
  }
  return std::fabs(turn - 2 * M_PI) < 1.0;
}

}  // namespace

std::vector<uint32_t> star_shaped_pieces(const std::vector<P3>& given_points, const std::vector<Tri>& given_triangles,
                                         const std::vector<uint8_t>& given_usable, const EdgeTriangles* edges) {
  const ClosedUp closed = close_holes(given_points, given_triangles, given_usable, edges);
  const std::vector<P3>& p = closed.points;
  const std::vector<Tri>& triangles = closed.triangles;
  const std::vector<uint8_t>& usable = closed.usable;
  const size_t n = triangles.size();
  const std::vector<uint32_t>& across = closed.across;
  // Pieces: triangles joined across such sides (a serial walk; cheap beside the rest), and
  // each piece's mean vertex (of its triangles' corners).
  std::vector<uint32_t> piece(n, kNoPiece);
  std::vector<uint8_t> ok;  // per piece
  std::vector<P3> centre;
  std::vector<uint32_t> queue;
  for (uint32_t seed = 0; seed < n; ++seed) {
    if (!usable[seed] || piece[seed] != kNoPiece) continue;
    const uint32_t id = uint32_t(ok.size());
    ok.push_back(1);
    piece[seed] = id;
    queue.assign(1, seed);
    double sum[3] = {0, 0, 0};
    for (size_t q = 0; q < queue.size(); ++q) {
      for (uint32_t v : triangles[queue[q]])
        for (int k = 0; k < 3; ++k) sum[k] += p[v][k];
      for (int e = 0; e < 3; ++e) {
        const uint32_t nb = across[3 * queue[q] + e];
        if (nb == kNoPiece) {
          ok[id] = 0;  // open, non-manifold, inconsistently oriented or beside a degenerate triangle
        } else if (piece[nb] == kNoPiece) {
          piece[nb] = id;
          queue.push_back(nb);
        }
      }
    }
    const double corners = 3.0 * double(queue.size());
    centre.emplace_back(sum[0] / corners, sum[1] / corners, sum[2] / corners);
  }
  // Triangles: each sees its piece's centre strictly from one side, the same for the piece.
  std::vector<int8_t> facing(n, 0);
  tbb::parallel_for(tbb::blocked_range<size_t>(0, n, 4096), [&](const tbb::blocked_range<size_t>& r) {
    for (size_t t = r.begin(); t != r.end(); ++t) {
      if (piece[t] == kNoPiece || !ok[piece[t]]) continue;
      const Tri& tri = triangles[t];
      facing[t] = int8_t(CGAL::orientation(p[tri[0]], p[tri[1]], p[tri[2]], centre[piece[t]]));
    }
  });
  std::vector<int8_t> piece_facing(ok.size(), 0);
  for (size_t t = 0; t < n; ++t) {
    const uint32_t id = piece[t];
    if (id == kNoPiece || !ok[id]) continue;
    if (facing[t] == 0 || (piece_facing[id] != 0 && facing[t] != piece_facing[id])) ok[id] = 0;
    piece_facing[id] = facing[t];
  }
  // Vertices: all their triangles in one piece, turning once round.
  const VertexStars stars = vertex_stars(p.size(), triangles, usable);
  std::vector<uint8_t> vertex_ok(p.size(), 1);
  tbb::parallel_for(tbb::blocked_range<size_t>(0, p.size(), 4096), [&](const tbb::blocked_range<size_t>& r) {
    for (size_t c = r.begin(); c != r.end(); ++c) {
      if (stars[c].empty()) continue;
      const uint32_t id = piece[stars.items[stars.first[c]]];
      if (!ok[id]) continue;
      bool one_piece = true;
      for (uint32_t k = stars.first[c]; k < stars.first[c + 1] && one_piece; ++k)
        one_piece = piece[stars.items[k]] == id;
      vertex_ok[c] = one_piece && turns_once(p, triangles, stars, uint32_t(c), centre[id]);
    }
  });
  for (size_t c = 0; c < p.size(); ++c)
    if (!vertex_ok[c])
      for (uint32_t k = stars.first[c]; k < stars.first[c + 1]; ++k) ok[piece[stars.items[k]]] = 0;
  piece.resize(given_triangles.size());  // the fans were for the checks only
  tbb::parallel_for(tbb::blocked_range<size_t>(0, piece.size(), 4096), [&](const tbb::blocked_range<size_t>& r) {
    for (size_t t = r.begin(); t != r.end(); ++t)
      if (piece[t] != kNoPiece && !ok[piece[t]]) piece[t] = kNoPiece;
  });
  return piece;
}

}  // namespace vdbwrap::check::pair_search

namespace vdbwrap::check {

std::vector<uint32_t> star_shaped_pieces(const std::vector<Vec3>& points, const std::vector<Tri>& triangles) {
  const pair_search::ExactInput in = pair_search::exact_input(points, triangles);
  return pair_search::star_shaped_pieces(in.p, triangles, in.usable);
}

}  // namespace vdbwrap::check
