// Vertex shift and triangle shift (paper, part 1), planned and measured without touching
// the mesh: the caller applies a move, checks the intersections and keeps or undoes it.
#include "repair/local_operations.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <unordered_map>

#include "common/edge_key.h"
#include "common/vec.h"

namespace vdbwrap::local_repair {
namespace {

bool has_vertex(const Tri& t, uint32_t v) { return t[0] == v || t[1] == v || t[2] == v; }

}  // namespace

std::vector<Vec3> segment_triangle_points(const Vec3& a, const Vec3& b, const Vec3& p, const Vec3& q, const Vec3& r,
                                          bool* coplanar) {
  if (coplanar) *coplanar = false;
  Vec3 n = area_vector(p, q, r);
  double nn = norm(n);
  Vec3 ab = b - a;
  double len = norm(ab);
  if (nn <= 0 || len <= 0) return {};
  n = n * (1.0 / nn);
  double da = dot(a - p, n), db = dot(b - p, n);
  const double scale = std::max({len, norm(q - p), norm(r - q), norm(p - r)});
  const double tol = 1e-12 * scale;
  if ((da > tol && db > tol) || (da < -tol && db < -tol)) return {};
  const Vec3 corner[3] = {p, q, r};
  if (std::fabs(da) <= tol && std::fabs(db) <= tol) {
    // Coplanar: clip the segment by the three inward half-planes of the triangle.
    if (coplanar) *coplanar = true;
    double s0 = 0, s1 = 1;
    for (int k = 0; k < 3; ++k) {
      Vec3 m = cross(n, corner[(k + 1) % 3] - corner[k]);  // inward, in the plane
      double f0 = dot(a - corner[k], m), df = dot(ab, m);
      double slack = tol * norm(m);
      if (std::fabs(df) <= 0) {
        if (f0 < -slack) return {};
        continue;
      }
      double s = -f0 / df;
      if (df > 0)
        s0 = std::max(s0, s);
      else
        s1 = std::min(s1, s);
    }
    if (s0 > s1) return {};
    if (s1 - s0 <= 1e-12) return {a + ab * s0};
    return {a + ab * s0, a + ab * s1};
  }
  double s = da / (da - db);
  s = std::clamp(s, 0.0, 1.0);
  Vec3 x = a + ab * s;
  // Inside the triangle: on the inner side of all three edges (with a little slack).
  for (int k = 0; k < 3; ++k) {
    Vec3 m = cross(n, corner[(k + 1) % 3] - corner[k]);
    if (dot(x - corner[k], m) < -tol * norm(m)) return {};
  }
  return {x};
}

std::vector<Crossing> edge_crossings(const std::vector<Vec3>& points, const std::vector<Tri>& triangles,
                                     const std::vector<check::TrianglePair>& pairs) {
  std::map<std::pair<uint64_t, uint32_t>, Crossing> found;  // (edge, triangle cut)
  for (const auto& pair : pairs) {
    if (pair.a == pair.b) continue;  // a degenerate triangle, not a pair
    for (int side = 0; side < 2; ++side) {
      const Tri& x = triangles[side ? pair.b : pair.a];
      uint32_t cut = side ? pair.a : pair.b;
      const Tri& y = triangles[cut];
      for (int k = 0; k < 3; ++k) {
        uint32_t u = x[k], v = x[(k + 1) % 3];
        if (u == v || (has_vertex(y, u) && has_vertex(y, v))) continue;  // the common edge
        auto key = std::make_pair(edge_key(u, v), cut);
        if (found.count(key)) continue;
        bool coplanar = false;
        std::vector<Vec3> pts =
            segment_triangle_points(points[u], points[v], points[y[0]], points[y[1]], points[y[2]], &coplanar);
        // A shared vertex is where the two triangles are meant to meet: not a crossing.
        const double near = 1e-12 * norm(points[v] - points[u]);
        pts.erase(std::remove_if(pts.begin(), pts.end(),
                                 [&](const Vec3& z) {
                                   return (has_vertex(y, u) && norm(z - points[u]) <= near) ||
                                          (has_vertex(y, v) && norm(z - points[v]) <= near);
                                 }),
                  pts.end());
        if (pts.empty()) continue;
        found.emplace(key, Crossing{std::min(u, v), std::max(u, v), cut, std::move(pts), coplanar});
      }
    }
  }
  std::vector<Crossing> out;
  out.reserve(found.size());
  for (auto& [key, c] : found) out.push_back(std::move(c));
  return out;
}

double shift_fraction(double gap, double shortest, double longest, double alpha, double beta) {
  if (0.5 * gap <= shortest) return 0.5;
  if (shortest < alpha * gap && alpha * gap < beta * longest) return alpha;
  return shortest / gap;
}

std::vector<Move> plan_vertex_shifts(const std::vector<Vec3>& points, const std::vector<Tri>& triangles,
                                     const std::vector<uint32_t>& region, const std::vector<Crossing>& crossings,
                                     const LocalParams& params, size_t extra) {
  // Cutting edges (each once) and their crossings; an overlap in a plane keeps both ends
  // (the one farther from the moving vertex is its crossing).
  std::unordered_map<uint64_t, std::vector<const Crossing*>> along;
  for (const Crossing& c : crossings) along[edge_key(c.u, c.v)].push_back(&c);
  const std::vector<uint32_t> region_vertices = vertices_of(triangles, region);
  std::unordered_map<uint32_t, int> cutting;  // vertex -> cutting edges on it
  for (const auto& [key, list] : along) {
    uint32_t u = uint32_t(key >> 32), v = uint32_t(key & 0xffffffffu);
    for (uint32_t w : {u, v})
      if (std::binary_search(region_vertices.begin(), region_vertices.end(), w)) ++cutting[w];
  }
  std::vector<std::pair<int, uint32_t>> ranked;  // (-count, vertex)
  for (const auto& [v, count] : cutting) ranked.push_back({-count, v});
  if (ranked.empty()) return {};
  std::sort(ranked.begin(), ranked.end());
  const int most = -ranked.front().first;
  std::vector<uint32_t> chosen;
  size_t primaries = 0;
  for (const auto& [count, v] : ranked) {
    if (-count == most) {
      if (primaries < 4) chosen.push_back(v), ++primaries;  // ties: a few, the queue orders them
    } else if (chosen.size() < primaries + extra) {
      chosen.push_back(v);
    }
  }
  const EdgeRange range = edge_range(points, triangles, region);
  std::vector<Move> moves;
  for (uint32_t a : chosen) {
    Vec3 sum{0, 0, 0};
    int used = 0;
    for (const auto& [key, raw] : along) {
      uint32_t u = uint32_t(key >> 32), v = uint32_t(key & 0xffffffffu);
      if (u != a && v != a) continue;
      uint32_t b = u == a ? v : u;
      std::vector<Vec3> pts;
      for (const Crossing* c : raw) {
        if (!c->coplanar) {
          pts.insert(pts.end(), c->points.begin(), c->points.end());
          continue;
        }
        pts.push_back(*std::max_element(c->points.begin(), c->points.end(), [&](const Vec3& p, const Vec3& q) {
          return norm2(p - points[a]) < norm2(q - points[a]);
        }));
      }
      std::sort(pts.begin(), pts.end(),
                [&](const Vec3& p, const Vec3& q) { return norm2(p - points[a]) < norm2(q - points[a]); });
      const Vec3& x1 = pts[0];
      const Vec3& x2 = pts.size() > 1 ? pts[1] : points[b];
      double gap = norm(x2 - x1);
      if (!(gap > 0)) continue;
      double t = shift_fraction(gap, range.shortest, range.longest, params.alpha, params.beta);
      sum = sum + lerp(x1, x2, t);
      ++used;
    }
    if (used == 0) continue;
    Move m;
    m.kind = Move::Kind::VertexShift;
    m.primary = cutting[a] == most;
    m.positions.push_back({a, sum * (1.0 / used)});
    moves.push_back(std::move(m));
  }
  return moves;
}

double move_epsilon(double accuracy, double longest, double delta, double gamma) {
  double de = delta * accuracy;
  if (de <= gamma * longest) return std::max(1e-16, de);
  return gamma * longest;
}

std::vector<Move> plan_triangle_shifts(const std::vector<Vec3>& points, const std::vector<Tri>& triangles,
                                       const std::vector<uint32_t>& region,
                                       const std::vector<check::TrianglePair>& pairs,
                                       const std::vector<Crossing>& crossings, const LocalParams& params) {
  // The triangle in the most pairs (the first on a tie).
  std::unordered_map<uint32_t, int> count;
  for (const auto& p : pairs)
    if (p.a != p.b) ++count[p.a], ++count[p.b];
  uint32_t best = UINT32_MAX;
  int most = 0;
  for (uint32_t t : region) {
    auto it = count.find(t);
    if (it != count.end() && (it->second > most)) most = it->second, best = t;
  }
  if (best == UINT32_MAX) return {};
  const Tri& tri = triangles[best];
  Vec3 n = normalized(area_vector(points[tri[0]], points[tri[1]], points[tri[2]]));
  if (norm2(n) == 0) return {};
  // p_i: vertices of the edges that cut it; when only its own edges cut the others, the
  // vertices of the triangles it meets, so the shifted plane clears them as well.
  std::vector<uint32_t> p;
  for (const Crossing& c : crossings)
    if (c.triangle == best) p.push_back(c.u), p.push_back(c.v);
  if (p.empty())
    for (const auto& pair : pairs)
      if (pair.a != pair.b && (pair.a == best || pair.b == best)) {
        const Tri& other = triangles[pair.a == best ? pair.b : pair.a];
        p.insert(p.end(), other.begin(), other.end());
      }
  double dmin = INFINITY, dmax = -INFINITY;
  for (uint32_t v : p) {
    if (has_vertex(tri, v)) continue;
    double d = dot(points[v] - points[tri[0]], n);
    dmin = std::min(dmin, d);
    dmax = std::max(dmax, d);
  }
  if (!(dmin <= dmax)) return {};
  const EdgeRange range = edge_range(points, triangles, region);
  const double eps = move_epsilon(params.accuracy, range.longest, params.delta, params.gamma);
  std::vector<Move> moves;
  for (double shift : {dmax + eps, dmin - eps}) {
    Move m;
    m.kind = Move::Kind::TriangleShift;
    for (uint32_t v : tri) m.positions.push_back({v, points[v] + n * shift});
    moves.push_back(std::move(m));
  }
  return moves;
}

std::vector<uint32_t> triangles_moved(const VertexFaces& faces, const Move& move) {
  std::vector<uint32_t> out;
  for (const auto& [v, pos] : move.positions) out.insert(out.end(), faces.begin(v), faces.end(v));
  std::sort(out.begin(), out.end());
  out.erase(std::unique(out.begin(), out.end()), out.end());
  return out;
}

void measure_move(const std::vector<Vec3>& points, const std::vector<Tri>& triangles, const VertexFaces& faces,
                  Move& move) {
  auto moved_point = [&](uint32_t v) -> const Vec3& {
    for (const auto& [w, pos] : move.positions)
      if (w == v) return pos;
    return points[v];
  };
  Vec3 origin{0, 0, 0};
  for (const auto& [v, pos] : move.positions) origin = origin + points[v];
  origin = origin * (1.0 / double(std::max<size_t>(1, move.positions.size())));
  double area_before = 0, area_after = 0, half_squares = 0, volume = 0;
  auto longest2 = [](const Vec3& a, const Vec3& b, const Vec3& c) {
    return std::max({norm2(b - a), norm2(c - b), norm2(a - c)});
  };
  for (uint32_t t : triangles_moved(faces, move)) {
    const Tri& tri = triangles[t];
    const Vec3 &a = points[tri[0]], &b = points[tri[1]], &c = points[tri[2]];
    const Vec3 &a2 = moved_point(tri[0]), &b2 = moved_point(tri[1]), &c2 = moved_point(tri[2]);
    area_before += 0.5 * norm(area_vector(a, b, c));
    area_after += 0.5 * norm(area_vector(a2, b2, c2));
    half_squares += 0.25 * std::max(longest2(a, b, c), longest2(a2, b2, c2));
    // Signed volume of the cone from `origin`: its change is the volume the move sweeps.
    volume +=
        dot(a2 - origin, cross(b2 - origin, c2 - origin)) / 6 - dot(a - origin, cross(b - origin, c - origin)) / 6;
  }
  move.volume_change = std::fabs(volume);
  move.area_ratio = area_change_ratio(area_before, area_after, half_squares);
}

double area_change_ratio(double before, double after, double half_squares) {
  const double hi = std::max({before, after, half_squares});
  return hi > 0 ? 1 - std::fabs(after - before) / hi : 1.0;
}

}  // namespace vdbwrap::local_repair
