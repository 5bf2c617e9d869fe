// Fan proofs (see fan_proofs.h) and the public closed_fan_unfolded they rest on.
#include "check/fan_proofs.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

#include "check/intersections.h"
#include "check/plane_proofs.h"
#include "common/vec.h"

namespace vdbwrap::check::pair_search {

VertexStars vertex_stars(size_t points, const std::vector<Tri>& triangles, const std::vector<uint8_t>& usable) {
  return compressed_lists(points, [&](auto&& emit) {
    for (uint32_t t = 0; t < triangles.size(); ++t)
      if (usable[t])
        for (uint32_t v : triangles[t]) emit(v, t);
  });
}

std::vector<uint8_t> unfolded_fan_vertices(const std::vector<P3>& p, const std::vector<Tri>& triangles,
                                           const VertexStars& stars) {
  constexpr uint32_t min_fan = 16;
  const std::vector<uint32_t>& first = stars.first;
  const auto& star = stars.items;
  std::vector<uint8_t> fan(p.size(), 0);
  tbb::parallel_for(tbb::blocked_range<size_t>(0, p.size(), 4096), [&](const tbb::blocked_range<size_t>& r) {
    struct Sector {
      uint32_t a, b;  // the triangle (c, a, b) in its own order
      V2 da, db;      // a - c and b - c, projected
      double start, width;
    };
    std::vector<Sector> sectors;
    for (size_t c = r.begin(); c != r.end(); ++c) {
      if (first[c + 1] - first[c] < min_fan) continue;
      sectors.clear();
      const P3& o = p[c];
      double normal[3] = {0, 0, 0};
      for (uint32_t k = first[c]; k < first[c + 1]; ++k) {
        const Tri& t = triangles[star[k]];
        int i = 0;
        while (t[i] != c) ++i;
        const P3 &pa = p[t[(i + 1) % 3]], &pb = p[t[(i + 2) % 3]];
        const double u[3] = {pa.x() - o.x(), pa.y() - o.y(), pa.z() - o.z()},
                     v[3] = {pb.x() - o.x(), pb.y() - o.y(), pb.z() - o.z()};
        normal[0] += u[1] * v[2] - u[2] * v[1], normal[1] += u[2] * v[0] - u[0] * v[2],
            normal[2] += u[0] * v[1] - u[1] * v[0];
        sectors.push_back({t[(i + 1) % 3], t[(i + 2) % 3], {}, {}, 0, 0});
      }
      int drop = 0;
      for (int k = 1; k < 3; ++k)
        if (std::fabs(normal[k]) > std::fabs(normal[drop])) drop = k;
      const int u = (drop + 1) % 3, v = (drop + 2) % 3;
      const double mirror = normal[drop] > 0 ? 1.0 : -1.0;  // so that the fan turns counter-clockwise
      double magnitude = std::max(std::fabs(o[u]), std::fabs(o[v]));
      for (const Sector& q : sectors)
        magnitude = std::max(
            {magnitude, std::fabs(p[q.a][u]), std::fabs(p[q.a][v]), std::fabs(p[q.b][u]), std::fabs(p[q.b][v])});
      const double err = 8 * std::numeric_limits<double>::epsilon() * magnitude;
      bool ok = true;
      for (Sector& q : sectors) {
        q.da = {mirror * (p[q.a][u] - o[u]), p[q.a][v] - o[v]};
        q.db = {mirror * (p[q.b][u] - o[u]), p[q.b][v] - o[v]};
        ok = ok && side(q.da, q.db, err) > 0;  // clearly turning forwards, by less than half a turn
        q.start = std::atan2(q.da[1], q.da[0]);
        q.width = std::atan2(cross2(q.da, q.db), q.da[0] * q.db[0] + q.da[1] * q.db[1]);
      }
      if (!ok) continue;
      // A repeated triangle covers the same sector twice: it is apart from the others as its
      // first copy is (the copies themselves share all three vertices and are not skipped).
      std::sort(sectors.begin(), sectors.end(),
                [](const Sector& x, const Sector& y) { return x.a != y.a ? x.a < y.a : x.b < y.b; });
      sectors.erase(std::unique(sectors.begin(), sectors.end(),
                                [](const Sector& x, const Sector& y) { return x.a == y.a && x.b == y.b; }),
                    sectors.end());
      std::sort(sectors.begin(), sectors.end(), [](const Sector& x, const Sector& y) { return x.start < y.start; });
      // Each sector must end where the next one starts (the same vertex) or clearly before it.
      double total = 0;
      for (size_t k = 0; k < sectors.size() && ok; ++k) {
        const Sector &x = sectors[k], &y = sectors[(k + 1) % sectors.size()];
        double gap = 0;
        if (x.b != y.a) {
          gap = y.start - x.start - x.width + (k + 1 == sectors.size() ? 2 * M_PI : 0.0);
          ok = side(x.db, y.da, err) > 0 || gap > 0.1;
        }
        total += x.width + gap;
      }
      // Round once: sorted sectors that overlap or wind twice sum to more.
      if (ok && std::fabs(total - 2 * M_PI) < 0.5) fan[c] = 1;
    }
  });
  return fan;
}

std::vector<uint8_t> closed_fan_vertices(const std::vector<Vec3>& points, const std::vector<Tri>& triangles,
                                         const VertexStars& stars) {
  std::vector<uint8_t> fan(points.size(), 0);
  tbb::parallel_for(tbb::blocked_range<size_t>(0, points.size(), 4096), [&](const tbb::blocked_range<size_t>& r) {
    std::vector<std::array<uint32_t, 2>> corners;
    for (size_t c = r.begin(); c != r.end(); ++c) {
      corners.clear();
      for (uint32_t t : stars[c]) {
        const Tri& tri = triangles[t];
        const int k = tri[0] == c ? 0 : tri[1] == c ? 1 : 2;
        corners.push_back({tri[(k + 1) % 3], tri[(k + 2) % 3]});
      }
      fan[c] = closed_fan_unfolded(points, uint32_t(c), corners.data(), corners.size());
    }
  });
  return fan;
}

}  // namespace vdbwrap::check::pair_search

namespace vdbwrap::check {

bool closed_fan_unfolded(const std::vector<Vec3>& points, uint32_t c, const std::array<uint32_t, 2>* corners,
                         size_t count) {
  constexpr size_t kMost = 64;
  if (count < 3 || count > kMost) return false;
  // Closed: each triangle's second corner is the first corner of exactly one triangle, and
  // the first corners differ (so the triangles link into cycles; the turn count below allows
  // only one).
  std::array<uint8_t, kMost> next;
  for (size_t i = 0; i < count; ++i) {
    size_t as_first = 0, as_second = 0;
    for (size_t j = 0; j < count; ++j) {
      as_first += corners[j][0] == corners[i][0];
      if (corners[j][0] == corners[i][1]) ++as_second, next[i] = uint8_t(j);
    }
    if (as_first != 1 || as_second != 1) return false;
  }
  const Vec3& o = points[c];
  Vec3 normal{0, 0, 0};
  for (size_t i = 0; i < count; ++i) normal = normal + cross(points[corners[i][0]] - o, points[corners[i][1]] - o);
  if (!(norm2(normal) > 0)) return false;
  // Any two independent axes across the normal give a linear map to the plane; the proof is
  // for that map, so they need not be exactly orthonormal.
  const Vec3 n = normalized(normal);
  const Vec3 least = std::fabs(n[0]) <= std::fabs(n[1]) && std::fabs(n[0]) <= std::fabs(n[2]) ? Vec3{1, 0, 0}
                     : std::fabs(n[1]) <= std::fabs(n[2])                                     ? Vec3{0, 1, 0}
                                                                                              : Vec3{0, 0, 1};
  const Vec3 e1 = normalized(cross(n, least)), e2 = cross(n, e1);
  // Each spoke projected once, so that a spoke two sectors share is the same numbers in both.
  std::array<std::array<double, 2>, kMost> ray;
  std::array<double, kMost> length2;
  for (size_t i = 0; i < count; ++i) {
    const Vec3 d = points[corners[i][0]] - o;
    ray[i] = {dot(e1, d), dot(e2, d)};
    length2[i] = norm2(d);
  }
  // Each sector must turn forwards by clearly more than the rounding (the differences to c
  // are exact to a relative epsilon, the projections to a few more): then its exact
  // projection turns forwards too, and each spoke's direction is off by under a millionth of
  // a radian, so the exact sectors wind as often as the computed ones. Winding: the sectors
  // that cross the first axis upwards (half-open on the computed numbers, so once each).
  int turns = 0;
  for (size_t i = 0; i < count; ++i) {
    const auto &ra = ray[i], &rb = ray[next[i]];
    const double turn = ra[0] * rb[1] - ra[1] * rb[0];
    if (!(turn > 0 && turn * turn > 1e-18 * length2[i] * length2[next[i]])) return false;
    turns += ra[1] <= 0 && rb[1] > 0;
  }
  return turns == 1;
}

}  // namespace vdbwrap::check
