#include "post/quality.h"

#include <tbb/parallel_for.h>
#include <tbb/parallel_sort.h>

#include <algorithm>
#include <cmath>

#include "check/intersections.h"
#include "common/edge_key.h"
#include "common/in_background.h"
#include "common/vec.h"

namespace vdbwrap::post {
namespace {

constexpr double kDeg = 180.0 / M_PI;

double angle_deg(const Vec3& u, const Vec3& w) { return std::atan2(norm(cross(u, w)), dot(u, w)) * kDeg; }

// Angle between the triangle's normal and the input's at q (local frame), orientation ignored;
// negative when the input is farther than `reach`. The input's normal at the foot point is the
// direction from it to q: the face's normal inside a face, and at an edge or a corner the one
// of its normal cone that points at q (the wrap over a rim is not "perpendicular" to the wall
// below the rim).
double deviation_at(const Vec3& q, const Vec3& unit_normal, double reach, const QualityReference& ref) {
  mesh::SurfaceIndex::Hit hit;
  if (!ref.closest_within(q, reach, hit)) return -1;
  const double d = std::sqrt(hit.squared_distance);
  const Vec3 n = d > 1e-6 * reach ? (q - hit.point) * (1.0 / d) : hit.normal;
  if (norm2(n) == 0) return -1;
  const double c = std::min(1.0, std::fabs(dot(unit_normal, n)));
  return std::acos(c) * kDeg;
}

}  // namespace

std::vector<Vec3> sample_sharp_edges(const prep::PreparedInput& input, double spacing, size_t max_samples) {
  std::vector<Vec3> out;
  if (!(spacing > 0)) return out;
  double length = 0;
  for (const auto& e : input.feature_edges)
    if (e.kind == prep::FeatureKind::Sharp) length += norm(input.mesh.points[e.b] - input.mesh.points[e.a]);
  spacing = std::max(spacing, length / double(std::max<size_t>(1, max_samples)));
  for (const auto& e : input.feature_edges) {
    if (e.kind != prep::FeatureKind::Sharp) continue;
    const Vec3 &a = input.mesh.points[e.a], &b = input.mesh.points[e.b];
    const size_t k = std::max<size_t>(1, size_t(std::ceil(norm(b - a) / spacing)));
    // Each edge's own points, its start included; shared corners come twice, which is harmless.
    for (size_t i = 0; i <= k; ++i) out.push_back(lerp(a, b, double(i) / double(k)));
  }
  return out;
}

double min_angle_deg(const Vec3& a, const Vec3& b, const Vec3& c) {
  if (norm2(b - a) == 0 || norm2(c - b) == 0 || norm2(a - c) == 0) return 0;
  return std::min({angle_deg(b - a, c - a), angle_deg(c - b, a - b), angle_deg(a - c, b - c)});
}

uint8_t shape_flags(const Vec3& a, const Vec3& b, const Vec3& c, double cell, const QualityThresholds& t) {
  uint8_t f = 0;
  if (0.5 * norm(area_vector(a, b, c)) < t.small_area * cell * cell) f |= kSmallArea;
  if (min_angle_deg(a, b, c) < t.sliver_angle_deg) f |= kSliver;
  return f;
}

double normal_deviation_deg(const Vec3& a, const Vec3& b, const Vec3& c, double cell, const QualityReference& ref) {
  const Vec3 n = normalized(area_vector(a, b, c));
  if (norm2(n) == 0) return -1;
  const double reach = ref.thresholds.near_input * cell;
  const Vec3 centre = (a + b + c) * (1.0 / 3.0) - ref.origin;
  double best = deviation_at(centre, n, reach, ref);
  if (best >= 0 && best <= ref.thresholds.normal_deviation_deg) return best;
  // A triangle on a face whose centroid lies nearer another face (a concave corner) is fine
  // when any of its inner points finds its own face.
  for (const Vec3* v : {&a, &b, &c}) {
    const double d = deviation_at((centre + (*v - ref.origin)) * 0.5, n, reach, ref);
    if (d >= 0 && (best < 0 || d < best)) best = d;
  }
  return best;
}

NormalDeviationMemo::Key NormalDeviationMemo::key(const Vec3& a, const Vec3& b, const Vec3& c, double cell) {
  return bitwise_key<10>({a[0], a[1], a[2], b[0], b[1], b[2], c[0], c[1], c[2], cell});
}

bool NormalDeviationMemo::find(const Vec3& a, const Vec3& b, const Vec3& c, double cell, double& deviation) const {
  const auto it = known_.find(key(a, b, c, cell));
  if (it == known_.end()) return false;
  deviation = it->second;
  return true;
}

void NormalDeviationMemo::add(const Vec3& a, const Vec3& b, const Vec3& c, double cell, double deviation) {
  known_.emplace(key(a, b, c, cell), deviation);
}

QualityCounts analyse_quality(const std::vector<Vec3>& p, const std::vector<Tri>& tris,
                              const std::vector<double>& cell_size, const QualityReference& ref,
                              std::vector<uint8_t>* flags_out, const std::vector<uint32_t>* intersecting,
                              NormalDeviationMemo* memo) {
  const QualityThresholds& t = ref.thresholds;
  QualityCounts q;
  q.triangles = tris.size();
  std::vector<uint8_t> flags(tris.size(), 0);

  // Lost features: sharp-edge samples of the input farther from the surface than the
  // tolerance, within reach of the wrap; the surface triangle nearest each is flagged (below).
  // Measured beside the rest: building the surface's index is partly serial.
  q.feature_samples = ref.feature_samples.size();
  struct SampleStates {
    std::vector<int8_t> state;  // 1 lost, 2 out of reach
    std::vector<uint32_t> nearest;
  };
  InBackground<SampleStates> samples([&] {
    SampleStates out;
    if (ref.feature_samples.empty() || tris.empty()) return out;
    out.state.assign(ref.feature_samples.size(), 0);
    out.nearest.assign(ref.feature_samples.size(), 0);
    mesh::SurfaceIndex surface(p, tris);
    const double tolerance = t.feature_tolerance * ref.finest_size;
    tbb::parallel_for(tbb::blocked_range<size_t>(0, ref.feature_samples.size(), 1024),
                      [&](const tbb::blocked_range<size_t>& r) {
                        for (size_t i = r.begin(); i != r.end(); ++i) {
                          auto hit = surface.closest(ref.feature_samples[i] + ref.origin);
                          const double d = std::sqrt(hit.squared_distance);
                          if (d <= tolerance) continue;
                          const Tri& tri = tris[hit.triangle];
                          const double cell = std::max({cell_size[tri[0]], cell_size[tri[1]], cell_size[tri[2]]});
                          out.state[i] = d > t.feature_reach * cell ? 2 : 1;
                          out.nearest[i] = hit.triangle;
                        }
                      });
    return out;
  });

  // Intersecting and degenerate triangles.
  std::vector<uint32_t> crossing;
  if (intersecting) {
    crossing = *intersecting;
  } else {
    crossing = check::intersecting_triangles(p, tris, check::SoupKind::kWrap);
  }
  for (uint32_t f : crossing)
    if (f < flags.size()) flags[f] |= kSelfIntersecting;

  // Shape, edges and normals, per triangle.
  std::vector<double> min_angle(tris.size(), 180), deviation(tris.size(), -1);
  std::vector<uint8_t> measured(tris.size(), 0);  // asked of the input here (not known to the memo)
  tbb::parallel_for(tbb::blocked_range<size_t>(0, tris.size(), 512), [&](const tbb::blocked_range<size_t>& r) {
    for (size_t f = r.begin(); f != r.end(); ++f) {
      const Tri& tri = tris[f];
      const Vec3 &a = p[tri[0]], &b = p[tri[1]], &c = p[tri[2]];
      const double cell = std::min({cell_size[tri[0]], cell_size[tri[1]], cell_size[tri[2]]});
      flags[f] |= shape_flags(a, b, c, cell, t);
      min_angle[f] = min_angle_deg(a, b, c);
      for (int k = 0; k < 3; ++k) {
        const uint32_t u = tri[k], v = tri[(k + 1) % 3];
        const double len = norm(p[v] - p[u]);
        if (len < t.short_edge * std::min(cell_size[u], cell_size[v])) flags[f] |= kShortEdge;
        if (len > t.long_edge * std::max(cell_size[u], cell_size[v])) flags[f] |= kLongEdge;
      }
      if (ref.input) {
        if (!memo || !memo->find(a, b, c, cell, deviation[f]))
          deviation[f] = normal_deviation_deg(a, b, c, cell, ref), measured[f] = 1;
        if (deviation[f] > t.normal_deviation_deg) flags[f] |= kNormalDeviation;
      }
    }
  });

  if (memo && ref.input) {  // only what it did not know: the final analysis adds the few changed triangles
    for (uint32_t f = 0; f < tris.size(); ++f) {
      if (!measured[f]) continue;
      const Tri& tri = tris[f];
      const double cell = std::min({cell_size[tri[0]], cell_size[tri[1]], cell_size[tri[2]]});
      memo->add(p[tri[0]], p[tri[1]], p[tri[2]], cell, deviation[f]);
    }
  }

  // Edges are counted once each (an edge defect flags both its triangles). Listed and sorted
  // in parallel: serially this was a visible share of each analysis on big wraps.
  std::vector<std::pair<uint64_t, uint8_t>> edges(tris.size() * 3);
  tbb::parallel_for(tbb::blocked_range<size_t>(0, tris.size(), 4096), [&](const tbb::blocked_range<size_t>& r) {
    for (size_t f = r.begin(); f != r.end(); ++f)
      for (int k = 0; k < 3; ++k) {
        const uint32_t u = tris[f][k], v = tris[f][(k + 1) % 3];
        const double len = norm(p[v] - p[u]);
        uint8_t e = 0;
        if (len < t.short_edge * std::min(cell_size[u], cell_size[v])) e |= kShortEdge;
        if (len > t.long_edge * std::max(cell_size[u], cell_size[v])) e |= kLongEdge;
        edges[3 * f + size_t(k)] = {edge_key(u, v), e};
      }
  });
  tbb::parallel_sort(edges.begin(), edges.end());
  edges.erase(std::unique(edges.begin(), edges.end(), [](const auto& x, const auto& y) { return x.first == y.first; }),
              edges.end());
  q.edges = edges.size();
  for (const auto& [key, e] : edges) {
    q.short_edges += (e & kShortEdge) ? 1 : 0;
    q.long_edges += (e & kLongEdge) ? 1 : 0;
  }

  const SampleStates& lost = samples.get();
  for (size_t i = 0; i < lost.state.size(); ++i) {
    if (lost.state[i] == 1) ++q.lost_feature_samples, flags[lost.nearest[i]] |= kLostFeature;
    if (lost.state[i] == 2) ++q.unreachable_feature_samples;
  }

  q.min_angle_deg = tris.empty() ? 0 : 180;
  for (uint32_t f = 0; f < tris.size(); ++f) {
    const uint8_t x = flags[f];
    q.self_intersecting += (x & kSelfIntersecting) ? 1 : 0;
    q.small_area += (x & kSmallArea) ? 1 : 0;
    q.slivers += (x & kSliver) ? 1 : 0;
    q.normal_deviation += (x & kNormalDeviation) ? 1 : 0;
    q.min_angle_deg = std::min(q.min_angle_deg, min_angle[f]);
    q.max_normal_deviation_deg = std::max(q.max_normal_deviation_deg, deviation[f]);
  }
  if (flags_out) *flags_out = std::move(flags);
  return q;
}

}  // namespace vdbwrap::post
