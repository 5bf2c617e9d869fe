#include "fit/fit_surface.h"

#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <set>
#include <unordered_map>

#include "check/intersections.h"
#include "common/compressed_lists.h"
#include "common/float_round.h"
#include "common/grid_key.h"
#include "common/sorted_point_grid.h"
#include "common/cell_lists.h"
#include "common/triangle_buckets.h"
#include "common/vec.h"
#include "fit/two_sided.h"
#include "vdbwrap/errors.h"

namespace vdbwrap::fit {
using grid::Coord;

std::vector<uint32_t> invalid_triangles(const std::vector<Vec3>& points, const std::vector<Tri>& triangles,
                                        double min_area2, bool* complete) {
  std::vector<uint32_t> bad;
  for (uint32_t t = 0; t < triangles.size(); ++t) {
    const Tri& tri = triangles[t];
    if (norm(area_vector(points[tri[0]], points[tri[1]], points[tri[2]])) < min_area2) bad.push_back(t);
  }
  if (complete) *complete = bad.empty();
  if (!bad.empty()) return bad;
  // Box intersection and exact predicates, with the fast proofs in doubles first: on a
  // lattice surface most candidate pairs are exactly coplanar neighbours, slow for the exact
  // predicates alone. (The final validation still asks CGAL's own self-intersection test.)
  return check::intersecting_triangles(points, triangles, check::SoupKind::kWrap);
}

namespace {

// Nodes closer than min_separation to another node: coincident or nearly coincident
// vertices break meshers and hide intersections, so they count as invalid. The nodes'
// starting positions sit in a sorted grid (built in parallel); the few that move later go
// to a small hash grid as well (stale entries in either are harmless: distances are measured
// on current positions).
class NodeProximity {
 public:
  NodeProximity(const std::vector<Vec3>& p, double min_separation)
      : p_(p),
        sep_(min_separation),
        sep2_(min_separation * min_separation),
        start_(p, 1024 * min_separation),
        moved_(1024 * min_separation) {}
  void update(uint32_t i) {
    auto& list = moved_[moved_.cell_of(p_[i])];
    if (std::find(list.begin(), list.end(), i) == list.end()) list.push_back(i);
  }
  bool crowded(uint32_t i) const {
    const Vec3& q = p_[i];
    auto near = [&](uint32_t j) { return j != i && norm2(q - p_[j]) < sep2_; };
    if (start_.any_near(q, sep_, near)) return true;
    if (moved_.empty()) return false;
    return any_cell_near(q, sep_, moved_.inverse_cell(), [&](const GridKey& k) {
      const std::vector<uint32_t>* list = moved_.find(k);
      return list && std::any_of(list->begin(), list->end(), near);
    });
  }

 private:
  const std::vector<Vec3>& p_;
  double sep_, sep2_;
  SortedPointGrid start_;
  CellLists<> moved_;
};

// Diagonal (0-2 or 1-3) of a quad whose midpoint lies nearer the input: the split that
// deviates least from it. A split that makes a degenerate triangle is never chosen.
// `foot`: each node's nearest input triangle when it was projected (a hint: see closest()).
bool split_along_02(const std::array<uint32_t, 4>& q, const std::vector<Vec3>& p, const mesh::SurfaceIndex& input,
                    double min_area2, const std::vector<uint32_t>& foot) {
  auto area2 = [&](uint32_t a, uint32_t b, uint32_t c) { return norm(area_vector(p[a], p[b], p[c])); };
  double min02 = std::min(area2(q[0], q[1], q[2]), area2(q[0], q[2], q[3]));
  double min13 = std::min(area2(q[0], q[1], q[3]), area2(q[1], q[2], q[3]));
  if (min02 < min_area2 && min13 >= min_area2) return false;
  if (min13 < min_area2 && min02 >= min_area2) return true;
  const double d02 = input.closest((p[q[0]] + p[q[2]]) * 0.5, foot[q[0]]).squared_distance;
  // The other midpoint is only compared with it: a query bounded a little beyond d02 finds
  // its exact distance when it is that near (the two may then tie), and else 0-2 is nearer.
  // (The bounded query prunes more: choosing diagonals is a visible part of the projection.)
  mesh::SurfaceIndex::Hit near13;
  if (!input.closest_within((p[q[1]] + p[q[3]]) * 0.5, std::sqrt(d02 * (1 + 1e-9)), near13, foot[q[1]])) return true;
  const double d13 = near13.squared_distance;
  if (std::fabs(d02 - d13) <= 1e-12 * (d02 + d13)) return min02 >= min13;
  return d02 < d13;
}

}  // namespace

FittedSurface fit_to_input(const extract::LatticeSurface& surf, const grid::AdaptiveGrid& g,
                           const mesh::SurfaceIndex& input, const std::vector<FeatureCurve>& curves, const Vec3& origin,
                           const FitParams& params, ProgressSink* progress) {
  const double hf = g.fine_size();
  // Nodes: lattice nodes, then one centre node per polygon with more than four nodes.
  std::vector<Vec3> lattice;
  std::vector<double> cell_size;  // the local target size of the post-processing
  lattice.reserve(surf.nodes.size());
  for (size_t i = 0; i < surf.nodes.size(); ++i) {
    lattice.push_back(g.node_position(surf.nodes[i]));
    cell_size.push_back(surf.node_size[i] * hf);
  }
  std::vector<std::array<uint32_t, 4>> quads;
  std::vector<Tri> fans;
  for (const auto& poly : surf.polygons) {
    if (poly.size() == 4) {
      quads.push_back({poly[0], poly[1], poly[2], poly[3]});
      continue;
    }
    // An axis-aligned square with extra nodes on its edges: fan around its centre.
    Coord lo = surf.nodes[poly[0]], hi = lo;
    for (uint32_t v : poly) {
      lo = Coord::minComponent(lo, surf.nodes[v]);
      hi = Coord::maxComponent(hi, surf.nodes[v]);
    }
    Coord mid((lo.x() + hi.x()) / 2, (lo.y() + hi.y()) / 2, (lo.z() + hi.z()) / 2);
    uint32_t centre = uint32_t(lattice.size());
    lattice.push_back(g.node_position(mid));
    cell_size.push_back(std::max({hi.x() - lo.x(), hi.y() - lo.y(), hi.z() - lo.z()}) * hf);
    for (size_t k = 0; k < poly.size(); ++k) fans.push_back({centre, poly[k], poly[(k + 1) % poly.size()]});
  }
  const size_t n = lattice.size();

  // Untangling before projection: nearest-point projection of a voxel staircase folds at
  // every step, while projection of a smooth surface near the input does not. So the
  // lattice surface is smoothed first (umbrella operator over polygon edges; Taubin's
  // non-shrinking variant measured worse on the corpus: it untangles less), then each
  // smoothed node goes to its nearest input point, stopped a small offset short of it on
  // its lattice node's side, so sheets wrapped around a zero-thickness input never coincide.
  CompressedLists neighbours = compressed_lists(n, [&](auto&& emit) {
    auto link = [&](uint32_t a, uint32_t b) { emit(a, b), emit(b, a); };
    for (const auto& poly : surf.polygons)
      for (size_t k = 0; k < poly.size(); ++k)
        if (poly[k] < poly[(k + 1) % poly.size()] || poly.size() != 4) link(poly[k], poly[(k + 1) % poly.size()]);
    for (const Tri& f : fans) link(f[0], f[1]);
  });
  sort_and_unique(neighbours);
  std::vector<Vec3> smoothed = lattice, next(n);
  for (int it = 0; it < params.presmooth_iterations; ++it) {
    tbb::parallel_for(tbb::blocked_range<size_t>(0, n, 1024), [&](const tbb::blocked_range<size_t>& r) {
      for (size_t i = r.begin(); i != r.end(); ++i) {
        Vec3 avg{0, 0, 0};
        for (uint32_t j : neighbours[i]) avg = avg + smoothed[j];
        avg = avg * (1.0 / double(std::max<size_t>(1, neighbours[i].size())));
        next[i] = lerp(smoothed[i], avg, 0.5);
      }
    });
    smoothed.swap(next);
  }

  if (progress) progress->progress("project", 0.0, "projecting " + std::to_string(n) + " nodes onto the input");
  const double offset = params.surface_offset * hf;
  // The nearest input point of `from`, `offset` off the input on node i's side (the side
  // its lattice node is on, judged against the plane of the triangle hit: smoothing may
  // have carried `from` across a thin sheet).
  // Each node's nearest triangle from its last projection: the next query for the node
  // (relaxing moves it a little) and the quads' diagonal choice start from it.
  std::vector<uint32_t> foot(n, UINT32_MAX);
  // The lattice surface's normal at each node, the way its sheet faces.
  std::vector<Vec3> facing(n, Vec3{0, 0, 0});
  for (const auto& q : quads) {
    const Vec3 a = cross(lattice[q[2]] - lattice[q[0]], lattice[q[3]] - lattice[q[1]]);
    for (uint32_t v : q) facing[v] = facing[v] + a;
  }
  for (const Tri& f : fans) {
    const Vec3 a = area_vector(lattice[f[0]], lattice[f[1]], lattice[f[2]]);
    for (uint32_t v : f) facing[v] = facing[v] + a;
  }
  TwoSidedParams two_sided_params;
  two_sided_params.cell = hf;
  two_sided_params.offset = offset;
  TwoSidedSheets sheets(n, two_sided_params);
  auto project_on_side = [&](size_t i, const Vec3& from) {
    auto hit = input.closest(from, foot[i]);
    foot[i] = hit.triangle;
    const double lattice_side = dot(lattice[i] - hit.point, hit.normal);
    const Vec3 fallback = lattice_side >= 0 ? hit.normal : hit.normal * -1.0;
    Vec3 away = from - hit.point;
    double d = norm(away);
    const bool same_side = (dot(away, hit.normal) >= 0) == (lattice_side >= 0);
    Vec3 dir = (d > 1e-3 * offset && same_side) ? away * (1.0 / d) : fallback;
    if (norm2(dir) == 0) {  // a degenerate input triangle: away from the input's point nearest the lattice node
      const auto foot = input.closest(lattice[i]);
      dir = (lattice[i] - foot.point) * (1.0 / std::sqrt(foot.squared_distance));
    }
    Vec3 t = hit.point + dir * offset;
    sheets.record(i, hit.point, hit.triangle, hit.normal, dir, facing[i]);
    if (norm(t - lattice[i]) > 3.0 * g.base_size()) t = lattice[i], sheets.forget(i);  // a wild move: keep it off
    return t;
  };
  // A lattice node within the offset of the input stays where it is. (Asked as "is the input
  // that near?", which is cheap for so small a radius: the nearest point itself is needed only
  // for the others, from their smoothed positions.)
  std::vector<Vec3> target(n);
  std::vector<uint8_t> on_input(n);
  tbb::parallel_for(tbb::blocked_range<size_t>(0, n, 256), [&](const tbb::blocked_range<size_t>& r) {
    for (size_t i = r.begin(); i != r.end(); ++i) {
      on_input[i] = input.within(lattice[i], offset);
      target[i] = on_input[i] ? lattice[i] : project_on_side(i, smoothed[i]);
    }
  });
  if (progress && progress->cancelled()) throw Error(ErrorKind::Cancelled, "cancelled");

  // Feature snapping: chains of wrap edges traced along the feature curves and moved onto
  // them; then the nodes around them relax onto the faces on either side (smoothing with
  // re-projection), the snapped nodes held fixed.
  FittedSurface out;
  std::vector<uint8_t> snapped(n, 0);
  std::set<std::pair<uint32_t, uint32_t>> traced;
  sheets.classify();
  // The wrap passes around the rim of a two-sided sheet (a scan's jagged hole rims): chains
  // traced there on either sheet hold the other sheet's nodes back. Those rims are left to the
  // projection.
  std::vector<FeatureCurve> one_sided_curves;
  out.rim_of_two_sided_sheet.assign(curves.size(), 0);
  if (params.two_sided_sheets)
    for (size_t ci = 0; ci < curves.size(); ++ci) {
      const FeatureCurve& c = curves[ci];
      if (c.boundary && sheets.two_sided_along(c.points))
        out.rim_of_two_sided_sheet[ci] = 1;
      else
        one_sided_curves.push_back(c);
    }
  const std::vector<FeatureCurve>& traced_curves = params.two_sided_sheets ? one_sided_curves : curves;
  if (!traced_curves.empty()) {
    if (progress)
      progress->progress("project", 0.05, "snapping to " + std::to_string(curves.size()) + " feature curves");
    // The chosen volume next to a concave crease is often coarse (only cells the input
    // passes through are refined), so nodes along it can be a base cell apart: the trace
    // radius covers that.
    const double trace_radius = std::max(2.0 * hf, 1.5 * g.base_size());
    WrapGraph graph;
    graph.neighbours = compressed_lists(n, [&](auto&& emit) {  // each node's neighbours, then its diagonals
      for (uint32_t i = 0; i < n; ++i)
        for (uint32_t w : neighbours[i]) emit(i, w);
      for (const auto& q : quads) emit(q[0], q[2]), emit(q[2], q[0]), emit(q[1], q[3]), emit(q[3], q[1]);
    });
    // Across a crack the faces stand a gap behind or beyond each other: one side's rim can hide
    // a crease the other side's face makes.
    const double view = std::max(offset, 4 * params.gap);
    auto reachable = [&](const Vec3& from, const Vec3& to) { return input.in_view(from, to, view); };
    for (const auto& [a, b] : snap_to_curves(traced_curves, graph, lattice, target, snapped, trace_radius,
                                             std::max(8.0 * hf, 2.0 * trace_radius), offset, out.snap, reachable))
      traced.insert({std::min(a, b), std::max(a, b)});
    // Relax the unsnapped nodes within three rings of a snapped one.
    std::vector<uint8_t> relax(n, 0);
    std::vector<uint32_t> ring;
    for (uint32_t i = 0; i < n; ++i)
      if (snapped[i]) ring.push_back(i);
    for (int r = 0; r < 3; ++r) {
      std::vector<uint32_t> next_ring;
      for (uint32_t v : ring)
        for (uint32_t w : neighbours[v])
          if (!snapped[w] && !relax[w]) relax[w] = 1, next_ring.push_back(w);
      ring.swap(next_ring);
    }
    std::vector<uint32_t> relaxed;
    for (uint32_t i = 0; i < n; ++i)
      if (relax[i] && !on_input[i]) relaxed.push_back(i);
    for (int it = 0; it < 4; ++it) {
      std::vector<Vec3> moved(relaxed.size());
      tbb::parallel_for(tbb::blocked_range<size_t>(0, relaxed.size(), 256), [&](const tbb::blocked_range<size_t>& r) {
        for (size_t k = r.begin(); k != r.end(); ++k) {
          uint32_t i = relaxed[k];
          Vec3 avg{0, 0, 0};
          for (uint32_t j : neighbours[i]) avg = avg + target[j];
          avg = avg * (1.0 / double(std::max<size_t>(1, neighbours[i].size())));
          moved[k] = project_on_side(i, avg);
        }
      });
      for (size_t k = 0; k < relaxed.size(); ++k) target[relaxed[k]] = moved[k];
    }
  }

  const double min_area2 = 1e-6 * hf * hf;
  out.triangles = fans;
  out.triangles.reserve(fans.size() + 2 * quads.size());
  // Traced feature edges stay edges: a quad whose diagonal was traced is split along it.
  // A split that puts two traced sides into one triangle is avoided: their three nodes lie on
  // one curve, so the triangle would be flat.
  auto is_traced = [&](uint32_t a, uint32_t b) { return traced.count({std::min(a, b), std::max(a, b)}) > 0; };
  // Decided in parallel: the traced edges (read only) and the input's choice of diagonal (two
  // nearest-point queries per quad); the triangles are then appended in quad order.
  std::vector<uint8_t> split_02(quads.size());
  tbb::parallel_for(tbb::blocked_range<size_t>(0, quads.size(), 512), [&](const tbb::blocked_range<size_t>& r) {
    for (size_t k = r.begin(); k != r.end(); ++k) {
      const auto& q = quads[k];
      const bool side[4] = {is_traced(q[0], q[1]), is_traced(q[1], q[2]), is_traced(q[2], q[3]), is_traced(q[3], q[0])};
      bool along02 = is_traced(q[0], q[2]) || (side[0] && side[3]) || (side[1] && side[2]);
      bool along13 = is_traced(q[1], q[3]) || (side[0] && side[1]) || (side[2] && side[3]);
      if (along02 == along13) along02 = along13 = false;  // both or neither: the input decides
      split_02[k] = along02 || (!along13 && split_along_02(q, target, input, min_area2, foot));
    }
  });
  for (size_t k = 0; k < quads.size(); ++k) {
    const auto& q = quads[k];
    if (split_02[k]) {
      out.triangles.push_back({q[0], q[1], q[2]});
      out.triangles.push_back({q[0], q[2], q[3]});
    } else {
      out.triangles.push_back({q[0], q[1], q[3]});
      out.triangles.push_back({q[1], q[2], q[3]});
    }
  }

  // Validity loop: every node starts at its target; nodes of offending triangles move half
  // way back toward the lattice, where the surface is valid by construction. After one full
  // check, only the triangles around moved nodes are tested again (against all others), so
  // the loop can afford many short rounds; a full CGAL check confirms the end.
  // Checked in output (world) coordinates: the translation back from the local frame rounds,
  // and only what is written counts.
  std::vector<double> t(n, 1.0);
  std::vector<Vec3>& p = out.points;
  auto world = [&](const Vec3& local) {
    Vec3 w = local + origin;
    if (params.float_coordinates) w = round_to_float(w);  // not double(float(x)): see float_round.h
    return w;
  };
  p.resize(n);
  for (size_t i = 0; i < n; ++i) p[i] = world(target[i]);
  std::vector<uint8_t> strikes(n, 0);
  const CompressedLists vertex_triangles = vertex_triangle_lists(n, out.triangles);

  // Nodes on a feature curve stay on it: an offending triangle moves its other nodes first.
  auto flag_triangle = [&](uint32_t f, std::vector<uint8_t>& flag) {
    const Tri& tri = out.triangles[f];
    bool free_can_move = false;
    for (uint32_t v : tri) free_can_move |= !snapped[v] && t[v] > 0;
    for (uint32_t v : tri)
      if (!free_can_move || !snapped[v]) flag[v] = 1;
  };
  NodeProximity nodes(p, 1e-3 * hf);
  // A full check that came back complete (intersections tested too, not only small triangles)
  // and clean stays true while the local checks below keep it so: they test every triangle
  // around every moved node against all others, and nothing else moves. So the loop needs
  // one complete check, not one more after the last round (a third of a large wrap's loop).
  bool complete = false;
  auto full_check = [&](std::vector<uint8_t>& flag) {
    tbb::parallel_for(tbb::blocked_range<uint32_t>(0, uint32_t(n), 4096), [&](const tbb::blocked_range<uint32_t>& r) {
      for (uint32_t i = r.begin(); i != r.end(); ++i)
        if (nodes.crowded(i)) flag[i] = 1;  // each task writes its own range of flags
    });
    for (uint32_t f : invalid_triangles(p, out.triangles, min_area2, &complete)) flag_triangle(f, flag);
  };
  TriangleBuckets buckets(p, out.triangles, 2.0 * g.base_size());
  tbb::enumerable_thread_specific<std::pair<std::vector<uint32_t>, uint32_t>> bucket_marks;  // see for_each_in_box
  tbb::enumerable_thread_specific<std::vector<uint32_t>> offending;  // triangles the local check found
  auto local_check = [&](const std::vector<uint32_t>& moved, std::vector<uint8_t>& flag) {
    for (uint32_t v : moved) nodes.update(v);
    for (uint32_t v : moved)
      if (nodes.crowded(v)) flag[v] = 1;
    std::vector<uint32_t> around;
    for (uint32_t v : moved) around.insert(around.end(), vertex_triangles[v].begin(), vertex_triangles[v].end());
    std::sort(around.begin(), around.end());
    around.erase(std::unique(around.begin(), around.end()), around.end());
    for (uint32_t f : around) buckets.update(f);
    // The tests in parallel (the buckets only read, each thread with its own marks); the
    // offending triangles are flagged afterwards, so the flags do not depend on the threads.
    tbb::parallel_for(tbb::blocked_range<size_t>(0, around.size(), 32), [&](const tbb::blocked_range<size_t>& r) {
      auto& [seen, stamp] = bucket_marks.local();
      std::vector<uint32_t>& bad = offending.local();
      for (size_t i = r.begin(); i != r.end(); ++i) {
        const uint32_t f = around[i];
        const Tri& tri = out.triangles[f];
        if (norm(area_vector(p[tri[0]], p[tri[1]], p[tri[2]])) < min_area2 || check::triangle_is_degenerate(p, tri)) {
          bad.push_back(f);
          continue;
        }
        buckets.for_each_in_box(buckets.box(f), seen, stamp, [&](uint32_t other) {
          if (other != f && !check::triangle_is_degenerate(p, out.triangles[other]) &&
              check::triangle_pair_intersects(p, tri, out.triangles[other]))
            bad.push_back(f), bad.push_back(other);
        });
      }
    });
    for (std::vector<uint32_t>& bad : offending) {
      for (uint32_t f : bad) flag_triangle(f, flag);
      bad.clear();
    }
  };

  // A node flagged again and again sits in a tangle that halving resolves only slowly:
  // after a few strikes it goes straight back to its lattice position.
  const int max_rounds = params.validity_rounds, give_up_halving = std::min(200, max_rounds / 2),
            strikes_to_lattice = 4;
  std::vector<uint8_t> flag(n, 0);
  full_check(flag);
  int round = 0;
  bool valid = false;
  for (; round < max_rounds; ++round) {
    if (progress && progress->cancelled()) throw Error(ErrorKind::Cancelled, "cancelled");
    size_t flagged = size_t(std::count(flag.begin(), flag.end(), 1));
    if (flagged == 0 && !complete) {
      full_check(flag);  // the last full check tested small triangles only: the whole surface now
      flagged = size_t(std::count(flag.begin(), flag.end(), 1));
    }
    if (flagged == 0) {
      valid = true;
      break;
    }
    if (progress && (round < 10 || round % 10 == 0))
      progress->progress(
          "project", std::min(0.95, 0.1 + round * 0.01),
          "untangling round " + std::to_string(round + 1) + ": " + std::to_string(flagged) + " nodes to pull back");
    std::vector<uint32_t> moved;
    for (uint32_t i = 0; i < n; ++i) {
      if (!flag[i]) continue;
      flag[i] = 0;
      if (t[i] == 0.0) continue;
      // Two-sided: farther off the input on its own side first (not back to the staircase).
      if (params.two_sided_sheets && !snapped[i] && sheets.raise(i, target[i])) {
        p[i] = world(lerp(lattice[i], target[i], t[i]));
        moved.push_back(i);
        continue;
      }
      ++strikes[i];
      t[i] = (t[i] < 1.0 / 64 || round >= give_up_halving || strikes[i] >= strikes_to_lattice) ? 0.0 : t[i] * 0.5;
      p[i] = world(lerp(lattice[i], target[i], t[i]));
      moved.push_back(i);
    }
    local_check(moved, flag);
  }
  // Coincident nodes are beyond the repair (it moves triangles, and welding them on output
  // would pinch the surface): when the rounds ran out, a node still crowded steps a tenth of
  // its way back toward its lattice position (far more than the crowding distance; nodes are
  // distinct there), a few times if need be. A larger step makes intersections the repair
  // then has to fix (measured: all the way back broke busted.STL at 0 rounds).
  if (!valid)
    for (int step = 0; step < 4; ++step) {
      size_t moved = 0;
      for (uint32_t i = 0; i < n; ++i)
        if (t[i] > 0 && nodes.crowded(i)) {
          t[i] = std::max(0.0, t[i] - 0.1);
          p[i] = world(lerp(lattice[i], target[i], t[i]));
          nodes.update(i);
          ++moved;
        }
      if (moved == 0) break;
    }
  out.validity_rounds = round;
  out.valid = valid;
  if (!valid && progress)
    progress->progress("project", 1.0, "the validity loop ran out of rounds: intersections left for the repair");
  for (size_t i = 0; i < n; ++i)
    if (t[i] < 1.0 && norm2(target[i] - lattice[i]) > 0) ++out.held_back, out.held_back_points.push_back(p[i]);
  if (progress) progress->progress("project", 1.0, std::to_string(out.held_back) + " nodes held back to stay valid");
  out.two_sided = sheets.take_stats();
  out.snapped = std::move(snapped);
  out.cell_size = std::move(cell_size);
  out.feature_edges.assign(traced.begin(), traced.end());
  return out;
}

}  // namespace vdbwrap::fit
