#include "post/remesh.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <unordered_map>
#include <unordered_set>

#include "check/intersections.h"
#include "common/compressed_lists.h"
#include "common/edge_key.h"
#include "common/float_round.h"
#include "common/grid_key.h"
#include "common/cell_lists.h"
#include "common/triangle_buckets.h"
#include "common/vec.h"
#include "post/region_fill.h"
#include "vdbwrap/errors.h"

namespace vdbwrap::post {
namespace {

uint64_t directed_key(uint32_t a, uint32_t b) { return (uint64_t(a) << 32) | b; }

// Points where a triangle set is measured: its corners, edge midpoints and centroids, each once.
std::vector<Vec3> samples_of(const std::vector<Vec3>& p, const std::vector<Tri>& tris) {
  std::vector<Vec3> out;
  std::unordered_set<uint32_t> corners;
  std::unordered_set<uint64_t> edges;
  for (const Tri& t : tris) {
    for (int k = 0; k < 3; ++k) {
      if (corners.insert(t[k]).second) out.push_back(p[t[k]]);
      if (edges.insert(edge_key(t[k], t[(k + 1) % 3])).second) out.push_back((p[t[k]] + p[t[(k + 1) % 3]]) * 0.5);
    }
    out.push_back((p[t[0]] + p[t[1]] + p[t[2]]) * (1.0 / 3.0));
  }
  return out;
}

// A region to rebuild: its triangles, the problem the fills solve, and the map back.
struct Region {
  std::vector<uint32_t> triangles;  // sorted
  std::vector<uint32_t> node_ids;   // problem node -> mesh vertex (contour, then fixed)
  std::vector<uint32_t> ring;       // live triangles outside the region sharing a vertex with it
  RegionProblem problem;
  Substrate substrate;
  double cell = 0;             // smallest cell size at its nodes
  double old_far = -1;         // farthest sample of the replaced surface from the input (once known)
  std::vector<Vec3> old_feet;  // the input points nearest those samples (known with old_far)
  RegionFill on_input, by_ears;
};

class Remesher {
 public:
  Remesher(PostSurface& s, const std::vector<uint8_t>& flags, const QualityReference& ref,
           const prep::PreparedInput& input, const RemeshParams& params)
      : s_(s),
        ref_(ref),
        input_(input),
        prm_(params),
        flags_(flags),
        buckets_(s.points, s.triangles, 2.0 * *std::max_element(s.cell_size.begin(), s.cell_size.end())) {
    alive_.assign(s.triangles.size(), 1);
    deviation_.assign(s.triangles.size(), -1);
    tbb::parallel_for(size_t(0), s.triangles.size(), [&](size_t f) {
      if (!(flags[f] & kNormalDeviation)) return;
      const Tri& t = s.triangles[f];
      const double cell = std::min({s.cell_size[t[0]], s.cell_size[t[1]], s.cell_size[t[2]]});
      deviation_[f] = float(normal_deviation_deg(s.points[t[0]], s.points[t[1]], s.points[t[2]], cell, ref));
    });
    for (const auto& [a, b] : s.feature_edges) feature_edges_.insert(edge_key(a, b));
    vf_ = to_vectors(vertex_triangle_lists(s.points.size(), s.triangles));
    // Feature samples bucketed, to find those near a region.
    features_ = CellLists<>(2.0 * *std::max_element(s.cell_size.begin(), s.cell_size.end()));
    for (uint32_t i = 0; i < ref.feature_samples.size(); ++i) features_.add(ref.feature_samples[i] + ref.origin, i);
  }

  RemeshStats run(ProgressSink* progress) {
    for (int round = 0; round < prm_.rounds; ++round) {
      if (progress && progress->cancelled()) throw Error(ErrorKind::Cancelled, "cancelled");
      const int rings = round == 1 ? 2 : 1;
      std::vector<Region> regions = gather(rings);
      if (regions.empty()) break;
      if (progress)
        progress->progress(
            "remesh", double(round) / prm_.rounds,
            "round " + std::to_string(round + 1) + ": rebuilding " + std::to_string(regions.size()) + " bad regions");
      stats_.regions += regions.size();
      tbb::parallel_for(size_t(0), regions.size(), [&](size_t i) {
        regions[i].on_input = fill_on_substrate(regions[i].problem, regions[i].substrate);
        regions[i].by_ears = fill_by_ear_clipping(regions[i].problem);
      });
      std::vector<std::array<Verdict, 2>> verdicts(regions.size());
      tbb::parallel_for(size_t(0), regions.size(), [&](size_t i) {
        if (regions[i].on_input.ok) verdicts[i][0] = precheck(regions[i], regions[i].on_input);
        if (regions[i].by_ears.ok) verdicts[i][1] = precheck(regions[i], regions[i].by_ears);
      });
      const size_t rebuilt_before = stats_.on_input + stats_.ear_clipping;
      for (size_t i = 0; i < regions.size(); ++i) {
        if (progress && (i & 63) == 63 && progress->cancelled()) throw Error(ErrorKind::Cancelled, "cancelled");
        settle(regions[i], verdicts[i]);
      }
      // A round that rebuilt under a tenth of its regions (a wrap bridging gaps everywhere)
      // would not do better with bigger regions: stop there.
      if (10 * (stats_.on_input + stats_.ear_clipping - rebuilt_before) < regions.size()) break;
    }
    compact();
    return stats_;
  }

 private:
  // Bad: a trigger kind, normals only when very poor (beyond the trigger angle).
  bool bad_by(uint8_t flags, double deviation) const {
    if (flags & prm_.triggers & ~kNormalDeviation) return true;
    return (flags & prm_.triggers & kNormalDeviation) && deviation > prm_.trigger_normal_deviation_deg;
  }
  bool is_bad(uint32_t f) const { return bad_by(flags_[f], deviation_[f]); }
  Vec3 centroid(uint32_t f) const {
    const Tri& t = s_.triangles[f];
    return (s_.points[t[0]] + s_.points[t[1]] + s_.points[t[2]]) * (1.0 / 3.0);
  }

  // Regions of this round: bad triangles near each other (sharing vertices, within a few
  // cells of the first), grown by `rings` rings, kept apart by a ring of untouched triangles.
  std::vector<Region> gather(int rings) {
    std::vector<Region> out;
    std::vector<uint8_t> taken(s_.triangles.size(), 0);
    std::vector<uint32_t> bad;
    for (uint32_t f = 0; f < s_.triangles.size(); ++f)
      if (alive_[f] && is_bad(f) && !tried_.count(signature_of(f, rings))) bad.push_back(f);
    for (uint32_t seed : bad) {
      if (taken[seed]) continue;
      const Tri& st = s_.triangles[seed];
      const double reach = 3.0 * std::max({s_.cell_size[st[0]], s_.cell_size[st[1]], s_.cell_size[st[2]]});
      const Vec3 at = centroid(seed);
      std::vector<uint32_t> core{seed};
      const uint32_t in = next_mark();  // marks_[g] == in: g is in the core
      marks_[seed] = in;
      for (size_t k = 0; k < core.size() && core.size() < prm_.max_region_triangles; ++k)
        for (uint32_t v : s_.triangles[core[k]])
          for (uint32_t g : vf_[v])
            if (marks_[g] != in && is_bad(g) && !taken[g] && core.size() < prm_.max_region_triangles &&
                norm(centroid(g) - at) < reach)
              marks_[g] = in, core.push_back(g);
      // Next to another region: a later round. Checked after each growth step (each one only
      // adds triangles), so a clash costs no more growth than it takes to find it.
      auto clashes = [&](const std::vector<uint32_t>& set) {
        return std::any_of(set.begin(), set.end(), [&](uint32_t f) { return taken[f] != 0; });
      };
      std::vector<uint32_t> region = core;
      bool clash = false;
      for (int r = 0; r < rings && !clash; ++r) clash = clashes(region = grow_marked(region));
      if (clash || clashes(region = close_pockets(region))) continue;
      tried_.insert(signature_of(seed, rings));
      const std::vector<uint32_t> around = grow_marked(region);
      for (uint32_t f : around) taken[f] = 1;
      Region reg;
      reg.triangles = region;
      out.push_back(std::move(reg));
    }
    // Each region described on its own (the mesh does not change meanwhile).
    std::vector<std::string> why(out.size());
    tbb::parallel_for(size_t(0), out.size(), [&](size_t i) {
      if (!describe(out[i], why[i])) out[i].triangles.clear();
    });
    std::vector<Region> kept;
    for (size_t i = 0; i < out.size(); ++i) {
      if (out[i].triangles.empty())
        ++stats_.refusals["region: " + why[i]];
      else
        kept.push_back(std::move(out[i]));
    }
    return kept;
  }

  // A triangle tried with this many rings (and not rebuilt) is not tried again the same way.
  uint64_t signature_of(uint32_t f, int rings) const { return (uint64_t(f) << 2) | uint64_t(rings); }

  // `set` (sorted) plus the pockets it encloses: groups of other triangles, connected through
  // edges, that reach nothing but the set (a ring-shaped region becomes a disc).
  std::vector<uint32_t> close_pockets(const std::vector<uint32_t>& set) {
    // Marks instead of hash sets (gathering is serial, and its sets were most of it).
    const uint32_t in = next_mark(), seen = next_mark();
    for (uint32_t f : set) marks_[f] = in;
    auto is_in = [&](uint32_t f) { return marks_[f] == in; };
    auto was_seen = [&](uint32_t f) { return marks_[f] == seen; };
    std::vector<uint32_t> out = set;
    const size_t limit = set.size();
    for (uint32_t f : set)
      for (uint32_t v : s_.triangles[f])
        for (uint32_t start : vf_[v]) {
          if (is_in(start) || was_seen(start)) continue;
          std::vector<uint32_t> pocket{start};
          marks_[start] = seen;
          bool open = false;
          for (size_t k = 0; k < pocket.size() && !open; ++k) {
            const Tri& t = s_.triangles[pocket[k]];
            for (int e = 0; e < 3 && !open; ++e)
              for (uint32_t g : vf_[t[e]]) {
                const Tri& o = s_.triangles[g];
                const uint32_t w = t[(e + 1) % 3];
                if (is_in(g) || was_seen(g) || !(o[0] == w || o[1] == w || o[2] == w)) continue;
                marks_[g] = seen;
                pocket.push_back(g);
                if (pocket.size() > limit) open = true;
              }
          }
          if (!open) out.insert(out.end(), pocket.begin(), pocket.end());
        }
    std::sort(out.begin(), out.end());
    return out;
  }

  // grow() for gathering, which is serial: marks drop the repeats before the sort (each
  // triangle is listed from the fans of up to three vertices, and sorting every listing was
  // most of gathering).
  std::vector<uint32_t> grow_marked(const std::vector<uint32_t>& set) {
    const uint32_t in = next_mark();
    std::vector<uint32_t> out;
    auto add = [&](uint32_t g) {
      if (marks_[g] != in) marks_[g] = in, out.push_back(g);
    };
    for (uint32_t f : set) add(f);
    for (uint32_t f : set)
      for (uint32_t v : s_.triangles[f])
        for (uint32_t g : vf_[v]) add(g);
    std::sort(out.begin(), out.end());
    return out;
  }

  // `set` plus every live triangle sharing a vertex with it, sorted.
  std::vector<uint32_t> grow(const std::vector<uint32_t>& set) const {
    std::vector<uint32_t> out = set;
    for (uint32_t f : set)
      for (uint32_t v : s_.triangles[f])
        for (uint32_t g : vf_[v]) out.push_back(g);
    std::sort(out.begin(), out.end());
    out.erase(std::unique(out.begin(), out.end()), out.end());
    return out;
  }

  // The region's contour, kept nodes and edges, the surface it replaces and the input under
  // it. False (with the reason) when it is not a disc.
  bool describe(Region& reg, std::string& why) const {
    std::sort(reg.triangles.begin(), reg.triangles.end());
    std::unordered_set<uint64_t> half;
    std::unordered_set<uint64_t> edges;
    std::vector<uint32_t> verts;
    for (uint32_t f : reg.triangles)
      for (int k = 0; k < 3; ++k) {
        const uint32_t u = s_.triangles[f][k], v = s_.triangles[f][(k + 1) % 3];
        half.insert(directed_key(u, v));
        edges.insert(edge_key(u, v));
        verts.push_back(u);
      }
    std::sort(verts.begin(), verts.end());
    verts.erase(std::unique(verts.begin(), verts.end()), verts.end());
    // The boundary: half-edges whose twin is not in the region.
    std::unordered_map<uint32_t, uint32_t> next;
    for (uint32_t f : reg.triangles)
      for (int k = 0; k < 3; ++k) {
        const uint32_t u = s_.triangles[f][k], v = s_.triangles[f][(k + 1) % 3];
        if (half.count(directed_key(v, u))) continue;
        if (!next.emplace(u, v).second) return why = "its boundary touches itself", false;
      }
    if (next.size() < 3) return why = "no boundary (a whole closed piece)", false;
    std::vector<uint32_t> loop{std::min_element(next.begin(), next.end())->first};
    while (loop.size() <= next.size()) {
      auto it = next.find(loop.back());
      if (it == next.end()) return why = "open boundary", false;
      if (it->second == loop.front()) break;
      loop.push_back(it->second);
    }
    if (loop.size() != next.size()) return why = "more than one boundary loop", false;
    if (long(verts.size()) - long(edges.size()) + long(reg.triangles.size()) != 1) return why = "not a disc", false;

    // Problem numbering: contour, then the kept (locked) nodes inside; the rest go.
    std::unordered_map<uint32_t, uint32_t> index;
    RegionProblem& pr = reg.problem;
    for (uint32_t v : loop)
      index[v] = uint32_t(reg.node_ids.size()), reg.node_ids.push_back(v), pr.contour.push_back(s_.points[v]);
    std::unordered_set<uint32_t> on_loop(loop.begin(), loop.end());
    // Snapped nodes inside stay, unless one almost on another (where feature curves meet):
    // those make the slivers, and the region's check keeps the edges where they were.
    for (uint32_t v : verts) {
      if (on_loop.count(v) || !s_.locked[v]) continue;
      bool crowded = false;
      for (uint32_t w : reg.node_ids) crowded |= norm(s_.points[v] - s_.points[w]) < 0.2 * s_.cell_size[v];
      if (crowded) continue;
      index[v] = uint32_t(reg.node_ids.size());
      reg.node_ids.push_back(v);
      pr.fixed.push_back(s_.points[v]);
    }
    // Edges traced along the feature curves stay, between kept nodes.
    for (uint64_t e : edges) {
      const uint32_t u = uint32_t(e >> 32), v = uint32_t(e & 0xffffffffu);
      const bool contour_edge = (next.count(u) && next.at(u) == v) || (next.count(v) && next.at(v) == u);
      if (contour_edge || !feature_edges_.count(e) || !index.count(u) || !index.count(v)) continue;
      pr.fixed_edges.push_back({index.at(u), index.at(v)});
    }
    std::sort(pr.fixed_edges.begin(), pr.fixed_edges.end());
    std::unordered_map<uint32_t, uint32_t> old_index;
    Vec3 area{0, 0, 0};
    for (uint32_t f : reg.triangles) {
      Tri t;
      for (int k = 0; k < 3; ++k) {
        auto [it, added] = old_index.emplace(s_.triangles[f][k], uint32_t(pr.old_points.size()));
        if (added) pr.old_points.push_back(s_.points[s_.triangles[f][k]]);
        t[k] = it->second;
      }
      pr.old_triangles.push_back(t);
      area = area + area_vector(pr.old_points[t[0]], pr.old_points[t[1]], pr.old_points[t[2]]);
    }
    if (norm(area) == 0) return why = "no normal", false;
    pr.normal = normalized(area);
    reg.cell = INFINITY;
    for (uint32_t v : verts) reg.cell = std::min(reg.cell, s_.cell_size[v]);
    double contour_length = 0;
    for (size_t i = 0; i < loop.size(); ++i)
      contour_length += norm(s_.points[loop[(i + 1) % loop.size()]] - s_.points[loop[i]]);
    pr.target = std::max(contour_length / double(loop.size()), 0.5 * reg.cell);
    reg.ring = grow(reg.triangles);
    reg.ring.erase(
        std::remove_if(reg.ring.begin(), reg.ring.end(),
                       [&](uint32_t f) { return std::binary_search(reg.triangles.begin(), reg.triangles.end(), f); }),
        reg.ring.end());

    // The substrate: the input triangles nearest to points spread over the region.
    std::vector<uint32_t> hits;
    for (const Tri& t : pr.old_triangles) {
      const Vec3 &a = pr.old_points[t[0]], &b = pr.old_points[t[1]], &c = pr.old_points[t[2]];
      for (const Vec3& q : {a, (a + b + c) * (1.0 / 3.0), (a + b) * 0.5})
        hits.push_back(ref_.closest(q - ref_.origin).triangle);
    }
    std::sort(hits.begin(), hits.end());
    hits.erase(std::unique(hits.begin(), hits.end()), hits.end());
    std::unordered_map<uint32_t, uint32_t> sub_index;
    for (uint32_t t : hits) {
      Tri local;
      for (int k = 0; k < 3; ++k) {
        const uint32_t g = input_.mesh.triangles[t][k];
        auto [it, added] = sub_index.emplace(g, uint32_t(reg.substrate.points.size()));
        if (added) reg.substrate.points.push_back(input_.mesh.points[g] + ref_.origin);
        local[k] = it->second;
      }
      reg.substrate.triangles.push_back(local);
    }
    reg.substrate.offset = prm_.offset;
    reg.substrate.flat_angle_deg = prm_.flat_angle_deg;
    return true;
  }

  // A fill's checks that do not depend on the other regions of its round (they are kept
  // apart by a ring of untouched triangles: no node, no triangle and no ring in common), so
  // they run for all regions in parallel; the check against the rest of the surface, which
  // the round's earlier fills change, and the change itself stay in region order.
  struct Verdict {
    std::string why;                 // the first failed check before the surface test, or empty
    std::string far_why;             // the first failed distance check, or empty
    std::vector<Vec3> new_points;    // as written (rounded when asked)
    std::vector<uint8_t> new_flags;  // per fill triangle
    std::vector<float> new_deviation;
  };

  // Keeps the first fill that passes every check, or leaves the region as it was.
  void settle(Region& reg, const std::array<Verdict, 2>& verdicts) {
    for (int way = 0; way < 2; ++way) {
      const RegionFill& fill = way == 0 ? reg.on_input : reg.by_ears;
      const std::string name = way == 0 ? "on the input: " : "ear clipping: ";
      if (!fill.ok) {
        ++stats_.refusals[name + fill.why];
        continue;
      }
      std::string why;
      if (accept(reg, fill, verdicts[size_t(way)], why)) {
        ++(way == 0 ? stats_.on_input : stats_.ear_clipping);
        return;
      }
      ++stats_.refusals[name + why];
    }
    ++stats_.restored;
  }

  // The checks of `fill` that read only the region, its ring and the input (read only: safe
  // in parallel). The fill's own numbering: region nodes (reg.node_ids), then its new nodes.
  Verdict precheck(Region& reg, const RegionFill& fill) const {
    Verdict out;
    const RegionProblem& pr = reg.problem;
    const uint32_t nc = uint32_t(pr.contour.size()), base = uint32_t(reg.node_ids.size());
    out.new_points = fill.new_points;
    for (Vec3& q : out.new_points) {
      if (prm_.float_coordinates) q = round_to_float(q);
      if (!std::isfinite(q[0]) || !std::isfinite(q[1]) || !std::isfinite(q[2]))
        return out.why = "a new node is not finite", out;
    }
    const std::vector<Tri>& tris = fill.triangles;

    // Topology: the fill's border is the contour, in its direction; inside, every edge has a
    // triangle on each side; no edge the mesh already has elsewhere.
    std::unordered_map<uint64_t, int> directed;
    for (const Tri& t : tris)
      for (int k = 0; k < 3; ++k) {
        if (t[k] == t[(k + 1) % 3]) return out.why = "a triangle repeats a node", out;
        if (++directed[directed_key(t[k], t[(k + 1) % 3])] > 1) return out.why = "not consistently oriented", out;
      }
    std::unordered_set<uint64_t> contour_edges;
    for (uint32_t i = 0; i < nc; ++i) {
      const uint32_t u = i, v = (i + 1) % nc;
      if (!directed.count(directed_key(u, v)) || directed.count(directed_key(v, u)))
        return out.why = "its border is not the contour", out;
      contour_edges.insert(edge_key(u, v));
    }
    const std::unordered_set<uint32_t> in_region(reg.triangles.begin(), reg.triangles.end());
    for (const auto& [key, count] : directed) {
      const uint32_t u = uint32_t(key >> 32), v = uint32_t(key & 0xffffffffu);
      if (contour_edges.count(edge_key(u, v))) continue;
      if (!directed.count(directed_key(v, u))) return out.why = "an edge inside has one triangle", out;
      if (u < base && v < base)
        for (uint32_t f : vf_[reg.node_ids[u]])
          if (!in_region.count(f)) {
            const Tri& t = s_.triangles[f];
            const uint32_t gv = reg.node_ids[v];
            if (t[0] == gv || t[1] == gv || t[2] == gv) return out.why = "it would make a non-manifold edge", out;
          }
    }

    // Geometry on the points as they would be: the fill's nodes, then the other nodes of the
    // region and of its ring as needed.
    std::vector<Vec3> points;
    std::unordered_map<uint32_t, uint32_t> local_of;
    for (uint32_t i = 0; i < base; ++i)
      points.push_back(s_.points[reg.node_ids[i]]), local_of.emplace(reg.node_ids[i], i);
    points.insert(points.end(), out.new_points.begin(), out.new_points.end());
    auto local = [&](uint32_t g) {
      auto [it, added] = local_of.emplace(g, uint32_t(points.size()));
      if (added) points.push_back(s_.points[g]);
      return it->second;
    };
    auto cell_of = [&](uint32_t i) { return i < base ? s_.cell_size[reg.node_ids[i]] : reg.cell; };
    const QualityThresholds& th = ref_.thresholds;
    // The region's defects must drop: bad triangles (the triggers) fewer, defective edges
    // and poor normals not more.
    // Short and long edges, counted per triangle side (inside edges twice, in both).
    auto count_edges = [&](const std::vector<Vec3>& p, const Tri& t, auto&& cell, size_t& short_edges,
                           size_t& long_edges) {
      for (int k = 0; k < 3; ++k) {
        const uint32_t u = t[k], v = t[(k + 1) % 3];
        const double len = norm(p[v] - p[u]);
        if (len < th.short_edge * std::min(cell(u), cell(v))) ++short_edges;
        if (len > th.long_edge * std::max(cell(u), cell(v))) ++long_edges;
      }
    };
    auto mesh_cell = [&](uint32_t v) { return s_.cell_size[v]; };
    size_t old_bad = 0, new_bad = 0, old_normals = 0, new_normals = 0;
    size_t old_short = 0, old_long = 0, new_short = 0, new_long = 0;
    for (uint32_t f : reg.triangles) {
      old_bad += is_bad(f) ? 1 : 0;
      old_normals += (flags_[f] & kNormalDeviation) ? 1 : 0;
      count_edges(s_.points, s_.triangles[f], mesh_cell, old_short, old_long);
    }
    for (const Tri& t : tris) {
      if (check::triangle_is_degenerate(points, t)) return out.why = "a degenerate triangle", out;
      const Vec3 &a = points[t[0]], &b = points[t[1]], &c = points[t[2]];
      const double cell = std::min({cell_of(t[0]), cell_of(t[1]), cell_of(t[2])});
      uint8_t f = shape_flags(a, b, c, cell, th);
      const double deviation = normal_deviation_deg(a, b, c, cell, ref_);
      if (deviation > th.normal_deviation_deg) f |= kNormalDeviation;
      out.new_flags.push_back(f);
      out.new_deviation.push_back(float(deviation));
      count_edges(points, t, cell_of, new_short, new_long);
      new_bad += bad_by(f, deviation) ? 1 : 0;
      new_normals += (f & kNormalDeviation) ? 1 : 0;
    }
    if (new_bad >= old_bad) return out.why = "bad triangles not fewer", out;
    if (new_normals > old_normals) return out.why = "more triangles with poor normals", out;
    if (new_short > old_short || new_long > old_long) return out.why = "more edges of uncharacteristic length", out;

    // Close to the input: as close as the triangles it replaces, or within the bound.
    auto input_distance = [&](const Vec3& q) { return std::sqrt(ref_.closest(q - ref_.origin).squared_distance); };
    std::vector<Tri> old_tris;
    for (uint32_t f : reg.triangles) old_tris.push_back(s_.triangles[f]);
    if (reg.old_far < 0) {  // the same for both fills: the first one to get here measures it
      reg.old_far = 0;
      for (const Vec3& q : samples_of(s_.points, old_tris)) {
        const mesh::SurfaceIndex::Hit hit = ref_.closest(q - ref_.origin);
        reg.old_far = std::max(reg.old_far, std::sqrt(hit.squared_distance));
        reg.old_feet.push_back(hit.point + ref_.origin);
      }
    }
    const double bound = std::max(prm_.max_deviation, reg.old_far);
    for (const Vec3& q : samples_of(points, tris))
      if (input_distance(q) > bound) return out.far_why = "too far from the input", out;
    // The input near the region as close to the new surface as to the old one (or within
    // the bound), and its sharp edges kept (or within their tolerance).
    std::vector<Tri> before = old_tris, after = tris;
    for (uint32_t f : reg.ring) {
      before.push_back(s_.triangles[f]);
      const Tri& t = s_.triangles[f];
      after.push_back({local(t[0]), local(t[1]), local(t[2])});
    }
    mesh::SurfaceIndex old_index(s_.points, before), new_index(points, after);
    Box3 box;
    for (const Tri& t : old_tris)
      for (uint32_t v : t) box.add(s_.points[v]);
    const double eps = 1e-9 * std::max(box.diagonal(), pr.target);
    // Input points: the feet of points on the old surface, and the corners and edges of the
    // input under it (ridges and tips are where a rebuild cuts corners).
    std::vector<Vec3> near_input = reg.old_feet;
    Box3 reach = box;
    for (int k = 0; k < 3; ++k) reach.lo[k] -= pr.target, reach.hi[k] += pr.target;
    auto inside = [&](const Vec3& q) {
      for (int k = 0; k < 3; ++k)
        if (q[k] < reach.lo[k] || q[k] > reach.hi[k]) return false;
      return true;
    };
    for (const Tri& t : reg.substrate.triangles)
      for (int k = 0; k < 3; ++k) {
        const Vec3 &a = reg.substrate.points[t[k]], &b = reg.substrate.points[t[(k + 1) % 3]];
        const size_t n = std::min<size_t>(64, size_t(std::ceil(4 * norm(b - a) / pr.target)));
        for (size_t i = 0; i < n; ++i) {
          const Vec3 q = lerp(a, b, double(i) / double(std::max<size_t>(1, n)));
          if (inside(q)) near_input.push_back(q);
        }
      }
    for (const Vec3& q : near_input) {
      const double was = std::sqrt(old_index.squared_distance(q)), now = std::sqrt(new_index.squared_distance(q));
      if (now > std::max(was, prm_.max_deviation) + eps) return out.far_why = "the input moves away from it", out;
    }
    const double tolerance = th.feature_tolerance * ref_.finest_size;
    const bool lost = features_.for_lists(
        box,
        [&](const std::vector<uint32_t>& list) {
          for (uint32_t i : list) {
            const Vec3 q = ref_.feature_samples[i] + ref_.origin;
            const double was = std::sqrt(old_index.squared_distance(q)), now = std::sqrt(new_index.squared_distance(q));
            if (now > std::max(was, tolerance) + eps) return true;
          }
          return false;
        },
        1);
    if (lost) out.far_why = "a sharp edge of the input gets lost";
    return out;
  }

  // The rest of the checks, against the surface as the round's earlier fills left it, in the
  // order of the checks (the pre-checked ones' verdicts where they come); applies the fill
  // when it passes.
  bool accept(Region& reg, const RegionFill& fill, const Verdict& verdict, std::string& why) {
    if (!verdict.why.empty()) return why = verdict.why, false;
    const uint32_t base = uint32_t(reg.node_ids.size());
    const uint32_t first_new = uint32_t(s_.points.size());
    auto global = [&](uint32_t i) { return i < base ? reg.node_ids[i] : first_new + (i - base); };
    std::vector<Tri> tris;
    for (const Tri& t : fill.triangles) tris.push_back({global(t[0]), global(t[1]), global(t[2])});
    const std::unordered_set<uint32_t> in_region(reg.triangles.begin(), reg.triangles.end());
    s_.points.insert(s_.points.end(), verdict.new_points.begin(), verdict.new_points.end());
    auto undo_points = [&]() { s_.points.resize(first_new); };

    // No intersection among the new triangles, nor with the rest of the surface.
    for (size_t i = 0; i < tris.size(); ++i) {
      for (size_t j = 0; j < i; ++j)
        if (check::triangle_pair_intersects(s_.points, tris[i], tris[j]))
          return undo_points(), why = "it intersects itself", false;
      Box3 box;
      for (uint32_t v : tris[i]) box.add(s_.points[v]);
      bool hit = false;
      buckets_.for_each_in_box(box, [&](uint32_t g) {
        if (hit || !alive_[g] || in_region.count(g)) return;
        hit = check::triangle_pair_intersects(s_.points, tris[i], s_.triangles[g]);
      });
      if (hit) return undo_points(), why = "it intersects the surface", false;
    }
    if (!verdict.far_why.empty()) return undo_points(), why = verdict.far_why, false;

    // Apply: the region's triangles die, the fill's are appended, its nodes too.
    s_.cell_size.resize(s_.points.size(), reg.cell);
    s_.locked.resize(s_.points.size(), 0);
    vf_.resize(s_.points.size());
    for (uint32_t f : reg.triangles) {
      alive_[f] = 0;
      for (uint32_t v : s_.triangles[f]) {
        auto& list = vf_[v];
        list.erase(std::remove(list.begin(), list.end(), f), list.end());
      }
    }
    for (size_t i = 0; i < tris.size(); ++i) {
      const uint32_t id = uint32_t(s_.triangles.size());
      s_.triangles.push_back(tris[i]);
      alive_.push_back(1);
      flags_.push_back(verdict.new_flags[i]);
      deviation_.push_back(verdict.new_deviation[i]);
      for (uint32_t v : tris[i]) vf_[v].push_back(id);
      buckets_.update(id);
    }
    return true;
  }

  // Live triangles and the points they use, with their data.
  void compact() {
    std::vector<uint32_t> remap;
    PostSurface out = live_part(s_, alive_, remap);
    // The traced feature edges whose nodes stay (the rebuilds keep them as constraints).
    std::vector<uint64_t> kept(feature_edges_.begin(), feature_edges_.end());
    std::sort(kept.begin(), kept.end());
    for (uint64_t e : kept) {
      const uint32_t a = remap[uint32_t(e >> 32)], b = remap[uint32_t(e)];
      if (a != UINT32_MAX && b != UINT32_MAX) out.feature_edges.push_back({a, b});
    }
    s_ = std::move(out);
  }

  PostSurface& s_;
  const QualityReference& ref_;
  const prep::PreparedInput& input_;
  RemeshParams prm_;
  std::vector<uint8_t> flags_;
  std::vector<float> deviation_;  // normal deviation of the flagged triangles (degrees), else -1
  TriangleBuckets buckets_;
  std::vector<uint8_t> alive_;
  std::vector<std::vector<uint32_t>> vf_;
  std::unordered_set<uint64_t> tried_;
  // Per triangle: the last mark given to it (see next_mark), for gathering's sets.
  std::vector<uint32_t> marks_;
  uint32_t mark_ = 0;
  uint32_t next_mark() {
    if (marks_.size() != s_.triangles.size()) marks_.assign(s_.triangles.size(), 0), mark_ = 0;
    if (++mark_ == 0) std::fill(marks_.begin(), marks_.end(), 0), mark_ = 1;  // wrapped around
    return mark_;
  }
  std::unordered_set<uint64_t> feature_edges_;
  CellLists<> features_;  // the input's sharp-edge samples
  RemeshStats stats_;
};

}  // namespace

RemeshStats remesh_bad_regions(PostSurface& surface, const std::vector<uint8_t>& flags, const QualityReference& ref,
                               const prep::PreparedInput& input, const RemeshParams& params, ProgressSink* progress) {
  if (surface.triangles.empty() || !ref.input) return {};
  Remesher r(surface, flags, ref, input, params);
  return r.run(progress);
}

PostSurface live_part(const PostSurface& s, const std::vector<uint8_t>& alive, std::vector<uint32_t>& remap) {
  remap.assign(s.points.size(), UINT32_MAX);
  PostSurface out;
  for (uint32_t f = 0; f < s.triangles.size(); ++f) {
    if (!alive[f]) continue;
    Tri t = s.triangles[f];
    for (uint32_t& v : t) {
      if (remap[v] == UINT32_MAX) {
        remap[v] = uint32_t(out.points.size());
        out.points.push_back(s.points[v]);
        out.cell_size.push_back(s.cell_size[v]);
        out.locked.push_back(s.locked[v]);
      }
      v = remap[v];
    }
    out.triangles.push_back(t);
  }
  return out;
}

}  // namespace vdbwrap::post
