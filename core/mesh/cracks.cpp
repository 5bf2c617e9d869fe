#include "mesh/cracks.h"

#include <algorithm>
#include <cmath>
#include <utility>

#include <tbb/parallel_for.h>

#include "common/edge_key.h"
#include "common/union_find.h"
#include "common/vec.h"
#include "mesh/segment_grid.h"
#include "mesh/weld.h"

namespace vdbwrap::mesh {
namespace {

// Partners of a gap's side within this many times the nearest's distance, or a sixteenth of the
// width (the nearest may be a copy of the side itself), are as near.
constexpr double kAsNear = 4;

// A crease kept from one side moves at most this many times the crack's width to where the
// planes of its faces meet.
constexpr double kMostMeetMove = 4;
// ... and only between faces whose least height is this many times the crack's width.
constexpr double kPlaneHeight = 10;

// A face's doubt about its turn (degrees) counts from this much: less would only tip the
// creases that turn by the feature angle itself (a twelve-sided prism's edges) to one side, where
// a welded surface's test leaves them to its normals' last bits.
constexpr double kLeastDoubt = 1;

// Whether `beside(p)` holds at the middle of a-b, a quarter from each end and two widths from
// each end: a side overlapped but for its end (a panel's edge beside a window's, shorter) is
// the rim of an opening there.
template <typename Beside>
bool covered_along(const Vec3& a, const Vec3& b, double width, Beside&& beside) {
  const double inset = std::min(0.25, 2 * width / norm(b - a));
  for (double f : {0.5, 0.25, 0.75, inset, 1 - inset})
    if (!beside(lerp(a, b, f))) return false;
  return true;
}

// The index of the component largest in magnitude.
int largest_component(const Vec3& v) {
  int lead = 0;
  for (int c = 1; c < 3; ++c)
    if (std::abs(v[c]) > std::abs(v[lead])) lead = c;
  return lead;
}

}  // namespace

std::vector<CrackSide> crack_sides(const std::vector<Vec3>& points, const std::vector<Tri>& triangles,
                                   const std::vector<Vec3>& normals, const std::vector<FeatureEdge>& edges,
                                   double width, double cell, double angle_deg, double feature_angle_deg,
                                   bool nearest_partner, std::vector<CrackAcross>* across,
                                   const std::vector<CrackSide>* decided) {
  std::vector<CrackSide> crack(edges.size(), CrackSide::None);
  if (across) across->assign(edges.size(), CrackAcross{});
  if (!(width > 0) || !(cell > 0) || normals.size() != triangles.size()) return crack;
  // The one face of each boundary edge.
  std::vector<std::pair<uint64_t, uint32_t>> rim;  // (edge key, index into edges), sorted
  double total = 0;
  for (size_t i = 0; i < edges.size(); ++i)
    if (edges[i].kind == FeatureKind::Boundary) {
      rim.emplace_back(edge_key(edges[i].a, edges[i].b), uint32_t(i));
      total += norm(points[edges[i].b] - points[edges[i].a]);
    }
  if (rim.size() < 2) return crack;
  // A gap wider than a quarter of the faces' edges tilts the faces across it as much as a
  // crease (a soup of confetti: its rims go as small ones, its tilts as noise), and the search
  // would look at many edges per point.
  if (nearest_partner) width = std::min(width, total / double(rim.size()) / 4);
  std::sort(rim.begin(), rim.end());
  std::vector<uint32_t> face(edges.size(), UINT32_MAX);
  std::vector<uint8_t> forward(edges.size(), 0);  // the face runs the edge from a to b
  for (size_t t = 0; t < triangles.size(); ++t)
    for (int e = 0; e < 3; ++e) {
      const uint64_t key = edge_key(triangles[t][e], triangles[t][(e + 1) % 3]);
      const auto it = std::lower_bound(rim.begin(), rim.end(), std::make_pair(key, uint32_t(0)));
      if (it != rim.end() && it->first == key)
        face[it->second] = uint32_t(t), forward[it->second] = triangles[t][e] == edges[it->second].a;
    }
  // From edge i into its face, square to the edge.
  auto into_face = [&](uint32_t i) {
    const Tri& t = triangles[face[i]];
    const uint32_t c = t[0] != edges[i].a && t[0] != edges[i].b   ? t[0]
                       : t[1] != edges[i].a && t[1] != edges[i].b ? t[1]
                                                                  : t[2];
    const Vec3 &a = points[edges[i].a], dir = normalized(points[edges[i].b] - a), ac = points[c] - a;
    return ac - dir * dot(ac, dir);
  };
  // The normal of the face of `j` as it would be were it turned like the face of `i`: two faces
  // of one surface on either side of an edge run it opposite ways (on one side, one over the
  // other, the same way). The pieces of a soup are each turned outward on their own (a single
  // triangle by the side of its plane the origin is on), so two faces across a flat crack can
  // face opposite ways: no crease.
  auto facing_like = [&](uint32_t i, uint32_t j) {
    const Vec3 di = points[edges[i].b] - points[edges[i].a], dj = points[edges[j].b] - points[edges[j].a];
    const bool same_way = (dot(di, dj) > 0) == (forward[i] == forward[j]);
    const bool either_side = dot(into_face(i), into_face(j)) < 0;
    return same_way == either_side ? normals[face[j]] * -1.0 : normals[face[j]];
  };
  // Cells about as long as the edges: a soup's are many to a base cell.
  SegmentGrid grid(std::min(cell, 2 * total / double(rim.size())), width, total, rim.size());
  for (const auto& [key, i] : rim)
    if (face[i] != UINT32_MAX) grid.add(i, points[edges[i].a], points[edges[i].b]);
  // The surface's connected pieces: across a gap wider than a hairline, the other side is
  // another piece (a soup's triangle, a CAD face tessellated on its own); within a piece, edges
  // side by side are a jagged rim's zigzag.
  std::vector<uint32_t> piece(triangles.size(), 0);
  if (nearest_partner) {
    UnionFind joined(points.size());
    for (const Tri& t : triangles) joined.unite(t[0], t[1]), joined.unite(t[1], t[2]);
    for (size_t t = 0; t < triangles.size(); ++t) piece[t] = joined.find(triangles[t][0]);
  }
  const double parallel = std::cos(angle_deg * M_PI / 180), feature = feature_angle_deg * M_PI / 180;
  auto parallel_side_of = [&](uint32_t i, const Vec3& dir, uint32_t j) {
    const auto& s = grid.segment(j);
    return (!nearest_partner || piece[face[j]] != piece[face[i]]) &&
           std::abs(dot(dir, normalized(s[1] - s[0]))) >= parallel;
  };
  auto open_side = [&](uint32_t i) {
    return face[i] != UINT32_MAX && norm2(points[edges[i].b] - points[edges[i].a]) > 0 &&
           !(decided && (*decided)[i] != CrackSide::None);
  };
  // How far the corners of a hairline crack's faces may lie off: what nine in ten sides'
  // nearest parallel side at their middle stay within (a soup's rounding, an exporter's
  // tolerance).
  std::vector<double> nearest_at(nearest_partner ? 0 : rim.size(), INFINITY);
  if (!nearest_partner)
    tbb::parallel_for(tbb::blocked_range<size_t>(0, rim.size(), 256), [&](const tbb::blocked_range<size_t>& r) {
      for (size_t k = r.begin(); k != r.end(); ++k) {
        const uint32_t i = rim[k].second;
        if (!open_side(i)) continue;
        const Vec3 dir = normalized(points[edges[i].b] - points[edges[i].a]);
        grid.beside(lerp(points[edges[i].a], points[edges[i].b], 0.5), i, [&](uint32_t j, const Vec3& d) {
          if (parallel_side_of(i, dir, j)) nearest_at[k] = std::min(nearest_at[k], norm2(d));
          return false;
        });
      }
    });
  nearest_at.erase(std::remove(nearest_at.begin(), nearest_at.end(), INFINITY), nearest_at.end());
  double rounding = 0;
  if (!nearest_at.empty()) {
    const auto at = nearest_at.begin() + std::ptrdiff_t(nearest_at.size() * 9 / 10);
    std::nth_element(nearest_at.begin(), at, nearest_at.end());
    rounding = std::sqrt(*at);
  }
  // How far a face may turn about its edge `e` when its corners lie that far off: its far
  // corner and the edge each by the rounding, over its height above the edge (a needle's turn
  // about its long side is anyone's guess). Across a wider gap, none: the faces there are
  // tilted by the gap itself, and the sides kept hold the wrap to them (without them, a
  // gapped soup's wrap lies farther from the part).
  auto doubt = [&](uint32_t e) {
    if (nearest_partner) return 0.0;
    const Tri& t = triangles[face[e]];
    const double length = norm(points[edges[e].b] - points[edges[e].a]);
    const double height = norm(area_vector(points[t[0]], points[t[1]], points[t[2]])) / length;
    const double angle = std::atan2(2 * rounding, height);
    return angle >= kLeastDoubt * M_PI / 180 ? angle : 0.0;
  };
  // Whether the faces of `i` and of `j` turn from each other by more than the feature angle
  // and both faces' doubt.
  auto creased = [&](uint32_t i, uint32_t j) {
    const double turn = std::acos(std::clamp(dot(normals[face[i]], facing_like(i, j)), -1.0, 1.0));
    return turn > feature + doubt(i) + doubt(j);
  };
  tbb::parallel_for(tbb::blocked_range<size_t>(0, rim.size(), 256), [&](const tbb::blocked_range<size_t>& r) {
    std::vector<std::pair<double, uint32_t>> beside;  // (squared distance, edge) at an edge's middle
    for (size_t k = r.begin(); k != r.end(); ++k) {
      const uint32_t i = rim[k].second;
      const Vec3 &a = points[edges[i].a], &b = points[edges[i].b];
      if (!open_side(i)) continue;
      const Vec3 dir = normalized(b - a);
      auto parallel_side = [&](uint32_t j) { return parallel_side_of(i, dir, j); };
      // The other side, at the middle: a hairline crack's first parallel edge found; a gap's
      // nearest (a soup's neighbours of either side lie within a gap's width too: a row of a
      // fine tessellation beside a crease)... The crack's width is the nearest's distance.
      const Vec3 middle = lerp(a, b, 0.5);
      uint32_t other = UINT32_MAX;
      double nearest = INFINITY;
      beside.clear();
      grid.beside(middle, i, [&](uint32_t j, const Vec3& d) {
        if (!parallel_side(j)) return false;
        if (other == UINT32_MAX || (nearest_partner && norm2(d) < nearest)) other = j;
        nearest = std::min(nearest, norm2(d));
        if (nearest_partner) beside.emplace_back(norm2(d), j);
        return false;
      });
      if (other == UINT32_MAX) continue;
      // ... or, as near, the face across a crease: a face written twice lies as near as that.
      const double near = std::max(kAsNear * std::sqrt(nearest), width / 16);
      double gap2 = nearest, to_crease = INFINITY;
      for (const auto& [d2, j] : beside)
        if (d2 <= near * near && d2 < to_crease && creased(i, j)) to_crease = gap2 = d2, other = j;
      const bool covered = covered_along(a, b, width, [&](const Vec3& p) {
        // In a soup one edge of the other side covers all of this one: asked first.
        return grid.passes_beside(other, p) ||
               grid.beside(p, i, [&](uint32_t j, const Vec3&) { return parallel_side(j); });
      });
      if (!covered) continue;
      if (across) (*across)[i] = {face[i], face[other], std::sqrt(gap2)};
      if (!creased(i, other)) {
        crack[i] = CrackSide::Goes;
        continue;
      }
      // A crease: the side whose normal leads in the largest component of the two normals'
      // difference stays; all along the crack the same side, however its edges pair up. The
      // pair is turned so that the normals' sum leads positive: both sides then take the same
      // turn whichever way each face was given.
      const Vec3 other_normal = facing_like(i, other);
      const Vec3 sum = normals[face[i]] + other_normal;
      const Vec3 d = (normals[face[i]] - other_normal) * (sum[largest_component(sum)] < 0 ? -1.0 : 1.0);
      crack[i] = d[largest_component(d)] < 0 ? CrackSide::Goes : CrackSide::Crease;
    }
  });
  return crack;
}

std::vector<uint8_t> crossings_along_cracks(const std::vector<Vec3>& points, const std::vector<FeatureEdge>& edges,
                                            const std::vector<CrackSide>& side,
                                            const std::vector<std::array<Vec3, 2>>& lines, double width, double cell,
                                            double angle_deg) {
  std::vector<uint8_t> along(lines.size(), 0);
  if (!(width > 0) || !(cell > 0) || lines.empty()) return along;
  double total = 0;
  size_t count = 0;
  for (size_t i = 0; i < edges.size(); ++i)
    if (side[i] != CrackSide::None) total += norm(points[edges[i].b] - points[edges[i].a]), ++count;
  if (count == 0) return along;
  SegmentGrid grid(std::min(cell, 2 * total / double(count)), width, total, count);
  for (size_t i = 0; i < edges.size(); ++i)
    if (side[i] != CrackSide::None) grid.add(uint32_t(i), points[edges[i].a], points[edges[i].b]);
  const double parallel = std::cos(angle_deg * M_PI / 180);
  tbb::parallel_for(tbb::blocked_range<size_t>(0, lines.size(), 256), [&](const tbb::blocked_range<size_t>& r) {
    for (size_t k = r.begin(); k != r.end(); ++k) {
      const Vec3 &a = lines[k][0], &b = lines[k][1];
      if (!(norm2(b - a) > 0)) continue;
      const Vec3 dir = normalized(b - a);
      along[k] = covered_along(a, b, width, [&](const Vec3& p) {
        return grid.beside(p, UINT32_MAX, [&](uint32_t j, const Vec3&) {
          const auto& s = grid.segment(j);
          return std::abs(dot(dir, normalized(s[1] - s[0]))) >= parallel;
        });
      });
    }
  });
  return along;
}

bool crossing_at_shared_corner(const std::array<Vec3, 3>& a, const std::array<Vec3, 3>& b, const Vec3& from,
                               const Vec3& to, double width) {
  const double w2 = width * width;
  for (const Vec3& p : a)
    if (norm2(from - p) <= w2 && norm2(to - p) <= w2)
      for (const Vec3& q : b)
        if (norm2(q - p) <= w2 && q != p) return true;  // (at a corner they do share, a fold)
  return false;
}

void move_creases_to_plane_meet(std::vector<Vec3>& points, const std::vector<Tri>& triangles,
                                const std::vector<Vec3>& normals, const std::vector<CrackSide>& side,
                                const std::vector<CrackAcross>& across, double width, std::vector<FeatureEdge>& edges) {
  for (size_t i = 0; i < edges.size(); ++i) {
    if (side[i] != CrackSide::Crease || i >= across.size()) continue;
    const uint32_t f = across[i].face, g = across[i].other;
    if (f >= triangles.size() || g >= triangles.size()) continue;
    // A face whose corners may lie a gap off tells its plane only when it stands well clear
    // of its longest edge (a CAD fan's needles do not).
    auto plane_told = [&](uint32_t t) {
      const Vec3 &p = points[triangles[t][0]], &q = points[triangles[t][1]], &r = points[triangles[t][2]];
      const double longest = std::sqrt(std::max({norm2(q - p), norm2(r - q), norm2(p - r)}));
      return norm(area_vector(p, q, r)) >= kPlaneHeight * across[i].width * longest;
    };
    if (!plane_told(f) || !plane_told(g)) continue;
    const Vec3 &n = normals[f], &m = normals[g];
    const double c = dot(n, m), det = 1 - c * c;
    if (!(det > 1e-6)) continue;  // (parallel planes: no crease)
    const Vec3 &on_n = points[triangles[f][0]], &on_m = points[triangles[g][0]];
    // The point of both planes nearest p: p less a combination of the two normals.
    auto meet = [&](const Vec3& p) {
      const double rn = dot(n, p - on_n), rm = dot(m, p - on_m);
      const double l = (rn - c * rm) / det, k = (rm - c * rn) / det;
      return p - n * l - m * k;
    };
    // No farther than a few of the crack's widths: a gap across a crease of 30 degrees or more
    // moves an end at most twice its width; more is a face too small to tell its plane.
    const double most = std::min(width, kMostMeetMove * across[i].width);
    const Vec3 a = meet(points[edges[i].a]), b = meet(points[edges[i].b]);
    if (!(norm2(a - points[edges[i].a]) <= most * most && norm2(b - points[edges[i].b]) <= most * most)) continue;
    edges[i].a = uint32_t(points.size());
    points.push_back(a);
    edges[i].b = uint32_t(points.size());
    points.push_back(b);
  }
}

void join_crease_ends(const std::vector<Vec3>& points, const std::vector<CrackSide>& side, double width,
                      std::vector<FeatureEdge>& edges) {
  if (!(width > 0)) return;
  // The kept edges' ends in edge order, welded; each weld's first end stands for it.
  std::vector<uint32_t> ends;
  for (size_t i = 0; i < edges.size(); ++i)
    if (side[i] == CrackSide::Crease) ends.push_back(edges[i].a), ends.push_back(edges[i].b);
  std::vector<Vec3> at(ends.size()), welded;
  for (size_t k = 0; k < ends.size(); ++k) at[k] = points[ends[k]];
  const std::vector<uint32_t> weld = weld_points(at, width, welded);
  std::vector<uint32_t> first(welded.size(), UINT32_MAX);
  for (size_t k = 0; k < ends.size(); ++k)
    if (first[weld[k]] == UINT32_MAX) first[weld[k]] = ends[k];
  size_t k = 0;
  for (size_t i = 0; i < edges.size(); ++i)
    if (side[i] == CrackSide::Crease) edges[i].a = first[weld[k++]], edges[i].b = first[weld[k++]];
}

}  // namespace vdbwrap::mesh
