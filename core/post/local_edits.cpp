#include "post/local_edits.h"

#include <algorithm>
#include <cmath>
#include <iterator>
#include <unordered_set>

#include "common/closest_point.h"
#include "common/float_round.h"
#include "common/vec.h"

namespace vdbwrap::post {
namespace {

// Three mean edges: most triangles fall in one or two buckets.
double bucket_cell(const PostSurface& s) {
  double sum = 0;
  size_t n = 0;
  for (size_t f = 0; f < s.triangles.size(); f += 7, ++n)
    sum += norm(s.points[s.triangles[f][1]] - s.points[s.triangles[f][0]]);
  return n && sum > 0 ? 3 * sum / double(n) : 1.0;
}

}  // namespace

LocalEdits::LocalEdits(PostSurface& s, const QualityReference& ref, const LocalEditBounds& bounds)
    : s_(s), ref_(ref), bounds_(bounds), buckets_(s.points, s.triangles, bucket_cell(s)) {
  s_.locked.resize(s_.points.size(), 0);
  s_.cell_size.resize(s_.points.size(), 0);
  alive_.assign(s_.triangles.size(), 1);
  touched_.assign(s_.points.size(), -2);
  vt_.resize(s_.points.size());
  for (uint32_t f = 0; f < s_.triangles.size(); ++f)
    for (uint32_t v : s_.triangles[f]) vt_[v].push_back(f);
  feature_.resize(s_.points.size());
  for (const auto& [a, b] : s_.feature_edges) {
    if (a == b || a >= feature_.size() || b >= feature_.size() || !is_edge(a, b)) continue;
    if (std::find(feature_[a].begin(), feature_[a].end(), b) == feature_[a].end())
      feature_[a].push_back(b), feature_[b].push_back(a);
  }
  samples_ = CellLists<>(bucket_cell(s_));
  for (uint32_t i = 0; i < ref_.feature_samples.size(); ++i) samples_.add(ref_.feature_samples[i] + ref_.origin, i);
}

bool LocalEdits::feature_edge(uint32_t a, uint32_t b) const {
  return std::find(feature_[a].begin(), feature_[a].end(), b) != feature_[a].end();
}

bool LocalEdits::is_edge(uint32_t a, uint32_t b) const {
  for (uint32_t f : vt_[a]) {
    const Tri& t = s_.triangles[f];
    if (t[0] == b || t[1] == b || t[2] == b) return true;
  }
  return false;
}

void LocalEdits::neighbours(uint32_t v, std::vector<uint32_t>& out) const {
  out.clear();
  for (uint32_t f : vt_[v])
    for (uint32_t w : s_.triangles[f])
      if (w != v) out.push_back(w);
  std::sort(out.begin(), out.end());
  out.erase(std::unique(out.begin(), out.end()), out.end());
}

bool LocalEdits::edge_triangles(uint32_t a, uint32_t b, uint32_t& ab, uint32_t& ba) const {
  ab = ba = kNone;
  int count = 0;
  for (uint32_t f : vt_[a]) {
    const Tri& t = s_.triangles[f];
    for (int i = 0; i < 3; ++i) {
      if (t[i] == a && t[(i + 1) % 3] == b) ab = f, ++count;
      if (t[i] == b && t[(i + 1) % 3] == a) ba = f, ++count;
    }
  }
  return count == 2 && ab != kNone && ba != kNone;
}

uint32_t LocalEdits::third(const Tri& t, uint32_t a, uint32_t b) {
  for (uint32_t v : t)
    if (v != a && v != b) return v;
  return kNone;
}

double LocalEdits::min_angle(uint32_t f) const {
  const Tri& t = s_.triangles[f];
  return min_angle_deg(s_.points[t[0]], s_.points[t[1]], s_.points[t[2]]);
}

Vec3 LocalEdits::stored(const Vec3& x) const { return bounds_.float_coordinates ? round_to_float(x) : x; }

Vec3 LocalEdits::onto_input(const Vec3& q, double cell) const {
  decltype(ref_.closest(q)) hit;  // the index's Hit
  if (!ref_.closest_within(q - ref_.origin, 0.5 * cell, hit)) return stored(q);
  const Vec3 foot = hit.point + ref_.origin;
  const double d = norm(q - foot);
  return stored(d > 1e-9 * cell ? foot + (q - foot) * (std::min(bounds_.offset, d) / d) : foot);
}

Vec3 LocalEdits::onto_input_anywhere(const Vec3& q) const {
  const Vec3 foot = ref_.closest(q - ref_.origin).point + ref_.origin;
  const double d = norm(q - foot);
  return stored(d > 0 ? foot + (q - foot) * (std::min(bounds_.offset, d) / d) : foot);
}

double LocalEdits::distance_to_input(const Vec3& q) const {
  return std::sqrt(ref_.closest(q - ref_.origin).squared_distance);
}

void LocalEdits::sample(const Vec3& a, const Vec3& b, const Vec3& c, Spread& s) const {
  const double quarter = 0.25 * norm(area_vector(a, b, c));
  for (const Vec3& q : {(a + b + c) * (1.0 / 3.0), (a + b) * 0.5, (b + c) * 0.5, (c + a) * 0.5}) {
    const double d = distance_to_input(q);
    s.worst = std::max(s.worst, d), s.sum += quarter * d, s.area += quarter, s.plain_sum += d, ++s.n;
  }
}

void LocalEdits::sample_grid(const Vec3& a, const Vec3& b, const Vec3& c, Spread& s) const {
  const double tenth = 0.05 * norm(area_vector(a, b, c));
  for (int i = 0; i <= 3; ++i)
    for (int j = 0; i + j <= 3; ++j) {
      const double d = distance_to_input((a * double(i) + b * double(j) + c * double(3 - i - j)) * (1.0 / 3.0));
      s.worst = std::max(s.worst, d), s.sum += tenth * d, s.area += tenth, s.plain_sum += d, ++s.n;
    }
}

// Each sample within reach of the old triangles is as near the new ones.
bool LocalEdits::keeps_sharp_edges(const Change& c, const std::vector<check::Corners>& made_at,
                                   double tolerance) const {
  if (samples_.empty()) return true;
  if (tolerance < 0) tolerance = bounds_.feature_tolerance;
  Box3 box;
  for (uint32_t f : c.slots)
    if (f != Change::kNoSlot)
      for (uint32_t v : s_.triangles[f]) box.add(s_.points[v]);
  const double reach = 4 * tolerance;
  const Vec3 r{reach, reach, reach};
  const bool lost = samples_.for_lists(
      samples_.cell_of(box.lo - r), samples_.cell_of(box.hi + r), [&](const std::vector<uint32_t>& list) {
        for (uint32_t i : list) {
          const Vec3 q = ref_.feature_samples[i] + ref_.origin;
          if (box.squared_distance(q) > reach * reach) continue;
          double before = INFINITY, after = INFINITY;
          for (uint32_t f : c.slots) {
            if (f == Change::kNoSlot) continue;
            const Tri& o = s_.triangles[f];
            before =
                std::min(before, norm2(q - closest_on_triangle(q, s_.points[o[0]], s_.points[o[1]], s_.points[o[2]])));
          }
          before = std::sqrt(before);
          if (before > reach) continue;  // held by other triangles, or out of reach
          for (const auto& at : made_at)
            after = std::min(after, norm2(q - closest_on_triangle(q, at[0], at[1], at[2])));
          if (std::sqrt(after) > std::max(before, tolerance)) return true;
        }
        return false;
      });
  return !lost;
}

const char* LocalEdits::breaks_surface(const Change& c, const std::vector<Tri>& made,
                                       const std::vector<check::Corners>& made_at) {
  for (size_t i = 0; i < made.size(); ++i)
    for (size_t j = i + 1; j < made.size(); ++j)
      if (check::triangle_pair_intersects(made_at[i], made[i], made_at[j], made[j])) return "folds";
  std::unordered_set<uint32_t> replaced;
  for (uint32_t f : c.slots)
    if (f != Change::kNoSlot) replaced.insert(f);
  for (size_t i = 0; i < made.size(); ++i) {
    Box3 box;
    for (const Vec3& p : made_at[i]) box.add(p);
    bool hit = false;
    buckets_.for_each_in_box(box, [&](uint32_t g) {
      if (hit || !alive_[g] || replaced.count(g)) return;
      const Tri& o = s_.triangles[g];
      const check::Corners og = {s_.points[o[0]], s_.points[o[1]], s_.points[o[2]]};
      hit = check::triangle_pair_intersects(made_at[i], made[i], og, o);
    });
    if (hit) return "intersects";
  }
  return nullptr;
}

bool LocalEdits::propose_split(uint32_t a, uint32_t b, const Vec3& x) {
  uint32_t ab, ba;
  if (!edge_triangles(a, b, ab, ba)) return false;
  const uint32_t c = third(s_.triangles[ab], a, b), d = third(s_.triangles[ba], a, b);
  if (c == d) return false;
  const uint32_t m = uint32_t(s_.points.size());
  change_.clear();
  change_.added = m;
  change_.added_at = x;
  change_.added_cell = std::min(s_.cell_size[a], s_.cell_size[b]);
  change_.add(ab, Tri{a, m, c});
  change_.add(ba, Tri{b, m, d});
  change_.add(Change::kNoSlot, Tri{m, b, c});
  change_.add(Change::kNoSlot, Tri{m, a, d});
  return true;
}

const char* LocalEdits::collapse_blocked(uint32_t u, uint32_t v) const {
  uint32_t f1, f2;
  if (!edge_triangles(u, v, f1, f2)) return "";
  const uint32_t c = third(s_.triangles[f1], u, v), d = third(s_.triangles[f2], u, v);
  // Link condition: u and v share exactly the two neighbours across the edge.
  std::vector<uint32_t> nu, nv, common;
  neighbours(u, nu), neighbours(v, nv);
  std::set_intersection(nu.begin(), nu.end(), nv.begin(), nv.end(), std::back_inserter(common));
  if (common.size() != 2 || c == d) return "link";
  // c and d each lose an edge: keep them at three or more.
  std::vector<uint32_t> nc, nd;
  neighbours(c, nc), neighbours(d, nd);
  if (nc.size() < 4 || nd.size() < 4) return "valence";
  return nullptr;
}

void LocalEdits::propose_collapse(uint32_t u, uint32_t v, const Vec3& x) {
  uint32_t f1, f2;
  edge_triangles(u, v, f1, f2);
  change_.clear();
  change_.moved = u;
  change_.to = x;
  for (uint32_t g : vt_[u]) change_.add(g, s_.triangles[g], g == f1 || g == f2);
  for (uint32_t g : vt_[v]) {
    if (g == f1 || g == f2) continue;
    Tri t = s_.triangles[g];
    for (uint32_t& w : t)
      if (w == v) w = u;
    change_.add(g, t);
  }
}

void LocalEdits::hand_over(uint32_t u, uint32_t v) {
  vt_[v].clear();
  for (uint32_t w : feature_[v]) {
    auto& list = feature_[w];
    list.erase(std::remove(list.begin(), list.end(), v), list.end());
    if (w != u && !feature_edge(u, w)) feature_[u].push_back(w), list.push_back(u);
  }
  feature_[v].clear();
}

void LocalEdits::apply(const Change& c) {
  if (c.moved != kNone) s_.points[c.moved] = c.to;
  if (c.added != kNone) {
    s_.points.push_back(c.added_at);
    s_.cell_size.push_back(c.added_cell), s_.locked.push_back(0);
    touched_.push_back(round_), vt_.emplace_back(), feature_.emplace_back();
  }
  for (size_t i = 0; i < c.slots.size(); ++i)
    if (c.slots[i] != Change::kNoSlot)
      for (uint32_t v : s_.triangles[c.slots[i]]) touched_[v] = round_;
  for (size_t i = 0; i < c.slots.size(); ++i) {
    if (c.slots[i] == Change::kNoSlot) {
      const uint32_t f = uint32_t(s_.triangles.size());
      s_.triangles.push_back(c.tris[i]);
      alive_.push_back(1);
      for (uint32_t v : c.tris[i]) vt_[v].push_back(f), touched_[v] = round_;
      buckets_.update(f);
      continue;
    }
    const uint32_t f = c.slots[i];
    for (uint32_t v : s_.triangles[f]) {
      auto& list = vt_[v];
      list.erase(std::remove(list.begin(), list.end(), f), list.end());
    }
    if (c.dies[i]) {
      alive_[f] = 0;
      continue;
    }
    s_.triangles[f] = c.tris[i];
    for (uint32_t v : c.tris[i]) vt_[v].push_back(f);
    buckets_.move(f, true);
  }
}

bool LocalEdits::changed_near(uint32_t v) const {
  if (touched_[v] + 1 >= round_) return true;
  for (uint32_t f : vt_[v])
    for (uint32_t w : s_.triangles[f])
      if (touched_[w] + 1 >= round_) return true;
  return false;
}

void LocalEdits::compact() {
  std::vector<uint32_t> remap;
  PostSurface out = live_part(s_, alive_, remap);
  for (uint32_t a = 0; a < feature_.size(); ++a)
    for (uint32_t b : feature_[a])
      if (a < b && remap[a] != kNone && remap[b] != kNone) out.feature_edges.push_back({remap[a], remap[b]});
  s_ = std::move(out);
}

}  // namespace vdbwrap::post
