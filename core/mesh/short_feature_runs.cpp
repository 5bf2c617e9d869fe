#include "mesh/short_feature_runs.h"

#include <algorithm>
#include <cmath>
#include <cstdint>

#include <unordered_map>

#include "common/compressed_lists.h"
#include "common/grid_key.h"
#include "common/vec.h"

namespace vdbwrap::mesh {

namespace {
constexpr double kDense = 2;  // cell lengths of short runs per cell over which they are noise
}  // namespace

size_t drop_short_sharp_runs(const std::vector<Vec3>& points, std::vector<FeatureEdge>& edges, double shortest,
                             double corner_angle_deg) {
  if (!(shortest > 0)) return 0;
  const double cos_corner = std::cos(corner_angle_deg * M_PI / 180.0);
  // The sharp edges around each vertex, in increasing order.
  const CompressedLists around = compressed_lists(points.size(), [&](auto&& emit) {
    for (uint32_t i = 0; i < edges.size(); ++i)
      if (edges[i].kind == FeatureKind::Sharp) emit(edges[i].a, i), emit(edges[i].b, i);
  });
  if (around.items.size() == 0) return 0;
  // The runs: each sharp edge's run number, and each run's length.
  std::vector<uint32_t> run_of(edges.size(), UINT32_MAX);
  std::vector<double> run_length;
  for (uint32_t first = 0; first < edges.size(); ++first) {
    if (edges[first].kind != FeatureKind::Sharp || run_of[first] != UINT32_MAX) continue;
    // Walk both ways from the edge.
    const uint32_t number = uint32_t(run_length.size());
    run_of[first] = number;
    double length = norm(points[edges[first].b] - points[edges[first].a]);
    for (uint32_t from : {edges[first].a, edges[first].b}) {
      uint32_t v = from, e = first;
      while (true) {
        // On through the straightest other edge at v, where it turns less than the corner
        // angle: a crease runs on past the noise edges that meet it (at a vertex of two
        // sharp edges this is the other one; at a corner of a part none is straight).
        const uint32_t back = edges[e].a == v ? edges[e].b : edges[e].a;
        const Vec3 in = normalized(points[back] - points[v]);
        uint32_t next = UINT32_MAX;
        double straightest = -cos_corner;
        for (uint32_t other : around[v]) {
          if (other == e) continue;
          const uint32_t ahead = edges[other].a == v ? edges[other].b : edges[other].a;
          const double turn = dot(in, normalized(points[ahead] - points[v]));  // -1: straight on
          if (turn < straightest) straightest = turn, next = other;
        }
        if (next == UINT32_MAX || run_of[next] != UINT32_MAX) break;  // a turn, or a loop walked round
        run_of[next] = number;
        length += norm(points[edges[next].b] - points[edges[next].a]);
        v = edges[next].a == v ? edges[next].b : edges[next].a;
        e = next;
      }
    }
    run_length.push_back(length);
  }
  // The short runs' length per cell of 2 x `shortest`, in cell lengths, from
  // points every quarter cell along their edges. A rough surface has several per cell; a
  // small part's ends (a pin, a tooth, a bar's end) are short too, but few, beside long runs.
  const double inv_cell = 1 / (2 * shortest);
  std::unordered_map<GridKey, double, GridKeyHash> density;
  auto short_run = [&](size_t i) { return run_of[i] != UINT32_MAX && run_length[run_of[i]] < shortest; };
  for (size_t i = 0; i < edges.size(); ++i) {
    if (!short_run(i)) continue;
    const Vec3 &p = points[edges[i].a], &q = points[edges[i].b];
    const double length = norm(q - p);
    const int steps = std::max(1, int(std::ceil(4 * length * inv_cell)));
    for (int k = 0; k < steps; ++k)
      density[grid_key(p + (q - p) * ((k + 0.5) / steps), inv_cell)] += length / steps * inv_cell;
  }
  // A short run goes where the cell of its first edge's middle holds more than kDense.
  std::vector<uint8_t> noise(run_length.size(), 0), decided(run_length.size(), 0);
  for (size_t i = 0; i < edges.size(); ++i) {
    if (!short_run(i) || decided[run_of[i]]) continue;
    decided[run_of[i]] = 1;
    noise[run_of[i]] = density[grid_key((points[edges[i].a] + points[edges[i].b]) * 0.5, inv_cell)] > kDense;
  }
  size_t dropped = 0, kept = 0;
  for (size_t i = 0; i < edges.size(); ++i) {
    if (run_of[i] != UINT32_MAX && noise[run_of[i]]) {
      ++dropped;
      continue;
    }
    edges[kept++] = edges[i];
  }
  edges.resize(kept);
  return dropped;
}

}  // namespace vdbwrap::mesh
