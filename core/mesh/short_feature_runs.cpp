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

// Per segment (a, b) over `points`, whether it lies in a short run in a dense cell (see the
// header); `fold` (optional, per segment): a short run of folds only is noise however sparse.
std::vector<uint8_t> noise_runs(const std::vector<Vec3>& points, const std::vector<std::pair<uint32_t, uint32_t>>& segs,
                                double shortest, double corner_angle_deg, const std::vector<uint8_t>* fold = nullptr) {
  std::vector<uint8_t> noise_segment(segs.size(), 0);
  if (!(shortest > 0) || segs.empty()) return noise_segment;
  const double cos_corner = std::cos(corner_angle_deg * M_PI / 180.0);
  // The segments around each point, in increasing order.
  const CompressedLists around = compressed_lists(points.size(), [&](auto&& emit) {
    for (uint32_t i = 0; i < segs.size(); ++i) emit(segs[i].first, i), emit(segs[i].second, i);
  });
  auto far_end = [&](uint32_t s, uint32_t v) { return segs[s].first == v ? segs[s].second : segs[s].first; };
  // The runs: each segment's run number, and each run's length.
  std::vector<uint32_t> run_of(segs.size(), UINT32_MAX);
  std::vector<double> run_length;
  for (uint32_t first = 0; first < segs.size(); ++first) {
    if (run_of[first] != UINT32_MAX) continue;
    // Walk both ways from the segment.
    const uint32_t number = uint32_t(run_length.size());
    run_of[first] = number;
    double length = norm(points[segs[first].second] - points[segs[first].first]);
    for (uint32_t from : {segs[first].first, segs[first].second}) {
      uint32_t v = from, e = first;
      while (true) {
        // On through the straightest other segment at v, where it turns less than the corner
        // angle: a crease runs on past the noise edges that meet it (at a point of two
        // segments this is the other one; at a corner of a part none is straight).
        const Vec3 in = normalized(points[far_end(e, v)] - points[v]);
        uint32_t next = UINT32_MAX;
        double straightest = -cos_corner;
        for (uint32_t other : around[v]) {
          if (other == e) continue;
          const double turn = dot(in, normalized(points[far_end(other, v)] - points[v]));  // -1: straight on
          if (turn < straightest) straightest = turn, next = other;
        }
        if (next == UINT32_MAX || run_of[next] != UINT32_MAX) break;  // a turn, or a loop walked round
        run_of[next] = number;
        length += norm(points[segs[next].second] - points[segs[next].first]);
        v = far_end(next, v);
        e = next;
      }
    }
    run_length.push_back(length);
  }
  // The short runs' length per cell of 2 x `shortest`, in cell lengths, from
  // points every quarter cell along their segments. A rough surface has several per cell; a
  // small part's ends (a pin, a tooth, a bar's end) are short too, but few, beside long runs.
  const double inv_cell = 1 / (2 * shortest);
  std::unordered_map<GridKey, double, GridKeyHash> density;
  auto short_run = [&](size_t i) { return run_length[run_of[i]] < shortest; };
  for (size_t i = 0; i < segs.size(); ++i) {
    if (!short_run(i)) continue;
    const Vec3 &p = points[segs[i].first], &q = points[segs[i].second];
    const double length = norm(q - p);
    const int steps = std::max(1, int(std::ceil(4 * length * inv_cell)));
    for (int k = 0; k < steps; ++k)
      density[grid_key(p + (q - p) * ((k + 0.5) / steps), inv_cell)] += length / steps * inv_cell;
  }
  // A short run goes where the cell of its first segment's middle holds more than kDense.
  std::vector<uint8_t> noise(run_length.size(), 0), decided(run_length.size(), 0);
  std::vector<uint8_t> all_folds(run_length.size(), fold != nullptr);
  if (fold)
    for (size_t i = 0; i < segs.size(); ++i) all_folds[run_of[i]] &= (*fold)[i];
  for (size_t i = 0; i < segs.size(); ++i) {
    if (!short_run(i) || decided[run_of[i]]) continue;
    decided[run_of[i]] = 1;
    noise[run_of[i]] = all_folds[run_of[i]] ||
                       density[grid_key((points[segs[i].first] + points[segs[i].second]) * 0.5, inv_cell)] > kDense;
  }
  for (size_t i = 0; i < segs.size(); ++i) noise_segment[i] = noise[run_of[i]];
  return noise_segment;
}

}  // namespace

size_t drop_short_sharp_runs(const std::vector<Vec3>& points, std::vector<FeatureEdge>& edges, double shortest,
                             double corner_angle_deg) {
  std::vector<std::pair<uint32_t, uint32_t>> sharp;
  for (const FeatureEdge& e : edges)
    if (e.kind == FeatureKind::Sharp) sharp.emplace_back(e.a, e.b);
  const std::vector<uint8_t> noise = noise_runs(points, sharp, shortest, corner_angle_deg);
  size_t dropped = 0, kept = 0, k = 0;
  for (size_t i = 0; i < edges.size(); ++i) {
    if (edges[i].kind == FeatureKind::Sharp && noise[k++]) {
      ++dropped;
      continue;
    }
    edges[kept++] = edges[i];
  }
  edges.resize(kept);
  return dropped;
}

std::vector<uint8_t> short_line_runs(const std::vector<Vec3>& ends, double shortest, double corner_angle_deg,
                                     double weld, const std::vector<uint8_t>* fold) {
  // The ends as points, merged by position (the two triangles of a pair give a line's pieces
  // the same ends up to rounding).
  std::vector<Vec3> points;
  std::unordered_map<GridKey, uint32_t, GridKeyHash> at;
  const double inv = 1 / std::max(weld, 1e-300);
  auto point = [&](const Vec3& p) {
    auto [it, added] = at.emplace(grid_key(p, inv), uint32_t(points.size()));
    if (added) points.push_back(p);
    return it->second;
  };
  std::vector<std::pair<uint32_t, uint32_t>> segs;
  std::vector<uint32_t> seg_of;  // each line's segment, UINT32_MAX for a line shorter than the weld
  std::vector<uint8_t> seg_fold;
  for (size_t i = 0; i + 1 < ends.size(); i += 2) {
    const uint32_t a = point(ends[i]), b = point(ends[i + 1]);
    seg_of.push_back(a == b ? UINT32_MAX : uint32_t(segs.size()));
    if (a != b) segs.emplace_back(a, b), seg_fold.push_back(fold && (*fold)[i / 2]);
  }
  const std::vector<uint8_t> noise = noise_runs(points, segs, shortest, corner_angle_deg, fold ? &seg_fold : nullptr);
  std::vector<uint8_t> out(seg_of.size(), 0);
  for (size_t i = 0; i < seg_of.size(); ++i) out[i] = seg_of[i] != UINT32_MAX && noise[seg_of[i]];
  return out;
}

}  // namespace vdbwrap::mesh
