#include "grid/flood_fill.h"

#include "vdbwrap/errors.h"

namespace vdbwrap::grid {
namespace {
struct CellKey {
  int level;
  Coord c;
};
// A queued piece of a component: a leaf cell, or a whole uniform level-0 block.
struct Piece {
  int level;
  Coord c;  // the cell, or the block's low corner
  bool block;
};
}  // namespace

Components label_components(AdaptiveGrid& g, const std::function<bool(int32_t)>& member, int32_t first_label,
                            ProgressSink* progress) {
  Components comps;
  comps.first_label = first_label;
  std::vector<Piece> queue;
  size_t visited = 0;

  // The walk goes from cell to neighbouring cell: cached accessors (each look-up from the
  // tree's root cost about a sixth of the stage).
  AdaptiveGrid::Cursor cursor(g);
  const Coord& dims = g.dims0();
  double volume = 0;
  bool outside = false, level0 = false;
  int32_t label = 0;
  // Labels member leaf (level, c); a level-0 cell in a uniform block takes its whole block
  // (all member, so all one piece): one tile instead of up to 512 cells, which is what keeps
  // the outside volume of a fine grid cheap to label.
  auto take = [&](int level, const Coord& c) {
    if (level == 0) {
      level0 = true;
      const AdaptiveGrid::Block b = g.block_of(c);
      int32_t v;
      if (cursor.uniform_block(b.lo, v)) {
        cursor.set_block(b.lo, label);
        queue.push_back({0, b.lo, true});
        const double side = double(g.fine_units(0));
        volume += double(b.cells()) * side * side * side;
        return;
      }
    }
    cursor.set(level, c, label);
    queue.push_back({level, c, false});
    const double side = double(g.fine_units(level));
    volume += side * side * side;
  };
  auto reach = [&](const LeafRef& n) {
    if (n.outside_box)
      outside = true;
    else if (member(n.value))
      take(n.level, n.ijk);
  };
  // Across face (axis, dir) of a labelled block: the box's end, a uniform block (taken whole
  // or not at all), or cells of a mixed block, one by one.
  auto spread_from_block = [&](const AdaptiveGrid::Block& b, int axis, int dir) {
    const int across = dir < 0 ? b.lo[axis] - 1 : b.hi[axis];
    if (across < 0 || across >= dims[axis]) {
      outside = true;
      return;
    }
    Coord next = b.lo;
    next[axis] = across & ~(AdaptiveGrid::kBlock - 1);
    int32_t v;
    if (cursor.uniform_block(next, v)) {
      if (member(v)) take(0, next);
      return;
    }
    const int u = (axis + 1) % 3, w = (axis + 2) % 3;
    Coord c;
    c[axis] = dir < 0 ? b.lo[axis] : b.hi[axis] - 1;
    for (c[u] = b.lo[u]; c[u] < b.hi[u]; ++c[u])
      for (c[w] = b.lo[w]; c[w] < b.hi[w]; ++c[w]) cursor.for_each_face_neighbour(0, c, axis, dir, reach);
  };
  auto flood = [&](int level, const Coord& seed, int32_t new_label) {
    volume = 0;
    outside = level0 = false;
    label = new_label;
    queue.clear();
    take(level, seed);
    for (size_t q = 0; q < queue.size(); ++q) {
      const Piece cur = queue[q];
      if (progress && (++visited & 0xFFFFF) == 0 && progress->cancelled())
        throw Error(ErrorKind::Cancelled, "cancelled");
      for (int axis = 0; axis < 3; ++axis)
        for (int dir = -1; dir <= 1; dir += 2)
          if (cur.block)
            spread_from_block(g.block_of(cur.c), axis, dir);
          else
            cursor.for_each_face_neighbour(cur.level, cur.c, axis, dir, reach);
    }
    comps.volume.push_back(volume);
    comps.touches_outside.push_back(outside ? 1 : 0);
    comps.holds_level0.push_back(level0 ? 1 : 0);
  };

  int32_t next = first_label;
  if (member(cursor.get(0, Coord(0, 0, 0)))) flood(0, Coord(0, 0, 0), next++);
  // Collect seeds first: flooding while iterating a VDB tree would invalidate the iterator.
  // In the order of for_each_leaf, so that components are numbered as a cell-by-cell pass
  // would number them (a uniform run's first cell stands for the run).
  std::vector<CellKey> seeds;
  g.for_each_level0_run(
      [&](const Coord& first, int, int32_t v, const AdaptiveGrid::Block&) {
        if (member(v)) seeds.push_back({0, first});
      },
      [&](const Coord& c, int32_t v) {
        if (member(v)) seeds.push_back({0, c});
      });
  g.for_each_fine_leaf([&](int level, const Coord& c, int32_t v) {
    if (member(v)) seeds.push_back({level, c});
  });
  for (const CellKey& s : seeds)
    if (member(cursor.get(s.level, s.c))) flood(s.level, s.c, next++);
  return comps;
}

int32_t largest_enclosed_label(const Components& comps, double min_volume) {
  int32_t best = -1;
  double best_volume = 0;
  for (size_t i = 0; i < comps.count(); ++i)
    if (!comps.touches_outside[i] && comps.volume[i] > best_volume &&
        (comps.holds_level0[i] || comps.volume[i] >= min_volume)) {
      best_volume = comps.volume[i];
      best = comps.first_label + int32_t(i);
    }
  return best;
}

int32_t choose_volume(AdaptiveGrid& g, VolumeChoice choice, Components& comps, ProgressSink* progress) {
  if (progress) progress->progress("flood fill", 0.0, "labelling free cells");
  comps = label_components(
      g, [](int32_t v) { return v == kFree; }, 1, progress);
  if (progress) progress->progress("flood fill", 1.0, std::to_string(comps.count()) + " free volume(s) found");
  if (choice == VolumeChoice::Outside) return 1;
  const int32_t best = largest_enclosed_label(comps);
  if (best < 0)
    throw Error(
        ErrorKind::WrapFailed,
        "the input encloses no volume at this base size: nothing to wrap from inside (try a smaller --base-size)");
  return best;
}

}  // namespace vdbwrap::grid
