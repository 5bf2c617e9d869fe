#include "post/coarsen.h"

#include <algorithm>
#include <cmath>
#include <queue>

#include "check/intersections.h"
#include "common/triangle_buckets.h"
#include "common/vec.h"
#include "vdbwrap/errors.h"

namespace vdbwrap::post {
namespace {

double min_angle_cos_max(const Vec3& a, const Vec3& b, const Vec3& c) {
  // The largest cosine among the three angles (the smallest angle's cosine).
  auto cosine = [](const Vec3& o, const Vec3& p, const Vec3& q) {
    Vec3 u = p - o, w = q - o;
    double d = std::sqrt(norm2(u) * norm2(w));
    return d > 0 ? dot(u, w) / d : 1.0;
  };
  return std::max({cosine(a, b, c), cosine(b, c, a), cosine(c, a, b)});
}

class Coarsener {
 public:
  Coarsener(std::vector<Vec3>& p, std::vector<Tri>& t, const std::vector<uint8_t>& locked, const fit::SurfaceIndex& input,
            const Vec3& origin, const CoarsenParams& params)
      : p_(p), t_(t), locked_(locked), input_(input), origin_(origin), prm_(params),
        buckets_(p, t, std::max(params.max_edge, 1e-300)) {
    alive_.assign(t.size(), 1);
    vertex_alive_.assign(p.size(), 1);
    stamp_.assign(p.size(), 0);
    vf_.resize(p.size());
    for (uint32_t f = 0; f < t.size(); ++f)
      for (uint32_t v : t[f]) vf_[v].push_back(f);
    cos_turn_ = std::cos(prm_.max_normal_turn_deg * M_PI / 180.0);
    cos_min_angle_ = std::cos(prm_.min_angle_deg * M_PI / 180.0);
    dev2_ = prm_.max_deviation * prm_.max_deviation;
    for (uint32_t f = 0; f < t.size(); ++f)
      for (int e = 0; e < 3; ++e) {
        uint32_t a = t[f][e], b = t[f][(e + 1) % 3];
        if (a < b) push(a, b);
      }
  }

  // Passes over every edge, shortest first, until one pass changes nothing (or a few).
  size_t run(ProgressSink* progress) {
    size_t total = 0;
    for (int pass = 0; pass < 4; ++pass) {
      if (pass > 0)
        for (uint32_t f = 0; f < t_.size(); ++f)
          if (alive_[f])
            for (int e = 0; e < 3; ++e) {
              uint32_t a = t_[f][e], b = t_[f][(e + 1) % 3];
              if (a < b) push(a, b);
            }
      size_t n = one_pass(progress);
      total += n;
      if (n < 16) break;
    }
    return total;
  }

  size_t one_pass(ProgressSink* progress) {
    size_t collapses = 0, popped = 0;
    while (!queue_.empty()) {
      Entry e = queue_.top();
      queue_.pop();
      if (progress && (++popped & 0x3FFF) == 0 && progress->cancelled()) throw Error(ErrorKind::Cancelled, "cancelled");
      if (!vertex_alive_[e.a] || !vertex_alive_[e.b] || stamp_[e.a] != e.sa || stamp_[e.b] != e.sb) continue;
      bool done = (removable(e.a, e.b) && collapse(e.a, e.b)) || (removable(e.b, e.a) && collapse(e.b, e.a));
      if (done) ++collapses;
    }
    return collapses;
  }

 private:
  struct Entry {
    double length2;
    uint32_t a, b, sa, sb;
    bool operator<(const Entry& o) const { return length2 > o.length2; }  // shortest first
  };
  void push(uint32_t a, uint32_t b) {
    double l2 = norm2(p_[a] - p_[b]);
    if (l2 <= prm_.max_edge * prm_.max_edge) queue_.push({l2, a, b, stamp_[a], stamp_[b]});
  }
  // A free node may always go. A node on a feature curve may go only into a neighbour on the
  // same straight run of the curve: it has exactly two feature neighbours, v and one more, and
  // the chain through it is nearly straight, so the chain keeps following the curve.
  bool removable(uint32_t u, uint32_t v) const {
    if (!locked_[u]) return true;
    if (!locked_[v]) return false;
    std::vector<uint32_t> chain;
    for (uint32_t w : neighbours(u))
      if (locked_[w]) chain.push_back(w);
    if (chain.size() != 2) return false;
    const uint32_t w = chain[0] == v ? chain[1] : chain[0];
    const Vec3 a = normalized(p_[v] - p_[u]), b = normalized(p_[w] - p_[u]);
    return dot(a, b) < -std::cos(prm_.max_chain_turn_deg * M_PI / 180.0);
  }

  bool near_input(const Vec3& q) const { return input_.within(q - origin_, prm_.max_deviation); }

  // Merges u into v when every check passes.
  bool collapse(uint32_t u, uint32_t v) {
    // The two faces on edge u-v, and the link condition: u and v share exactly their two
    // opposite vertices as neighbours (else the collapse pinches the surface).
    std::vector<uint32_t> shared, moved;
    for (uint32_t f : vf_[u]) {
      const Tri& tri = t_[f];
      (tri[0] == v || tri[1] == v || tri[2] == v ? shared : moved).push_back(f);
    }
    if (shared.size() != 2) return false;
    std::vector<uint32_t> nu = neighbours(u), nv = neighbours(v), common;
    std::set_intersection(nu.begin(), nu.end(), nv.begin(), nv.end(), std::back_inserter(common));
    if (common.size() != 2) return false;
    if (vf_[v].size() + moved.size() > 24) return false;  // a star vertex makes slivers

    std::vector<Tri> fresh;
    for (uint32_t f : moved) {
      Tri n = t_[f];
      for (uint32_t& w : n)
        if (w == u) w = v;
      const Vec3 &a = p_[n[0]], &b = p_[n[1]], &c = p_[n[2]];
      const Vec3 area_new = area_vector(a, b, c);
      const double an = norm(area_new);
      if (an < prm_.min_area2) return false;
      const Tri& o = t_[f];
      const Vec3 area_old = area_vector(p_[o[0]], p_[o[1]], p_[o[2]]);
      if (dot(area_new, area_old) < cos_turn_ * an * norm(area_old)) return false;
      for (int k = 0; k < 3; ++k)
        if (norm2(p_[n[k]] - p_[n[(k + 1) % 3]]) > prm_.max_edge * prm_.max_edge) return false;
      const double cos_new = min_angle_cos_max(a, b, c);
      if (cos_new > cos_min_angle_ && cos_new > min_angle_cos_max(p_[o[0]], p_[o[1]], p_[o[2]])) return false;
      fresh.push_back(n);
    }
    // Close to the input: the centroid and the edge midpoints of every new triangle.
    for (const Tri& n : fresh) {
      const Vec3 &a = p_[n[0]], &b = p_[n[1]], &c = p_[n[2]];
      if (!near_input((a + b + c) * (1.0 / 3.0)) || !near_input((a + b) * 0.5) || !near_input((b + c) * 0.5) ||
          !near_input((c + a) * 0.5))
        return false;
    }
    // No intersection with the rest of the surface, nor among the new triangles.
    for (size_t i = 0; i < fresh.size(); ++i) {
      if (check::triangle_is_degenerate(p_, fresh[i])) return false;
      for (size_t j = 0; j < i; ++j)
        if (check::triangle_pair_intersects(p_, fresh[i], fresh[j])) return false;
      Box3 box;
      for (uint32_t w : fresh[i]) box.add(p_[w]);
      bool hit = false;
      buckets_.for_each_in_box(box, [&](uint32_t g) {
        if (hit || !alive_[g]) return;
        const Tri& other = t_[g];
        if (other[0] == u || other[1] == u || other[2] == u) return;  // replaced or removed
        hit = check::triangle_pair_intersects(p_, fresh[i], other);
      });
      if (hit) return false;
    }

    // Apply.
    for (uint32_t f : shared) {
      alive_[f] = 0;
      for (uint32_t w : t_[f]) {
        auto& list = vf_[w];
        list.erase(std::remove(list.begin(), list.end(), f), list.end());
      }
    }
    for (size_t i = 0; i < moved.size(); ++i) {
      t_[moved[i]] = fresh[i];
      vf_[v].push_back(moved[i]);
      buckets_.update(moved[i]);
    }
    vf_[u].clear();
    vertex_alive_[u] = 0;
    // Only v's edges changed length; the others are re-checked whenever they come up.
    ++stamp_[v];
    for (uint32_t w : neighbours(v)) push(std::min(v, w), std::max(v, w));
    return true;
  }

  std::vector<uint32_t> neighbours(uint32_t v) const {
    std::vector<uint32_t> out;
    for (uint32_t f : vf_[v])
      for (uint32_t w : t_[f])
        if (w != v) out.push_back(w);
    std::sort(out.begin(), out.end());
    out.erase(std::unique(out.begin(), out.end()), out.end());
    return out;
  }

 public:
  std::vector<uint32_t> compact() {
    std::vector<uint32_t> remap(p_.size(), UINT32_MAX);
    std::vector<Vec3> points;
    for (uint32_t i = 0; i < p_.size(); ++i)
      if (vertex_alive_[i] && !vf_[i].empty()) remap[i] = uint32_t(points.size()), points.push_back(p_[i]);
    std::vector<Tri> tris;
    for (uint32_t f = 0; f < t_.size(); ++f)
      if (alive_[f]) tris.push_back({remap[t_[f][0]], remap[t_[f][1]], remap[t_[f][2]]});
    p_.swap(points);
    t_.swap(tris);
    return remap;
  }

 private:
  std::vector<Vec3>& p_;
  std::vector<Tri>& t_;
  const std::vector<uint8_t>& locked_;
  const fit::SurfaceIndex& input_;
  Vec3 origin_;
  CoarsenParams prm_;
  TriangleBuckets buckets_;
  std::vector<uint8_t> alive_, vertex_alive_;
  std::vector<uint32_t> stamp_;
  std::vector<std::vector<uint32_t>> vf_;
  std::priority_queue<Entry> queue_;
  double cos_turn_ = 0, cos_min_angle_ = 0, dev2_ = 0;
};

}  // namespace

CoarsenStats coarsen(std::vector<Vec3>& points, std::vector<Tri>& triangles, const std::vector<uint8_t>& locked,
                     const fit::SurfaceIndex& input, const Vec3& origin, const CoarsenParams& params, ProgressSink* progress) {
  CoarsenStats stats;
  stats.triangles_before = triangles.size();
  if (progress) progress->progress("coarsen", 0.0, "merging nodes on flat parts of " + std::to_string(triangles.size()) + " triangles");
  Coarsener c(points, triangles, locked, input, origin, params);
  stats.collapses = c.run(progress);
  stats.remap = c.compact();
  stats.triangles_after = triangles.size();
  if (progress)
    progress->progress("coarsen", 1.0, std::to_string(stats.triangles_before) + " -> " + std::to_string(stats.triangles_after) + " triangles");
  return stats;
}

}  // namespace vdbwrap::post
