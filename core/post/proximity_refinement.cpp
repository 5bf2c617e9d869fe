#include "post/proximity_refinement.h"

#include <algorithm>
#include <array>
#include <cmath>

#include "common/vec.h"
#include "mesh/far_from_input.h"
#include "post/local_edits.h"

namespace vdbwrap::post {
namespace {

constexpr double kDeg = M_PI / 180.0;

// The far triangles' indices, the farthest first; `dist`: each node's distance to the input
// (or a bound of it).
std::vector<uint32_t> far_triangles(const PostSurface& s, const std::vector<uint8_t>& alive,
                                    const QualityReference& ref, double far, std::vector<double>& dist) {
  std::vector<uint32_t> out;
  for (const mesh::FarTriangle& f :
       mesh::far_triangles(s.points, s.triangles, alive, *ref.input, ref.origin, far, dist))
    out.push_back(f.triangle);
  return out;
}

class ProximityRefiner : LocalEdits {
 public:
  ProximityRefiner(PostSurface& s, const QualityReference& ref, const ProximityRefinementParams& prm)
      : LocalEdits(s, ref, edit_bounds(prm)), prm_(prm), cos_turn_(std::cos(prm.max_normal_turn_deg * kDeg)) {}

  // `far`, `dist`: the far triangles and the points' distances, found before the engine was built.
  ProximityRefinementStats run(std::vector<uint32_t> far, std::vector<double> dist) {
    dist_ = std::move(dist);
    // The attempts are bounded: where much of the wrap is far (a wrap around both sides of a
    // soup, bridges over openings), most are refused, each after distance queries.
    const size_t budget = std::max<size_t>(1000, size_t(prm_.budget * double(s_.triangles.size())));
    bool last_round_changed = false;
    stats_.far_before = far.size();
    for (round_ = 0; round_ <= prm_.rounds; ++round_) {
      if (round_ > 0 && !last_round_changed) break;  // the far triangles are those of the round before
      if (round_ > 0) far = far_triangles(s_, alive_, ref_, prm_.far_distance, dist_);
      stats_.far_after = far.size();
      if (round_ == prm_.rounds || far.empty() || attempts_ >= budget) break;
      const size_t edits = stats_.pulls + stats_.splits;
      for (uint32_t f : far) {
        if (attempts_ >= budget) break;
        if (alive_[f]) ++attempts_, bring_nearer(f);
      }
      last_round_changed = stats_.pulls + stats_.splits > edits;
    }
    if (stats_.collapses > 0) compact();  // the merged nodes and their triangles go
    stats_.refusals = refusals();
    return stats_;
  }

 private:
  // The triangle's farthest corner goes onto the input when it is far; else (or when that is
  // refused) its far edges are split, the farthest midpoint first. A node of a traced feature
  // edge is pulled too: one that far off the input is off its curve (the validity loop held
  // it back), and the check of the input's sharp edges keeps the curve as near.
  void bring_nearer(uint32_t f) {
    const Tri t = s_.triangles[f];
    uint32_t corner = kNone;
    for (uint32_t v : t)
      if (v < dist_.size() && dist_[v] > prm_.far_distance && (corner == kNone || dist_[v] > dist_[corner])) corner = v;
    if (corner != kNone && (pull(corner) || collapse(corner))) return;
    std::array<std::pair<double, int>, 3> edges;
    for (int i = 0; i < 3; ++i) edges[i] = {-distance_to_input((s_.points[t[i]] + s_.points[t[(i + 1) % 3]]) * 0.5), i};
    std::sort(edges.begin(), edges.end());
    for (const auto& [d, i] : edges)
      if (-d > prm_.far_distance && split(t[i], t[(i + 1) % 3])) return;
    // A face across a concave corner, its far point between corners held back under the far
    // distance, where no split helps: its farthest corner onto the input.
    uint32_t near_corner = kNone;
    for (uint32_t v : t)
      if (v != corner && node_distance(v) > 0.5 * prm_.far_distance &&
          (near_corner == kNone || node_distance(v) > node_distance(near_corner)))
        near_corner = v;
    if (near_corner != kNone) pull(near_corner);
  }

  // Node v onto the input, or as far toward it as the checks allow.
  bool pull(uint32_t v) {
    const Vec3 p = s_.points[v], target = onto_input_anywhere(p);
    for (double t : {1.0, 0.75, 0.5, 0.25}) {
      propose_move(v, stored(lerp(p, target, t)));
      if (!nearer(change_)) continue;
      apply(change_);
      ++stats_.pulls;
      return true;
    }
    return false;
  }

  // Node v, where no pull is allowed, merged into its neighbour nearest the input, which stays
  // where it is. A node in a pleat (its fan folded over itself, as where the validity loop held
  // back one side of a crease) does not come nearer by moving: every move turns the folded
  // triangles over. Merged away, it takes the pleat with it.
  bool collapse(uint32_t v) {
    std::vector<uint32_t> around;
    neighbours(v, around);
    std::sort(around.begin(), around.end(),
              [&](uint32_t a, uint32_t b) { return node_distance(a) < node_distance(b); });
    for (uint32_t u : around) {
      if (node_distance(u) >= dist_[v]) break;
      if (const char* why = collapse_blocked(u, v)) {
        if (*why) refuse(std::string("collapse: ") + why);
        continue;
      }
      propose_collapse(u, v, s_.points[u]);
      if (!nearer(change_)) continue;
      apply(change_);
      hand_over(u, v);
      ++stats_.collapses;
      return true;
    }
    return false;
  }
  double node_distance(uint32_t v) { return v < dist_.size() ? dist_[v] : distance_to_input(s_.points[v]); }

  // Edge (a, b) split at its midpoint, the new node placed on the input.
  bool split(uint32_t a, uint32_t b) {
    if (feature_edge(a, b)) return false;  // a traced feature edge stays one edge
    const Vec3 mid = (s_.points[a] + s_.points[b]) * 0.5;
    if (!propose_split(a, b, mid)) return false;
    const Vec3 target = onto_input_anywhere(mid);
    if (norm(target - mid) > prm_.max_reach) return refuse("split: out of reach");
    change_.added_at = target;
    if (!nearer(change_)) return false;
    apply(change_);
    ++stats_.splits;
    return true;
  }

  // Does the change bring the patch nearer the input and keep the surface valid, its
  // triangles no worse shaped and the input's sharp edges as near?
  bool nearer(const Change& c) {
    const char* kind = c.added != kNone                                             ? "split: "
                       : std::find(c.dies.begin(), c.dies.end(), 1) != c.dies.end() ? "collapse: "
                                                                                    : "pull: ";
    auto no = [&](const char* why) { return refuse(std::string(kind) + why); };
    double old_min = 180, new_min = 180;
    Spread old_d, new_d;
    std::vector<Tri> made;
    std::vector<check::Corners> made_at;
    for (size_t i = 0; i < c.slots.size(); ++i) {
      const Tri& t = c.tris[i];
      if (c.dies[i]) {  // a collapse's triangle on the edge: weighed as it was only
        const Tri& o = s_.triangles[c.slots[i]];
        old_min = std::min(old_min, min_angle_deg(s_.points[o[0]], s_.points[o[1]], s_.points[o[2]]));
        continue;
      }
      const check::Corners at = {this->at(t[0], c), this->at(t[1], c), this->at(t[2], c)};
      if (check::triangle_is_degenerate(at, t)) return no("degenerate");
      if (c.slots[i] != Change::kNoSlot) {
        const Tri& o = s_.triangles[c.slots[i]];
        const Vec3 &oa = s_.points[o[0]], &ob = s_.points[o[1]], &oc = s_.points[o[2]];
        old_min = std::min(old_min, min_angle_deg(oa, ob, oc));
        if (dot(normalized(area_vector(oa, ob, oc)), normalized(area_vector(at[0], at[1], at[2]))) < cos_turn_)
          return no("turns");
      }
      new_min = std::min(new_min, min_angle_deg(at[0], at[1], at[2]));
      made.push_back(t), made_at.push_back(at);
    }
    if (new_min < std::min(old_min, prm_.min_angle_deg)) return no("sliver");
    for (uint32_t f : c.slots)
      if (f != Change::kNoSlot) {
        const Tri& o = s_.triangles[f];
        sample_grid(s_.points[o[0]], s_.points[o[1]], s_.points[o[2]], old_d);
      }
    for (const check::Corners& at : made_at) sample_grid(at[0], at[1], at[2], new_d);
    // The integral of the distance over the patch, not its mean, must drop: a split that dips
    // into a concave crease adds area, and area still off the input raises the wrap's mean.
    if (new_d.worst > old_d.worst || !(new_d.sum < old_d.sum)) return no("no nearer");
    if (!keeps_sharp_edges(c, made_at)) return no("sharp edge farther");
    if (const char* why = breaks_surface(c, made, made_at)) return no(why);
    return true;
  }

  ProximityRefinementParams prm_;
  double cos_turn_;
  size_t attempts_ = 0;       // triangles worked on
  std::vector<double> dist_;  // per node: its distance to the input at the start of the round
  ProximityRefinementStats stats_;
};

}  // namespace

ProximityRefinementParams proximity_refinement_params(double base, double offset, double feature_tolerance,
                                                      bool float_coordinates) {
  ProximityRefinementParams p;
  p.far_distance = 0.75 * base, p.max_reach = 1.5 * base;
  p.offset = offset, p.feature_tolerance = feature_tolerance, p.float_coordinates = float_coordinates;
  return p;
}

ProximityRefinementStats refine_proximity(PostSurface& surface, const QualityReference& ref,
                                          const ProximityRefinementParams& params) {
  if (surface.triangles.empty() || !ref.input || !(params.far_distance > 0)) return {};
  // Most wraps have no far triangle: then the engine (adjacency, buckets, sharp-edge samples) is
  // not built at all.
  std::vector<double> dist;
  std::vector<uint32_t> far = far_triangles(surface, {}, ref, params.far_distance, dist);
  if (far.empty()) return {};
  ProximityRefiner r(surface, ref, params);
  return r.run(std::move(far), std::move(dist));
}

}  // namespace vdbwrap::post
