// The fallback rebuild (spec stage 4, second way): ear clipping of the region's contour in
// its plane, without the input. It respects the characteristic edge length: a corner wider
// than an ear gets one or two new nodes at that distance inside (the quadrilateral formed is
// split into two triangles), so the front advances like the triangles it replaces instead
// of closing with long chords. New nodes take the height of their neighbours, then a few
// smoothing passes make the patch fair. Also the plane helpers both fills share.
#include <algorithm>
#include <cmath>
#include <list>

#include "common/vec.h"
#include "common/vec2.h"
#include "post/region_fill.h"

namespace vdbwrap::post {

using P2 = Vec2;

namespace {

// Segments ab and cd share a point (touching counts).
bool segments_meet(const P2& a, const P2& b, const P2& c, const P2& d) {
  const double o1 = orient2(a, b, c), o2 = orient2(a, b, d), o3 = orient2(c, d, a), o4 = orient2(c, d, b);
  if (((o1 > 0 && o2 < 0) || (o1 < 0 && o2 > 0)) && ((o3 > 0 && o4 < 0) || (o3 < 0 && o4 > 0))) return true;
  auto on = [](const P2& p, const P2& q, const P2& r, double o) {  // r on segment pq, given orient2(p, q, r) = o
    if (o != 0) return false;
    return std::min(p[0], q[0]) <= r[0] && r[0] <= std::max(p[0], q[0]) && std::min(p[1], q[1]) <= r[1] &&
           r[1] <= std::max(p[1], q[1]);
  };
  return on(a, b, c, o1) || on(a, b, d, o2) || on(c, d, a, o3) || on(c, d, b, o4);
}

// Strictly inside triangle abc (counter-clockwise), with a margin relative to its size.
bool inside_triangle(const P2& p, const P2& a, const P2& b, const P2& c) {
  return orient2(a, b, p) > 0 && orient2(b, c, p) > 0 && orient2(c, a, p) > 0;
}

P2 rotate(const P2& v, double angle) {
  const double c = std::cos(angle), s = std::sin(angle);
  return {c * v[0] - s * v[1], s * v[0] + c * v[1]};
}

struct Node {
  uint32_t id;  // node number of the fill
  P2 q;
};

}  // namespace

std::array<double, 2> PlaneFrame::to_2d(const Vec3& p) const {
  const Vec3 d = p - origin;
  return {dot(d, e1), dot(d, e2)};
}
Vec3 PlaneFrame::to_3d(const std::array<double, 2>& q, double h) const {
  return origin + e1 * q[0] + e2 * q[1] + n * h;
}
double PlaneFrame::height(const Vec3& p) const { return dot(p - origin, n); }

PlaneFrame plane_frame(const RegionProblem& problem) {
  PlaneFrame f;
  f.origin = {0, 0, 0};
  for (const Vec3& p : problem.contour) f.origin = f.origin + p;
  if (!problem.contour.empty()) f.origin = f.origin * (1.0 / double(problem.contour.size()));
  f.n = normalized(problem.normal);
  // Any axis not along n.
  const Vec3 a = std::fabs(f.n[0]) < 0.6 ? Vec3{1, 0, 0} : Vec3{0, 1, 0};
  f.e1 = normalized(a - f.n * dot(a, f.n));
  f.e2 = cross(f.n, f.e1);
  return f;
}

double signed_area2(const std::vector<P2>& poly) {
  double s = 0;
  for (size_t i = 0; i < poly.size(); ++i) s += cross2(poly[i], poly[(i + 1) % poly.size()]);
  return s;
}

bool is_simple(const std::vector<P2>& poly) {
  const size_t n = poly.size();
  if (n < 3) return false;
  for (size_t i = 0; i < n; ++i)
    for (size_t j = i + 1; j < n; ++j) {
      if (j == i + 1 || (i == 0 && j == n - 1)) {
        // Adjacent edges share one end; they must not fold back onto each other.
        const P2& s = i == 0 && j == n - 1 ? poly[0] : poly[j];
        const P2& u = i == 0 && j == n - 1 ? poly[1] : poly[i];
        const P2& w = i == 0 && j == n - 1 ? poly[n - 1] : poly[(j + 1) % n];
        if (orient2(u, s, w) == 0 && dot2(sub2(u, s), sub2(w, s)) > 0) return false;
        continue;
      }
      if (segments_meet(poly[i], poly[(i + 1) % n], poly[j], poly[(j + 1) % n])) return false;
    }
  return true;
}

RegionFill fill_by_ear_clipping(const RegionProblem& problem) {
  RegionFill out;
  auto fail = [&](const std::string& why) {
    out = RegionFill{};
    out.why = why;
    return out;
  };
  const size_t nc = problem.contour.size(), base = nc + problem.fixed.size();
  if (nc < 3) return fail("contour has fewer than 3 nodes");
  if (!(problem.target > 0)) return fail("no characteristic length");
  const PlaneFrame frame = plane_frame(problem);
  std::vector<P2> polygon;
  std::vector<double> height;  // per fill node
  for (const Vec3& p : problem.contour) polygon.push_back(frame.to_2d(p)), height.push_back(frame.height(p));
  height.resize(base, 0);
  if (signed_area2(polygon) <= 0) return fail("contour not counter-clockwise in the region's plane");
  if (!is_simple(polygon)) return fail("contour overlaps itself in the region's plane");

  const double L = problem.target;
  std::list<Node> front;
  for (uint32_t i = 0; i < nc; ++i) front.push_back({i, polygon[i]});
  std::vector<P2> plane_of(base);  // 2D position of every fill node
  for (uint32_t i = 0; i < nc; ++i) plane_of[i] = polygon[i];
  auto add_node = [&](const P2& q, double h) {
    const uint32_t id = uint32_t(base + out.new_points.size());
    out.new_points.push_back(frame.to_3d(q, h));
    plane_of.push_back(q);
    height.push_back(h);
    return id;
  };
  auto next_of = [&](std::list<Node>::iterator it) { return ++it == front.end() ? front.begin() : it; };
  auto prev_of = [&](std::list<Node>::iterator it) {
    return it == front.begin() ? std::prev(front.end()) : std::prev(it);
  };
  // A new front edge or triangle side (p, q) must not meet the front except at the three nodes
  // of the corner being cut.
  auto crosses_front = [&](const P2& p, const P2& q, uint32_t skip_a, uint32_t skip_i, uint32_t skip_b) {
    for (auto it = front.begin(); it != front.end(); ++it) {
      auto nx = next_of(it);
      const bool touches_corner = (it->id == skip_a || it->id == skip_i || it->id == skip_b) &&
                                  (nx->id == skip_a || nx->id == skip_i || nx->id == skip_b);
      if (touches_corner) continue;
      if (it->id == skip_a || it->id == skip_b || nx->id == skip_a || nx->id == skip_b) {
        // Edges sharing a corner node: only a crossing away from that node counts.
        const P2& s = it->q;
        const P2& e = nx->q;
        const double o1 = orient2(p, q, s), o2 = orient2(p, q, e), o3 = orient2(s, e, p), o4 = orient2(s, e, q);
        if (((o1 > 0 && o2 < 0) || (o1 < 0 && o2 > 0)) && ((o3 > 0 && o4 < 0) || (o3 < 0 && o4 > 0))) return true;
        continue;
      }
      if (segments_meet(p, q, it->q, nx->q)) return true;
    }
    return false;
  };
  auto any_inside = [&](const P2& a, const P2& b, const P2& c, uint32_t ia, uint32_t ii, uint32_t ib) {
    for (const Node& n : front)
      if (n.id != ia && n.id != ii && n.id != ib && inside_triangle(n.q, a, b, c)) return true;
    return false;
  };
  auto near_front = [&](const P2& q, uint32_t ia, uint32_t ii, uint32_t ib) {
    for (const Node& n : front)
      if (n.id != ia && n.id != ii && n.id != ib && length2(sub2(n.q, q)) < 0.4 * L) return true;
    return false;
  };

  const size_t max_steps = 40 * nc + 200;
  for (size_t step = 0; front.size() > 3; ++step) {
    if (step > max_steps || out.new_points.size() > 20 * nc) return fail("ear clipping did not close the contour");
    // Corners by increasing interior angle; the first one that can be cut is.
    std::vector<std::pair<double, std::list<Node>::iterator>> corners;
    for (auto it = front.begin(); it != front.end(); ++it) {
      const P2 to_next = sub2(next_of(it)->q, it->q), to_prev = sub2(prev_of(it)->q, it->q);
      double angle =
          std::atan2(cross2(to_next, to_prev), dot2(to_next, to_prev));  // from next, counter-clockwise, to prev
      if (angle <= 0) angle += 2 * M_PI;
      corners.push_back({angle, it});
    }
    std::sort(corners.begin(), corners.end(), [](const auto& x, const auto& y) { return x.first < y.first; });
    // Two passes: by the rules, then any ear at all (a corner the rules want nodes in may
    // have no room for them).
    bool cut = false;
    for (int pass = 0; pass < 2 && !cut; ++pass)
      for (const auto& [angle, it] : corners) {
        if (angle >= M_PI) break;  // only convex corners are cut
        auto pv = prev_of(it), nx = next_of(it);
        const P2 &a = pv->q, &i = it->q, &b = nx->q;
        const double la = length2(sub2(a, i)), lb = length2(sub2(b, i));
        const double ha = height[pv->id], hi = height[it->id], hb = height[nx->id];
        // An ear when the corner is sharp, or not wide and its new edge stays within the
        // characteristic length; else new nodes at that length inside the corner.
        const double chord = length2(sub2(a, b));
        const double deg = angle * 180 / M_PI;
        const int new_nodes = (pass == 1 || deg < 75 || (deg < 100 && chord <= 1.25 * L) || front.size() == 4) ? 0
                              : deg < 135                                                                      ? 1
                                                                                                               : 2;
        if (new_nodes == 0) {
          if (orient2(a, i, b) <= 0 || any_inside(a, i, b, pv->id, it->id, nx->id) ||
              crosses_front(a, b, pv->id, it->id, nx->id))
            continue;
          out.triangles.push_back({pv->id, it->id, nx->id});
          front.erase(it);
          cut = true;
          break;
        }
        const P2 dir_b = {(b[0] - i[0]) / lb, (b[1] - i[1]) / lb};
        const double reach = std::clamp(0.5 * (la + lb), 0.6 * L, 1.4 * L);
        std::vector<P2> at;
        for (int k = new_nodes; k >= 1; --k) {  // from the prev side to the next side
          const P2 d = rotate(dir_b, angle * double(k) / double(new_nodes + 1));
          at.push_back({i[0] + reach * d[0], i[1] + reach * d[1]});
        }
        // The fan a, at..., b around i, and the new front a - at... - b.
        std::vector<P2> chain{a};
        chain.insert(chain.end(), at.begin(), at.end());
        chain.push_back(b);
        bool ok = true;
        for (size_t k = 0; k + 1 < chain.size() && ok; ++k) ok &= orient2(i, chain[k + 1], chain[k]) > 0;
        for (const P2& q : at) ok = ok && !near_front(q, pv->id, it->id, nx->id);
        for (size_t k = 0; k + 1 < chain.size() && ok; ++k)
          ok &= !crosses_front(chain[k], chain[k + 1], pv->id, it->id, nx->id);
        for (const P2& q : at) ok = ok && !crosses_front(i, q, pv->id, it->id, nx->id);
        if (!ok) continue;
        std::vector<uint32_t> ids;
        for (const P2& q : at) ids.push_back(add_node(q, (ha + hi + hb) / 3.0));
        // Triangles around i, counter-clockwise: (i, b, next-side node), ..., (i, prev-side node, a).
        std::vector<uint32_t> fan{pv->id};
        fan.insert(fan.end(), ids.begin(), ids.end());
        fan.push_back(nx->id);
        for (size_t k = fan.size() - 1; k >= 1; --k) out.triangles.push_back({it->id, fan[k], fan[k - 1]});
        auto pos = front.erase(it);
        for (size_t k = 0; k < ids.size(); ++k) front.insert(pos, Node{ids[k], at[k]});
        cut = true;
        break;
      }
    if (!cut) return fail("ear clipping found no corner to cut");
  }
  {
    auto it = front.begin();
    const Node a = *it++, b = *it++, c = *it;
    if (orient2(a.q, b.q, c.q) <= 0) return fail("ear clipping closed with a folded triangle");
    out.triangles.push_back({a.id, b.id, c.id});
  }
  // Fair the heights of the new nodes: the average of their neighbours', a few times.
  if (!out.new_points.empty()) {
    std::vector<std::vector<uint32_t>> nb(base + out.new_points.size());
    for (const Tri& t : out.triangles)
      for (int k = 0; k < 3; ++k) nb[t[k]].push_back(t[(k + 1) % 3]), nb[t[(k + 1) % 3]].push_back(t[k]);
    for (int pass = 0; pass < 5; ++pass)
      for (uint32_t v = uint32_t(base); v < nb.size(); ++v) {
        double s = 0;
        for (uint32_t w : nb[v]) s += height[w];
        if (!nb[v].empty()) height[v] = s / double(nb[v].size());
      }
    for (size_t k = 0; k < out.new_points.size(); ++k)
      out.new_points[k] = frame.to_3d(plane_of[base + k], height[base + k]);
  }
  out.ok = true;
  return out;
}

}  // namespace vdbwrap::post
