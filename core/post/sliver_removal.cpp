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
    round_ = 0;
    improve(0);
    // Slivers left in strips: more nodes along the rails, then the same operations near them.
    for (int pass = 0; pass < prm_.rail_passes; ++pass) {
      ++round_;
      if (split_rails() == 0) break;
      improve(round_ + 1);
    }
    stats_.slivers_after = slivers().size();
    if (changes() > 0) compact();
    stats_.refusals = refusals();
    return stats_;
  }

 private:
  size_t changes() const { return stats_.flips + stats_.collapses + stats_.moves + stats_.splits; }

  // Rounds of fixes and moves from round `first`: in the first of all every sliver is tried,
  // later only those near a change.
  void improve(int first) {
    for (round_ = first; round_ < first + prm_.rounds; ++round_) {
      const size_t before = changes();
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
      if (changes() == before) break;
    }
  }

  // Twice the area of f over edge (a, b)'s length: f's height over that edge.
  double height_over(uint32_t f, uint32_t a, uint32_t b) const {
    const Tri& t = s_.triangles[f];
    const double len = norm(s_.points[b] - s_.points[a]);
    return len > 0 ? norm(area_vector(s_.points[t[0]], s_.points[t[1]], s_.points[t[2]])) / len : 0.0;
  }

  // A strip of slivers between two rows of nodes (two close feature curves, the faces of a
  // rod thinner than the cells) cannot be triangulated well with the nodes it has: its
  // triangles are as long as the nodes are apart along the rows, and only as high as the rows
  // are apart. Each sliver's rails (its long edges along a row: a traced feature edge, or one
  // with a well-shaped triangle across it) are split at their middle, on the edge, so the
  // surface does not move; the flips after it then make triangles half as long. Rails too long
  // for their height to become good in two halvings are left (a step far finer than the cells).
  size_t split_rails() {
    const double t = std::tan(prm_.target_angle_deg * kDeg);
    const double reach = double(1 << std::min(prm_.rail_passes, 8));  // how much too long a rail may be
    std::vector<std::pair<uint32_t, uint32_t>> rails;
    for (uint32_t f : slivers()) {
      const Tri tri = s_.triangles[f];
      for (int i = 0; i < 3; ++i) {
        const uint32_t a = tri[i], b = tri[(i + 1) % 3];
        const double len = norm(s_.points[b] - s_.points[a]), h = height_over(f, a, b);
        if (!(h < len * t) || h * reach < len * t) continue;  // not long for its height, or hopeless
        uint32_t ab, ba;
        if (!edge_triangles(a, b, ab, ba)) continue;
        const uint32_t other = ab == f ? ba : ab;
        if (!feature_edge(a, b) && height_over(other, a, b) < len * t) continue;  // a diagonal
        rails.push_back({std::min(a, b), std::max(a, b)});
      }
    }
    std::sort(rails.begin(), rails.end());
    rails.erase(std::unique(rails.begin(), rails.end()), rails.end());
    size_t made = 0;
    for (const auto& [a, b] : rails) made += split_on_edge(a, b);
    return made;
  }

  // The traced chain's edge (a, b) now runs a - m - b; m stays on it (locked, as a and b are).
  void run_chain_through(uint32_t a, uint32_t b, uint32_t m) {
    std::replace(feature_[a].begin(), feature_[a].end(), b, m);
    std::replace(feature_[b].begin(), feature_[b].end(), a, m);
    feature_[m] = {a, b};
    s_.locked[m] = 1;
  }

  // Edge (a, b) split at its middle, the new node on the edge: the surface stays where it is
  // (up to the float rounding of the output, which the intersection check covers).
  bool split_on_edge(uint32_t a, uint32_t b) {
    const uint32_t m = uint32_t(s_.points.size());
    if (!propose_split(a, b, stored((s_.points[a] + s_.points[b]) * 0.5))) return false;
    std::vector<Tri> made;
    std::vector<check::Corners> made_at;
    for (const Tri& t : change_.tris) {
      made.push_back(t), made_at.push_back({at(t[0], change_), at(t[1], change_), at(t[2], change_)});
      if (check::triangle_is_degenerate(made_at.back(), t)) return refuse("split: degenerate");
    }
    if (const char* why = breaks_surface(change_, made, made_at)) return refuse(std::string("split: ") + why);
    const bool traced = feature_edge(a, b);
    commit(change_);
    if (traced) run_chain_through(a, b, m);
    ++stats_.splits;
    return true;
  }

  // Live triangles under the target angle, the worst first.
  // (Each triangle's smallest angle is kept current: the rounds ask for the slivers twice, and
  // the triangles they would measure are a few hundred times as many as the slivers.)
  std::vector<uint32_t> slivers() {
    std::vector<std::pair<double, uint32_t>> bad;
    for (uint32_t f = uint32_t(angle_.size()); f < s_.triangles.size(); ++f) angle_.push_back(min_angle(f));
    for (uint32_t f = 0; f < s_.triangles.size(); ++f)
      if (alive_[f] && angle_[f] < prm_.target_angle_deg) bad.push_back({angle_[f], f});
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
    // triangles are from it. A new triangle in a well-shaped triangle's slot turns little from
    // it. One in a sliver's slot, or an appended one, turns little from the patch or from a
    // triangle it replaces: the patch's normal alone says little where the patch spans a sharp
    // edge (a fan of slivers on a face beside a wall: its normal is half the wall's).
    Vec3 patch{0, 0, 0};
    for (uint32_t f : c.slots) {
      if (f == Change::kNoSlot) continue;
      const Tri& o = s_.triangles[f];
      patch = patch + area_vector(s_.points[o[0]], s_.points[o[1]], s_.points[o[2]]);
    }
    patch = normalized(patch);
    double patch_cos = cos_turn_;
    for (uint32_t f : c.slots)
      if (f != Change::kNoSlot && min_angle(f) >= prm_.target_angle_deg) {
        const Tri& o = s_.triangles[f];
        patch_cos =
            std::min(patch_cos, dot(patch, normalized(area_vector(s_.points[o[0]], s_.points[o[1]], s_.points[o[2]]))));
      }
    for (size_t i = 0; i < c.slots.size(); ++i) {
      const bool appended = c.slots[i] == Change::kNoSlot;
      Vec3 old_normal{0, 0, 0};
      double old_angle = 0;
      if (!appended) {
        const Tri& o = s_.triangles[c.slots[i]];
        const Vec3 &oa = s_.points[o[0]], &ob = s_.points[o[1]], &oc = s_.points[o[2]];
        old_angle = min_angle_deg(oa, ob, oc);
        old_normal = normalized(area_vector(oa, ob, oc));
        old_min = std::min(old_min, old_angle);
        old_bad += old_angle < prm_.target_angle_deg;
      }
      if (c.dies[i]) continue;
      const Tri& t = c.tris[i];
      const check::Corners at = {this->at(t[0], c), this->at(t[1], c), this->at(t[2], c)};
      if (check::triangle_is_degenerate(at, t)) return refuse("degenerate");
      const Vec3 n_new = normalized(area_vector(at[0], at[1], at[2]));
      bool own = !appended && dot(old_normal, n_new) >= cos_turn_;
      if (appended)
        for (uint32_t g : c.slots)
          if (g != Change::kNoSlot) {
            const Tri& o = s_.triangles[g];
            const Vec3 n = normalized(area_vector(s_.points[o[0]], s_.points[o[1]], s_.points[o[2]]));
            own = own || dot(n, n_new) >= cos_turn_;
          }
      const bool well_shaped = !appended && old_angle >= prm_.target_angle_deg;
      if (well_shaped ? !own : !own && dot(patch, n_new) < std::min(cos_turn_, patch_cos)) return refuse("turns");
      const double new_angle = min_angle_deg(at[0], at[1], at[2]);
      new_min = std::min(new_min, new_angle);
      new_bad += new_angle < prm_.target_angle_deg;
      made.push_back(t), made_at.push_back(at);
    }
    // The smallest angle grows; or, with a sliver next to it that stays as it is, it does not
    // shrink and fewer triangles are left under the target. In a strip too narrow for any
    // triangle across it, fewer slivers is the gain: each collapse of a rung leaves the rest of
    // the strip thinner, until its two rails are one.
    if (new_min < old_min + prm_.min_gain_deg && !(new_min >= old_min && new_bad < old_bad) &&
        !(narrow_strip_ && new_bad < old_bad))
      return refuse("no gain");
    // Distances last of the local checks: they ask the input's index, the rest reads the wrap.
    for (uint32_t f : c.slots)
      if (f != Change::kNoSlot) old_d.add(spread_of(f));
    for (size_t i = 0; i < made.size(); ++i) sample(made_at[i][0], made_at[i][1], made_at[i][2], new_d);
    const double bound = narrow_strip_ ? std::max(prm_.max_deviation, prm_.strip_width) : prm_.max_deviation;
    if (new_d.worst > std::max(bound, old_d.worst)) return refuse("far");
    // On average no farther from the input than before (a tenth of the bound for rounding).
    if (new_d.mean() > old_d.mean() + 0.1 * prm_.max_deviation) return refuse("farther on average");
    if (!keeps_sharp_edges(c, made_at, between_curves_ ? bound : -1)) return refuse("sharp edge farther");
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
    // A sliver with every corner on a feature curve lies in a strip between two curves closer
    // than the nodes along them (a lip a sixtieth of a base cell high on a print): the input's
    // sharp edges may move as far as the surface may, so the two curves become one there. (At
    // the feature tolerance 1514499.stl kept 2.4 % of its triangles under 10 degrees at 1 %;
    // everywhere, the looser bound moved p95 and the sharp edges elsewhere.)
    between_curves_ = fixed(t[0]) && fixed(t[1]) && fixed(t[2]);
    const bool done = cap ? flip_at(2) || collapse_at(0) || collapse_at(1)
                          : collapse_at(0) || flip_at(2) || flip_at(1) || collapse_at(1) || split_rail_and_flip(f);
    // Lower than a triangle across the strip can be (the same lips at 0.5 %: 2.5 %): its rungs
    // collapse while the slivers get fewer, the surface and the sharp edges allowed to move by
    // up to strip_width. The last resort: where the rails can be split, that keeps both curves.
    narrow_strip_ = between_curves_ && norm(area_vector(s_.points[t[0]], s_.points[t[1]], s_.points[t[2]])) <
                                           prm_.strip_width * std::sqrt(edges[2].first);
    if (!done && narrow_strip_) (void)(collapse_at(0) || collapse_at(1));
    between_curves_ = narrow_strip_ = false;
  }

  // A needle in a strip of them: two rows of nodes (a thin tube, or two close feature curves)
  // with edges along them much longer than the rows are apart. No flip or collapse helps
  // there; the rows need more nodes. One of the needle's long edges (the rail, along a row) is
  // split at its middle, and its other long edge (the diagonal across the strip) flipped onto
  // the new node: both needles on the diagonal become triangles twice as wide for their length.
  // The shorter long edge is tried as the rail first (the diagonal is the longer).
  bool split_rail_and_flip(uint32_t f) {
    const Tri t = s_.triangles[f];
    int apex = 0;  // the corner with the smallest angle: the one across the shortest edge
    double shortest = INFINITY;
    for (int i = 0; i < 3; ++i) {
      const double e = norm2(s_.points[t[(i + 2) % 3]] - s_.points[t[(i + 1) % 3]]);
      if (e < shortest) shortest = e, apex = i;
    }
    const uint32_t a = t[apex], b = t[(apex + 1) % 3], c = t[(apex + 2) % 3];  // f runs a -> b -> c
    const bool ab_first = norm2(s_.points[b] - s_.points[a]) <= norm2(s_.points[c] - s_.points[a]);
    // The rail a -> b (apex at its start) or c -> a (apex at its end), the third corner after it.
    return ab_first ? split_rail_flip(f, a, b, c, true) || split_rail_flip(f, c, a, b, false)
                    : split_rail_flip(f, c, a, b, false) || split_rail_flip(f, a, b, c, true);
  }

  // f = (u, v, w): rail u -> v split at a new node m, and the diagonal from the apex (u when
  // apex_first, else v) to w flipped onto m.
  bool split_rail_flip(uint32_t f, uint32_t u, uint32_t v, uint32_t w, bool apex_first) {
    uint32_t uv, vu;
    if (!edge_triangles(u, v, uv, vu) || uv != f) return false;
    const uint32_t d = third(s_.triangles[vu], u, v);  // across the rail
    const uint32_t apex = apex_first ? u : v;
    if (feature_edge(apex, w)) return false;  // the rail is the other long edge
    uint32_t across, back;                    // the triangle across the diagonal holds apex -> w when apex_first
    if (!(apex_first ? edge_triangles(u, w, across, back) : edge_triangles(w, v, across, back))) return false;
    const uint32_t x = third(s_.triangles[across], apex, w);
    if (x == d || x == u || x == v || d == w || across == vu || back != f) return false;
    const bool traced = feature_edge(u, v);
    const Vec3 mid = (s_.points[u] + s_.points[v]) * 0.5;
    const double cell = std::min(s_.cell_size[u], s_.cell_size[v]);
    const uint32_t m = uint32_t(s_.points.size());
    change_.clear();
    change_.added = m;
    // A traced rail keeps its line: the new node stays on it (it is locked as the rail's ends).
    change_.added_at = traced ? stored(mid) : onto_input(mid, cell > 0 ? cell : norm(s_.points[u] - s_.points[v]));
    change_.added_cell = cell;
    if (apex_first) {
      change_.add(f, Tri{m, w, x});
      change_.add(across, Tri{x, u, m});
      change_.add(Change::kNoSlot, Tri{m, v, w});
    } else {
      change_.add(f, Tri{u, m, w});
      change_.add(across, Tri{x, w, m});
      change_.add(Change::kNoSlot, Tri{m, v, x});
    }
    change_.add(vu, Tri{v, m, d});
    change_.add(Change::kNoSlot, Tri{m, u, d});
    if (!acceptable(change_)) return false;
    commit(change_);
    if (traced) run_chain_through(u, v, m);
    ++stats_.splits;
    return true;
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
    commit(change_);
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
    if (const char* why = collapse_blocked(u, v)) return *why && refuse(std::string("collapse: ") + why);
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
      propose_collapse(u, v, x);
      if (!acceptable(change_)) continue;
      commit(change_);
      hand_over(u, v);
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
      commit(change_);
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

  // Triangle f's distance samples, measured once while it stays as it is (each sliver is
  // weighed for several operations, over the same old triangles).
  const Spread& spread_of(uint32_t f) {
    if (spread_.size() < s_.triangles.size())
      spread_.resize(s_.triangles.size()), spread_known_.resize(s_.triangles.size(), 0);
    if (!spread_known_[f]) {
      const Tri& o = s_.triangles[f];
      spread_[f] = Spread{};
      sample(s_.points[o[0]], s_.points[o[1]], s_.points[o[2]], spread_[f]);
      spread_known_[f] = 1;
    }
    return spread_[f];
  }

  // The change made, and the smallest angles of the triangles it rewrote or appended.
  void commit(const Change& c) {
    const size_t had = s_.triangles.size();
    apply(c);
    for (uint32_t f : c.slots)
      if (f != Change::kNoSlot) {
        if (f < angle_.size()) angle_[f] = min_angle(f);
        if (f < spread_known_.size()) spread_known_[f] = 0;
      }
    if (angle_.size() == had)
      for (uint32_t f = uint32_t(had); f < s_.triangles.size(); ++f) angle_.push_back(min_angle(f));
  }

  SliverRemovalParams prm_;
  std::vector<double> angle_;   // per triangle: its smallest angle (degrees)
  std::vector<Spread> spread_;  // per triangle: its distance samples, where known
  std::vector<uint8_t> spread_known_;
  double cos_flat_ = 1, cos_turn_ = 1;
  bool between_curves_ = false;  // fixing a sliver whose corners are all on feature curves
  bool narrow_strip_ = false;    // and lower than strip_width: no triangle spans its strip well
  SliverRemovalStats stats_;
};

}  // namespace

SliverRemovalStats remove_slivers(PostSurface& surface, const QualityReference& ref,
                                  const SliverRemovalParams& params) {
  if (surface.triangles.empty() || !ref.input) return {};
  SliverRemover r(surface, ref, params);
  return r.run();
}

SliverRemovalParams sliver_removal_params(double max_deviation, double offset, double finest, bool float_coordinates) {
  SliverRemovalParams p;
  p.max_deviation = max_deviation, p.offset = offset, p.float_coordinates = float_coordinates;
  p.feature_tolerance = 0.5 * max_deviation;
  p.strip_width = 0.5 * std::tan(p.target_angle_deg * kDeg) * finest;
  return p;
}

}  // namespace vdbwrap::post
