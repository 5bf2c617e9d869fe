// Stage 2c, the manifold fix: rounds that take chosen cells out of the volume where the
// surface is not a 2-manifold (docs/pipeline.md, "Manifold repair"), then extract it again,
// until a round changes nothing.
#include "extract/extract_surface.h"

#include <algorithm>
#include <functional>
#include <optional>
#include <queue>
#include <set>
#include <string>
#include <utility>

#include <tbb/parallel_for.h>
#include <tbb/parallel_sort.h>

#include "common/dense_numbers.h"
#include "extract/lattice_faces.h"
#include "grid/flood_fill.h"
#include "vdbwrap/errors.h"

namespace vdbwrap::extract {
namespace {

using grid::AdaptiveGrid;
using grid::LeafRef;

// The searches for cut-off pockets may queue this many cells per face of the surface, all
// clusters together; past that one labelling of the volume and a whole round cost less. (Around
// a thin shell wrapped from both sides the searches from each cluster go far before they meet:
// teapot.stl queued 20 cells per face, an assembly of overlapping solids 0.2.)
constexpr size_t kPocketSearchPerFace = 2;

// Face-connected groups among the 8 octants around a node that share a membership
// (octants one bit apart share a face). Returns the number of groups on each side.
void octant_groups(const bool in[8], int group[8], int& groups_in, int& groups_out) {
  std::fill(group, group + 8, -1);
  groups_in = groups_out = 0;
  for (int o = 0; o < 8; ++o) {
    if (group[o] >= 0) continue;
    int id = in[o] ? groups_in++ : 8 + groups_out++;
    int stack[8], top = 0;
    stack[top++] = o;
    group[o] = id;
    while (top) {
      int cur = stack[--top];
      for (int k = 0; k < 3; ++k) {
        int nb = cur ^ (1 << k);
        if (group[nb] < 0 && in[nb] == in[o]) {
          group[nb] = id;
          stack[top++] = nb;
        }
      }
    }
  }
}

Coord lattice_point(const DenseNumbers& lattice, uint64_t number) {
  const auto q = lattice.point(number);
  return Coord(int32_t(q[0]), int32_t(q[1]), int32_t(q[2]));
}

Coord octant_cell(const Coord& p, int o) {
  return Coord(p.x() - 1 + (o & 1), p.y() - 1 + ((o >> 1) & 1), p.z() - 1 + ((o >> 2) & 1));
}

// Are the chosen finest cells around lattice point p, or the others, not face-connected?
bool nonmanifold_at(AdaptiveGrid::Reader& reader, int L, const Coord& p, int32_t label, VolumeChoice choice) {
  bool in[8];
  for (int o = 0; o < 8; ++o) in[o] = in_volume(reader.leaf_at(L, octant_cell(p, o)), label, choice);
  int group[8], groups_in, groups_out;
  octant_groups(in, group, groups_in, groups_out);
  return groups_in > 1 || groups_out > 1;
}

// Is lattice point p a corner of one of the quads faces_and_nodes makes (a surface node)?
// The quads with a corner at p lie on the faces of the volume's leaves around p.
bool is_surface_node(AdaptiveGrid::Reader& reader, const AdaptiveGrid& g, const Coord& p, int32_t label,
                     VolumeChoice choice) {
  const int L = g.max_level();
  LeafRef around[8];
  int count = 0;
  for (int o = 0; o < 8; ++o) {
    const LeafRef r = reader.leaf_at(L, octant_cell(p, o));
    if (r.outside_box || r.value != label) continue;
    bool seen = false;
    for (int k = 0; k < count && !seen; ++k) seen = around[k].level == r.level && around[k].ijk == r.ijk;
    if (!seen) around[count++] = r;
  }
  for (int k = 0; k < count; ++k) {
    const int level = around[k].level;
    const Coord& c = around[k].ijk;
    const int32_t s = g.fine_units(level);
    const Coord C(c.x() * s, c.y() * s, c.z() * s);
    for (int axis = 0; axis < 3; ++axis)
      for (int dir = -1; dir <= 1; dir += 2) {
        if (p[axis] != C[axis] + (dir > 0 ? s : 0)) continue;
        const int b = (axis + 1) % 3, cc = (axis + 2) % 3;
        bool corner = false;
        reader.for_each_face_neighbour(level, c, axis, dir, [&](const LeafRef& n) {
          if (corner || in_volume(n, label, choice)) return;
          int32_t u0 = C[b], v0 = C[cc], size = s;
          if (!n.outside_box && n.level > level)
            size = g.fine_units(n.level), u0 = n.ijk[b] * size, v0 = n.ijk[cc] * size;
          corner = (p[b] == u0 || p[b] == u0 + size) && (p[cc] == v0 || p[cc] == v0 + size);
        });
        if (corner) return true;
      }
  }
  return false;
}

// The finest lattice points on the closed boundary of cell (level, c), by number.
void boundary_points(const AdaptiveGrid& g, const DenseNumbers& lattice, int level, const Coord& c,
                     std::vector<uint64_t>& out) {
  const int64_t s = g.fine_units(level);
  const int64_t x0 = int64_t(c.x()) * s, y0 = int64_t(c.y()) * s, z0 = int64_t(c.z()) * s;
  for (int64_t x = x0; x <= x0 + s; ++x)
    for (int64_t y = y0; y <= y0 + s; ++y)
      for (int64_t z = z0; z <= z0 + s; ++z) {
        const bool face = x == x0 || x == x0 + s || y == y0 || y == y0 + s || z == z0 || z == z0 + s;
        if (face && x >= 0 && y >= 0 && z >= 0) out.push_back(lattice.number(x, y, z));
      }
}

// What one round changed.
struct RoundRepairs {
  std::vector<std::pair<int, Coord>> taken_out, split;  // cells; `split` lists no cell taken out
  size_t changed = 0;                                   // cells taken out plus cells chosen for splitting
  std::vector<uint64_t> visited;                        // lattice numbers of the nodes the round looked at
};

// One round of repairs at the surface nodes where the chosen cells around the node, or the
// others, are not face-connected (edge or corner contacts: non-manifold). Takes chosen cells
// finer than min_exclude_level out of the volume there, and splits coarser chosen cells into
// chosen children, so that the next round can take those out. Visits the nodes `flagged`
// (keys, ascending: the nodes not manifold as the grid stands) in order, with the later
// nodes on each cell taken out.
// A key orders the nodes: `point_of(key)` is its lattice point, and `key_of(point, number)`
// the key of a lattice point and its number (UINT64_MAX: not a surface node).
template <typename PointOf, typename KeyOf>
RoundRepairs repair_nodes(AdaptiveGrid& g, int32_t label, VolumeChoice choice, int min_exclude_level,
                          const DenseNumbers& lattice, const std::vector<uint64_t>& flagged, PointOf&& point_of,
                          KeyOf&& key_of) {
  const int L = g.max_level();
  const int exclude_from = min_exclude_level < 0 ? L : std::min(min_exclude_level, L);
  struct LeafKey {
    int level;
    Coord c;
    bool operator<(const LeafKey& o) const { return level != o.level ? level < o.level : c < o.c; }
  };
  std::set<LeafKey> to_exclude, to_split;
  auto excludable = [&](const LeafRef& r) {
    if (r.outside_box) return false;
    if (r.level > 0) return true;
    // The outermost layer of the padded box stays in the outside volume, so the wrap never reaches it.
    const Coord& d = g.dims0();
    return r.ijk.x() > 0 && r.ijk.y() > 0 && r.ijk.z() > 0 && r.ijk.x() < d.x() - 1 && r.ijk.y() < d.y() - 1 &&
           r.ijk.z() < d.z() - 1;
  };
  RoundRepairs out;
  std::priority_queue<uint64_t, std::vector<uint64_t>, std::greater<uint64_t>> pending;  // later nodes at taken cells
  uint64_t current = 0;                                                                  // the key of the node visited
  std::vector<uint64_t> around;
  auto queue_nodes_at = [&](const LeafKey& key) {  // the surface nodes on the cell's boundary after `current`
    around.clear();
    boundary_points(g, lattice, key.level, key.c, around);
    for (uint64_t number : around) {
      const uint64_t key = key_of(lattice_point(lattice, number), number);
      if (key != UINT64_MAX && key > current) pending.push(key);
    }
  };
  AdaptiveGrid::Reader reader(g);  // nodes come in order: cached reads (the grid changes only after)
  for (size_t next_flagged = 0;;) {
    uint64_t visit = next_flagged < flagged.size() ? flagged[next_flagged] : UINT64_MAX;
    if (!pending.empty() && pending.top() < visit) visit = pending.top();
    if (visit == UINT64_MAX) break;
    while (!pending.empty() && pending.top() == visit) pending.pop();
    if (next_flagged < flagged.size() && visit == flagged[next_flagged]) ++next_flagged;
    current = visit;
    const Coord p = point_of(visit);
    out.visited.push_back(lattice.number(p.x(), p.y(), p.z()));
    // The 8 finest cells around node p; octant bit k set means the +side along axis k.
    LeafRef leaf[8];
    bool in[8];
    for (int o = 0; o < 8; ++o) {
      leaf[o] = reader.leaf_at(L, octant_cell(p, o));
      LeafKey key{leaf[o].level, leaf[o].ijk};
      in[o] = in_volume(leaf[o], label, choice) && !to_exclude.count(key);
    }
    // Take chosen cells out one at a time, finest first, until both the chosen octants and
    // the others are each face-connected around the node: a manifold disc there.
    for (int step = 0; step < 8; ++step) {
      int group[8], groups_in, groups_out;
      octant_groups(in, group, groups_in, groups_out);
      if (groups_in <= 1 && groups_out <= 1) break;
      int victim = -1;
      auto consider = [&](int o) {
        if (!in[o] || !excludable(leaf[o])) return;
        if (victim < 0 || leaf[o].level > leaf[victim].level) victim = o;
      };
      if (groups_in > 1) {
        // Chosen cells meeting along an edge or at a corner: drop those outside the largest group.
        int count[8] = {0};
        for (int o = 0; o < 8; ++o)
          if (in[o]) ++count[group[o]];
        int keep = 0;
        for (int k = 1; k < groups_in; ++k)
          if (count[k] > count[keep]) keep = k;
        for (int o = 0; o < 8; ++o)
          if (in[o] && group[o] != keep) consider(o);
      } else {
        // Other cells meeting along an edge or at a corner: join them through a chosen octant,
        // best one that touches two of their groups.
        for (int o = 0; o < 8 && victim < 0; ++o) {
          if (!in[o]) continue;
          int touching = 0, first = -1;
          for (int k = 0; k < 3; ++k) {
            int nb = o ^ (1 << k);
            if (!in[nb] && group[nb] != first) ++touching, first = first < 0 ? group[nb] : first;
          }
          if (touching >= 2) consider(o);
        }
        if (victim < 0)
          for (int o = 0; o < 8; ++o) {
            bool next_to_other = false;
            for (int k = 0; k < 3; ++k) next_to_other |= !in[o ^ (1 << k)];
            if (next_to_other) consider(o);
          }
      }
      if (victim < 0) break;  // nothing may be taken out here; the caller gives up after its rounds
      LeafKey key{leaf[victim].level, leaf[victim].ijk};
      if (key.level < exclude_from) {
        // Taking out a coarse cell would push the surface far off the input: split it into
        // chosen children instead and decide again, one level finer, next round.
        to_split.insert(key);
        break;
      }
      to_exclude.insert(key);
      queue_nodes_at(key);
      for (int o = 0; o < 8; ++o)
        if (leaf[o].level == key.level && leaf[o].ijk == key.c) in[o] = false;
    }
  }
  for (const LeafKey& k : to_exclude) {
    g.set(k.level, k.c, grid::kExcluded);
    out.taken_out.emplace_back(k.level, k.c);
  }
  for (const LeafKey& k : to_split) {
    if (to_exclude.count(k)) continue;
    g.set(k.level, k.c, grid::kRefined);
    for (int j = 0; j < 8; ++j)
      g.set(k.level + 1, Coord(2 * k.c.x() + (j & 1), 2 * k.c.y() + ((j >> 1) & 1), 2 * k.c.z() + ((j >> 2) & 1)),
            label);
    out.split.emplace_back(k.level, k.c);
  }
  out.changed = to_exclude.size() + to_split.size();
  return out;
}

// A round over the whole surface: every node that is not manifold as the grid stands, in the
// order of `surf.nodes` (their first appearance among the faces), or by lattice point.
RoundRepairs repair_surface(AdaptiveGrid& g, int32_t label, VolumeChoice choice, const LatticeSurface& surf,
                            int min_exclude_level, bool in_lattice_order) {
  const int L = g.max_level();
  const DenseNumbers lattice = lattice_numbers(g);
  const size_t n = surf.nodes.size();
  // The nodes that are not manifold, in parallel (the grid is only read). The repairs visit
  // those, and the later nodes at a cell they take out (their octants change); at every other
  // node they would find a manifold disc and change nothing, and visiting all would cost a
  // large share of each round.
  std::vector<uint8_t> flag(n, 0);
  tbb::parallel_for(tbb::blocked_range<size_t>(0, n, 4096), [&](const tbb::blocked_range<size_t>& r) {
    AdaptiveGrid::Reader local(g);
    for (size_t i = r.begin(); i != r.end(); ++i) flag[i] = nonmanifold_at(local, L, surf.nodes[i], label, choice);
  });
  // Nodes by lattice point, to find those at a cell taken out.
  std::vector<std::pair<uint64_t, uint32_t>> by_point(n);
  tbb::parallel_for(size_t(0), n, [&](size_t i) {
    const Coord& p = surf.nodes[i];
    by_point[i] = {lattice.number(p.x(), p.y(), p.z()), uint32_t(i)};
  });
  tbb::parallel_sort(by_point.begin(), by_point.end());
  auto index_of = [&](uint64_t number) {
    auto it = std::lower_bound(by_point.begin(), by_point.end(), std::make_pair(number, uint32_t(0)));
    return it != by_point.end() && it->first == number ? uint64_t(it->second) : UINT64_MAX;
  };
  std::vector<uint64_t> flagged;
  if (in_lattice_order) {
    for (const auto& [number, i] : by_point)
      if (flag[i]) flagged.push_back(number);
    return repair_nodes(
        g, label, choice, min_exclude_level, lattice, flagged,
        [&](uint64_t number) { return lattice_point(lattice, number); },
        [&](const Coord&, uint64_t number) { return index_of(number) == UINT64_MAX ? UINT64_MAX : number; });
  }
  for (size_t i = 0; i < n; ++i)
    if (flag[i]) flagged.push_back(i);
  return repair_nodes(
      g, label, choice, min_exclude_level, lattice, flagged, [&](uint64_t i) { return surf.nodes[i]; },
      [&](const Coord&, uint64_t number) { return index_of(number); });
}

// A round near the last round's changes: only the nodes it looked at, and the lattice points
// on the cells it changed, can be surface nodes that are not manifold now (a node's octants
// change only with the cells holding them, and a new node is the corner of a new quad, on a
// changed cell). It visits what a round over the whole surface would, by lattice point.
RoundRepairs repair_near(AdaptiveGrid& g, int32_t label, VolumeChoice choice, std::vector<uint64_t>&& candidates,
                         int min_exclude_level) {
  const int L = g.max_level();
  const DenseNumbers lattice = lattice_numbers(g);
  tbb::parallel_sort(candidates.begin(), candidates.end());
  candidates.erase(std::unique(candidates.begin(), candidates.end()), candidates.end());
  std::vector<uint8_t> flag(candidates.size(), 0);
  tbb::parallel_for(tbb::blocked_range<size_t>(0, candidates.size(), 1024), [&](const tbb::blocked_range<size_t>& r) {
    AdaptiveGrid::Reader local(g);
    for (size_t i = r.begin(); i != r.end(); ++i) {
      const Coord p = lattice_point(lattice, candidates[i]);
      flag[i] = nonmanifold_at(local, L, p, label, choice) && is_surface_node(local, g, p, label, choice);
    }
  });
  std::vector<uint64_t> flagged;
  for (size_t i = 0; i < candidates.size(); ++i)
    if (flag[i]) flagged.push_back(candidates[i]);
  AdaptiveGrid::Reader reader(g);
  return repair_nodes(
      g, label, choice, min_exclude_level, lattice, flagged,
      [&](uint64_t number) { return lattice_point(lattice, number); },
      [&](const Coord& p, uint64_t number) {
        return is_surface_node(reader, g, p, label, choice) ? number : UINT64_MAX;
      });
}

}  // namespace

LatticeSurface extract_manifold_surface(AdaptiveGrid& g, int32_t& label, VolumeChoice choice, ExtractStats& stats,
                                        ProgressSink* progress, const std::vector<Coord>& anchors,
                                        int min_exclude_level, bool whole_rounds) {
  for (int k = 0; k < 3; ++k)
    if (int64_t(g.dims0()[k]) * g.fine_units(0) >= (1 << 21) - 2)
      throw Error(ErrorKind::InvalidArgument, "too many cells across the model at this base size and number of levels");
  // New labels must not collide with the labels of other free components.
  int32_t next_label = label + 1;
  auto higher = [&](int32_t v) { next_label = std::max(next_label, v + 1); };
  g.for_each_level0_block([&](const AdaptiveGrid::Block&, int32_t v) { higher(v); },
                          [&](const Coord&, int32_t v) { higher(v); });
  g.for_each_fine_leaf([&](int, const Coord&, int32_t v) { higher(v); });
  const int max_rounds = 64;
  // A round over the whole surface first; later rounds look only near the cells the last one
  // changed (extracting the whole surface's cell faces each round would cost most of the
  // stage), until a full labelling changes cells anywhere.
  bool whole = true;
  size_t surface_faces = 0;          // of the last whole round
  std::vector<uint64_t> candidates;  // for a round near the changes: lattice points to look at
  for (int round = 0; round < max_rounds; ++round) {
    if (progress) {
      if (progress->cancelled()) throw Error(ErrorKind::Cancelled, "cancelled");
      progress->progress("extract", std::min(0.9, round * 0.1),
                         whole ? "extracting cell faces, round " + std::to_string(round + 1)
                               : "repairing " + std::to_string(candidates.size()) + " lattice points, round " +
                                     std::to_string(round + 1));
    }
    std::optional<FacesAndNodes> faces;
    RoundRepairs rep;
    if (whole || whole_rounds) {
      faces = faces_and_nodes(g, label, choice);
      surface_faces = faces->quads.size();
      if (faces->quads.empty())
        throw Error(ErrorKind::WrapFailed, "the chosen volume has no boundary: nothing to wrap");
      rep = repair_surface(g, label, choice, faces->surf, min_exclude_level, !whole);
    } else {
      rep = repair_near(g, label, choice, std::move(candidates), min_exclude_level);
    }
    candidates.clear();
    stats.rounds = round + 1;
    if (rep.changed == 0) {
      LatticeSurface surf = faces ? with_polygons(std::move(*faces)) : extract_faces(g, label, choice);
      if (surf.polygons.empty())
        throw Error(ErrorKind::WrapFailed, "the chosen volume has no boundary: nothing to wrap");
      if (progress)
        progress->progress(
            "extract", 1.0,
            std::to_string(surf.polygons.size()) + " faces, " + std::to_string(surf.nodes.size()) + " nodes");
      return surf;
    }
    stats.excluded_cells += rep.changed;
    // Still one piece: nothing to drop, and labelling the whole volume again (most of a round
    // on fine grids) is not needed. With seed points the volume may hold several chambers,
    // and the full labelling below decides which stay.
    if (choice != VolumeChoice::SeedPoints) {
      size_t pockets = 0;
      std::vector<std::pair<int, Coord>> dropped;
      if (drop_cut_off_pockets(g, label, rep.taken_out, 0.25, kPocketSearchPerFace * surface_faces, pockets,
                               &dropped)) {
        stats.dropped_pieces += pockets;
        const DenseNumbers lattice = lattice_numbers(g);
        candidates = std::move(rep.visited);
        for (const auto* cells : {&rep.taken_out, &rep.split, &dropped})
          for (const auto& [level, c] : *cells) boundary_points(g, lattice, level, c, candidates);
        whole = false;
        continue;
      }
    }
    whole = true;
    // Taking cells out may cut small pockets off the volume: keep its main piece only.
    const int32_t old = label;
    grid::Components comps = grid::label_components(
        g, [old](int32_t v) { return v == old; }, next_label, progress);
    next_label += int32_t(comps.count());
    int32_t keep = -1;
    double best = -1;
    for (size_t i = 0; i < comps.count(); ++i) {
      bool better = choice == VolumeChoice::Outside ? comps.touches_outside[i] != 0 && comps.volume[i] > best
                                                    : comps.volume[i] > best;
      if (better) {
        best = comps.volume[i];
        keep = comps.first_label + int32_t(i);
      }
    }
    if (keep < 0) throw Error(ErrorKind::WrapFailed, "the chosen volume vanished while making the surface manifold");
    // With seed points, every piece holding one stays (one chamber per seed point).
    std::vector<int32_t> kept{keep};
    if (choice == VolumeChoice::SeedPoints && !anchors.empty()) {
      kept.clear();
      for (const Coord& a : anchors) {
        int32_t v = g.leaf_at(g.max_level(), a).value;
        if (v >= comps.first_label && std::find(kept.begin(), kept.end(), v) == kept.end()) kept.push_back(v);
      }
      if (kept.empty()) kept.push_back(keep);
    }
    stats.dropped_pieces += comps.count() - kept.size();
    if (comps.count() > 1) {
      g.relabel([&](int32_t v) {
        if (v < comps.first_label) return v;
        return std::find(kept.begin(), kept.end(), v) == kept.end() ? int32_t(grid::kExcluded) : kept.front();
      });
    }
    label = kept.front();
  }
  throw Error(ErrorKind::WrapFailed,
              "could not make the voxel surface manifold after " + std::to_string(max_rounds) + " rounds");
}

}  // namespace vdbwrap::extract
