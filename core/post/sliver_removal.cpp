#include "post/sliver_removal.h"

#include <algorithm>
#include <cmath>
#include <initializer_list>

#include "common/closest_point.h"
#include "common/vec.h"
#include "post/local_edits.h"

namespace vdbwrap::post {
namespace {

constexpr double kDeg = M_PI / 180.0;

class SliverRemover : LocalEdits {
 public:
  SliverRemover(PostSurface& s, const QualityReference& ref, const SliverRemovalParams& prm)
      : LocalEdits(s, ref, edit_bounds(prm)), prm_(prm) {
    cos_flat_ = std::cos(prm_.flat_angle_deg * kDeg);
    cos_turn_ = std::cos(prm_.max_normal_turn_deg * kDeg);
  }

  SliverRemovalStats run() {
    stats_.slivers_before = slivers().size();
    for (round_ = 0; round_ < prm_.rounds; ++round_) {
      const size_t changes = stats_.flips + stats_.collapses + stats_.moves;
      for (uint32_t f : slivers()) {
        if (!alive_[f] || min_angle(f) >= prm_.target_angle_deg) continue;  // changed by an earlier fix
        // A later round retries a sliver only where the surface near it changed since the
        // round before: elsewhere every check would read what refused it then.
        bool near_change = round_ == 0;
        for (uint32_t v : s_.triangles[f]) near_change = near_change || changed_near(v);
        if (near_change) fix(f);
      }
      // Nodes of the slivers left: a tangential move often opens their angles.
      std::vector<uint32_t> nodes;
      for (uint32_t f : slivers())
        for (uint32_t v : s_.triangles[f]) nodes.push_back(v);
      std::sort(nodes.begin(), nodes.end());
      nodes.erase(std::unique(nodes.begin(), nodes.end()), nodes.end());
      for (uint32_t v : nodes)
        if (round_ == 0 || changed_near(v)) try_move(v);
      if (stats_.flips + stats_.collapses + stats_.moves == changes) break;
    }
    stats_.slivers_after = slivers().size();
    if (stats_.flips + stats_.collapses + stats_.moves > 0) compact();
    stats_.refusals = refusals();
    return stats_;
  }

 private:
  // Live triangles under the target angle, the worst first.
  std::vector<uint32_t> slivers() const {
    std::vector<std::pair<double, uint32_t>> bad;
    for (uint32_t f = 0; f < s_.triangles.size(); ++f) {
      if (!alive_[f]) continue;
      const double a = min_angle(f);
      if (a < prm_.target_angle_deg) bad.push_back({a, f});
    }
    std::sort(bad.begin(), bad.end());
    std::vector<uint32_t> out;
    for (const auto& b : bad) out.push_back(b.second);
    return out;
  }

  // Is the change an improvement that keeps the surface valid and near the input?
  bool acceptable(const Change& c) {
    double old_min = 180, new_min = 180;
    size_t old_bad = 0, new_bad = 0;  // triangles under the target angle
    Spread old_d, new_d;
    std::vector<Tri> made;
    std::vector<check::Corners> made_at;
    // The patch's normal (area-weighted: slivers hardly count), and how far its well-shaped
    // triangles are from it. A sliver's own normal says little: a new triangle in its slot is
    // held to the patch's.
    Vec3 patch{0, 0, 0};
    for (uint32_t f : c.slots) {
      const Tri& o = s_.triangles[f];
      patch = patch + area_vector(s_.points[o[0]], s_.points[o[1]], s_.points[o[2]]);
    }
    patch = normalized(patch);
    double patch_cos = cos_turn_;
    for (uint32_t f : c.slots)
      if (min_angle(f) >= prm_.target_angle_deg) {
        const Tri& o = s_.triangles[f];
        patch_cos =
            std::min(patch_cos, dot(patch, normalized(area_vector(s_.points[o[0]], s_.points[o[1]], s_.points[o[2]]))));
      }
    for (size_t i = 0; i < c.slots.size(); ++i) {
      const Tri& o = s_.triangles[c.slots[i]];
      const Vec3 &oa = s_.points[o[0]], &ob = s_.points[o[1]], &oc = s_.points[o[2]];
      const double old_angle = min_angle_deg(oa, ob, oc);
      old_min = std::min(old_min, old_angle);
      old_bad += old_angle < prm_.target_angle_deg;
      if (c.dies[i]) continue;
      const Tri& t = c.tris[i];
      const check::Corners at = {this->at(t[0], c), this->at(t[1], c), this->at(t[2], c)};
      if (check::triangle_is_degenerate(at, t)) return refuse("degenerate");
      const Vec3 n_new = normalized(area_vector(at[0], at[1], at[2]));
      if (old_angle >= prm_.target_angle_deg ? dot(normalized(area_vector(oa, ob, oc)), n_new) < cos_turn_
                                             : dot(patch, n_new) < std::min(cos_turn_, patch_cos))
        return refuse("turns");
      const double new_angle = min_angle_deg(at[0], at[1], at[2]);
      new_min = std::min(new_min, new_angle);
      new_bad += new_angle < prm_.target_angle_deg;
      made.push_back(t), made_at.push_back(at);
    }
    // The smallest angle grows; or, with a sliver next to it that stays as it is, it does not
    // shrink and fewer triangles are left under the target.
    if (new_min < old_min + prm_.min_gain_deg && !(new_min >= old_min && new_bad < old_bad)) return refuse("no gain");
    // Distances last of the local checks: they ask the input's index, the rest reads the wrap.
    for (uint32_t f : c.slots) {
      const Tri& o = s_.triangles[f];
      sample(s_.points[o[0]], s_.points[o[1]], s_.points[o[2]], old_d);
    }
    for (size_t i = 0; i < made.size(); ++i) sample(made_at[i][0], made_at[i][1], made_at[i][2], new_d);
    if (new_d.worst > std::max(prm_.max_deviation, old_d.worst)) return refuse("far");
    // On average no farther from the input than before (a tenth of the bound for rounding).
    if (new_d.mean() > old_d.mean() + 0.1 * prm_.max_deviation) return refuse("farther on average");
    if (!keeps_sharp_edges(c, made_at)) return refuse("sharp edge farther");
    // No new triangle meets another: among themselves, then the rest of the surface.
    if (const char* why = breaks_surface(c, made, made_at)) return refuse(why);
    return true;
  }

  // A sliver is fixed by the first operation that passes: a cap (an angle over 100 degrees)
  // by flipping its longest edge first, a needle by collapsing its shortest edge first.
  void fix(uint32_t f) {
    const Tri t = s_.triangles[f];
    std::array<std::pair<double, int>, 3> edges;  // length of edge (t[i], t[i+1]), i
    for (int i = 0; i < 3; ++i) edges[i] = {norm2(s_.points[t[(i + 1) % 3]] - s_.points[t[i]]), i};
    std::sort(edges.begin(), edges.end());
    const bool cap = edges[2].first > edges[0].first + edges[1].first -
                                          2 * std::cos(100 * kDeg) * std::sqrt(edges[0].first * edges[1].first);
    auto flip_at = [&](int k) { return try_flip(t[edges[k].second], t[(edges[k].second + 1) % 3]); };
    auto collapse_at = [&](int k) { return try_collapse(t[edges[k].second], t[(edges[k].second + 1) % 3]); };
    if (cap) {
      if (flip_at(2) || collapse_at(0) || collapse_at(1)) return;
    } else {
      if (collapse_at(0) || flip_at(2) || flip_at(1) || collapse_at(1)) return;
    }
  }

  // Distance from p to the segment ab.
  static double to_segment(const Vec3& p, const Vec3& a, const Vec3& b) {
    double t;
    return norm(p - closest_on_segment(a, b, p, t));
  }

  // Edge (a, b) flipped. Where its triangles are nearly flat; or where one of them is a cap
  // whose apex lies almost on the edge (the flip then moves the surface by that little, even on
  // a sharp edge, and a traced edge a b runs on through the apex).
  bool try_flip(uint32_t a, uint32_t b) {
    uint32_t f1, f2;
    if (!edge_triangles(a, b, f1, f2)) return false;
    const uint32_t c = third(s_.triangles[f1], a, b), d = third(s_.triangles[f2], a, b);
    if (c == d) return false;
    for (uint32_t g : vt_[c]) {
      const Tri& t = s_.triangles[g];
      if (t[0] == d || t[1] == d || t[2] == d) return false;  // the new edge exists already
    }
    const Vec3 &pa = s_.points[a], &pb = s_.points[b];
    const bool c_on = to_segment(s_.points[c], pa, pb) <= prm_.max_deviation;
    const bool d_on = to_segment(s_.points[d], pa, pb) <= prm_.max_deviation;
    const bool traced = feature_edge(a, b);
    if (traced && !c_on && !d_on) return refuse("flip: feature edge");
    if (!c_on && !d_on) {
      const Vec3 n1 = normalized(area_vector(pa, pb, s_.points[c]));
      const Vec3 n2 = normalized(area_vector(pb, pa, s_.points[d]));
      if (dot(n1, n2) < cos_flat_) return refuse("flip: not flat");
    }
    change_.clear();
    change_.add(f1, Tri{c, a, d});
    change_.add(f2, Tri{d, b, c});
    if (!acceptable(change_)) return false;
    apply(change_);
    if (traced) {  // the chain a b now runs a - apex - b
      const uint32_t apex = c_on ? c : d;
      auto unlink = [&](uint32_t x, uint32_t y) {
        auto& list = feature_[x];
        list.erase(std::remove(list.begin(), list.end(), y), list.end());
      };
      unlink(a, b), unlink(b, a);
      for (uint32_t end : {a, b})
        if (!feature_edge(apex, end)) feature_[apex].push_back(end), feature_[end].push_back(apex);
      s_.locked[apex] = 1;
    }
    ++stats_.flips;
    return true;
  }

  // Edge (a, b) collapsed into one node. A fixed node keeps its place; of two fixed nodes one
  // goes into the other where the input's sharp edges stay as near (checked with the rest), and
  // the traced chains through it then run through the other.
  bool try_collapse(uint32_t a, uint32_t b) {
    if (fixed(a) && fixed(b)) return collapse_into(a, b) || collapse_into(b, a);
    return fixed(b) ? collapse_into(b, a) : collapse_into(a, b);
  }

  // v goes into u (u's index stays).
  bool collapse_into(uint32_t u, uint32_t v) {
    uint32_t f1, f2;
    if (!edge_triangles(u, v, f1, f2)) return false;
    const uint32_t c = third(s_.triangles[f1], u, v), d = third(s_.triangles[f2], u, v);
    // Link condition: u and v share exactly the two neighbours across the edge.
    std::vector<uint32_t> nu, nv, common;
    neighbours(u, nu), neighbours(v, nv);
    std::set_intersection(nu.begin(), nu.end(), nv.begin(), nv.end(), std::back_inserter(common));
    if (common.size() != 2 || c == d) return refuse("collapse: link");
    // c and d each lose an edge: keep them at three or more.
    std::vector<uint32_t> nc, nd;
    neighbours(c, nc), neighbours(d, nd);
    if (nc.size() < 4 || nd.size() < 4) return refuse("collapse: valence");
    std::vector<Vec3> places;
    if (fixed(u)) {
      places.push_back(s_.points[u]);
    } else {
      const double cell = std::min(s_.cell_size[u], s_.cell_size[v]);
      places.push_back(
          onto_input((s_.points[u] + s_.points[v]) * 0.5, cell > 0 ? cell : norm(s_.points[u] - s_.points[v])));
      places.push_back(s_.points[u]);
      places.push_back(s_.points[v]);
    }
    for (const Vec3& x : places) {
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
      if (!acceptable(change_)) continue;
      apply(change_);
      vt_[v].clear();
      // v's traced edges go to u.
      for (uint32_t w : feature_[v]) {
        auto& list = feature_[w];
        list.erase(std::remove(list.begin(), list.end(), v), list.end());
        if (w != u && !feature_edge(u, w)) feature_[u].push_back(w), list.push_back(u);
      }
      feature_[v].clear();
      ++stats_.collapses;
      return true;
    }
    return false;
  }

  // Node v moved toward the centroid of its neighbours, in its tangent plane, then onto the input.
  bool try_move(uint32_t v) {
    if (vt_[v].empty()) return false;
    if (fixed(v)) return slide_along_chain(v);
    std::vector<uint32_t> nv;
    neighbours(v, nv);
    Vec3 centroid{0, 0, 0}, normal{0, 0, 0};
    for (uint32_t w : nv) centroid = centroid + s_.points[w];
    centroid = centroid * (1.0 / double(nv.size()));
    for (uint32_t g : vt_[v]) {
      const Tri& t = s_.triangles[g];
      normal = normal + area_vector(s_.points[t[0]], s_.points[t[1]], s_.points[t[2]]);
    }
    normal = normalized(normal);
    const Vec3 p = s_.points[v];
    const Vec3 step = centroid - p;
    const Vec3 tangential = p + step - normal * dot(step, normal);
    const double cell = s_.cell_size[v] > 0 ? s_.cell_size[v] : norm(step);
    return move_to_first_acceptable(v, {onto_input(tangential, cell), onto_input(p + (tangential - p) * 0.5, cell)});
  }

  // Node v moved to the first of `targets` the checks accept, if any.
  bool move_to_first_acceptable(uint32_t v, std::initializer_list<Vec3> targets) {
    for (const Vec3& x : targets) {
      propose_move(v, x);
      if (!acceptable(change_)) continue;
      apply(change_);
      ++stats_.moves;
      return true;
    }
    return false;
  }

  // A snapped node on a straight run of its traced chain u - v - w slides along it toward the
  // middle of u w: the feature line stays where it is, and the triangles between two close
  // feature curves get their nodes staggered (needles between them open up).
  bool slide_along_chain(uint32_t v) {
    if (feature_[v].size() != 2) return false;
    const Vec3 &a = s_.points[feature_[v][0]], &b = s_.points[feature_[v][1]], p = s_.points[v];
    if (to_segment(p, a, b) > prm_.feature_tolerance) return false;
    const Vec3 middle = (a + b) * 0.5;
    return move_to_first_acceptable(v, {stored(middle), stored((p + middle) * 0.5)});
  }

  SliverRemovalParams prm_;
  double cos_flat_ = 1, cos_turn_ = 1;
  SliverRemovalStats stats_;
};

}  // namespace

SliverRemovalStats remove_slivers(PostSurface& surface, const QualityReference& ref,
                                  const SliverRemovalParams& params) {
  if (surface.triangles.empty() || !ref.input) return {};
  SliverRemover r(surface, ref, params);
  return r.run();
}

}  // namespace vdbwrap::post
