#include "grid/flood_fill.h"

#include "vdbwrap/errors.h"

namespace vdbwrap::grid {
namespace {
struct CellKey {
  int level;
  Coord c;
};
}  // namespace

Components label_components(AdaptiveGrid& g, const std::function<bool(int32_t)>& member, int32_t first_label,
                            ProgressSink* progress) {
  Components comps;
  comps.first_label = first_label;
  std::vector<CellKey> queue;
  const int L = g.max_level();
  size_t visited = 0;

  // The walk goes from cell to neighbouring cell: cached accessors (each look-up from the
  // tree's root cost about a sixth of the stage).
  AdaptiveGrid::Cursor cursor(g);
  auto flood = [&](int level, const Coord& seed, int32_t label) {
    double volume = 0;
    bool outside = false;
    cursor.set(level, seed, label);
    queue.assign(1, {level, seed});
    for (size_t q = 0; q < queue.size(); ++q) {
      const CellKey cur = queue[q];
      double side = double(g.fine_units(cur.level));
      volume += side * side * side;
      if (progress && (++visited & 0xFFFFF) == 0 && progress->cancelled()) throw Error(ErrorKind::Cancelled, "cancelled");
      for (int axis = 0; axis < 3; ++axis)
        for (int dir = -1; dir <= 1; dir += 2)
          cursor.for_each_face_neighbour(cur.level, cur.c, axis, dir, [&](const LeafRef& n) {
            if (n.outside_box) {
              outside = true;
              return;
            }
            if (!member(n.value)) return;
            cursor.set(n.level, n.ijk, label);
            queue.push_back({n.level, n.ijk});
          });
    }
    comps.volume.push_back(volume);
    comps.touches_outside.push_back(outside ? 1 : 0);
  };

  int32_t next = first_label;
  if (member(cursor.get(0, Coord(0, 0, 0)))) flood(0, Coord(0, 0, 0), next++);
  // Collect seeds first: flooding while iterating a VDB tree would invalidate the iterator.
  std::vector<CellKey> seeds;
  g.for_each_leaf([&](int level, const Coord& c, int32_t v) {
    if (member(v)) seeds.push_back({level, c});
  });
  for (const CellKey& s : seeds)
    if (member(cursor.get(s.level, s.c))) flood(s.level, s.c, next++);
  (void)L;
  return comps;
}

int32_t largest_enclosed_label(const Components& comps) {
  int32_t best = -1;
  double best_volume = 0;
  for (size_t i = 0; i < comps.count(); ++i)
    if (!comps.touches_outside[i] && comps.volume[i] > best_volume) {
      best_volume = comps.volume[i];
      best = comps.first_label + int32_t(i);
    }
  return best;
}

int32_t choose_volume(AdaptiveGrid& g, VolumeChoice choice, Components& comps, ProgressSink* progress) {
  if (progress) progress->progress("flood fill", 0.0, "labelling free cells");
  comps = label_components(g, [](int32_t v) { return v == kFree; }, 1, progress);
  if (progress)
    progress->progress("flood fill", 1.0, std::to_string(comps.count()) + " free volume(s) found");
  if (choice == VolumeChoice::Outside) return 1;
  const int32_t best = largest_enclosed_label(comps);
  if (best < 0)
    throw Error(ErrorKind::WrapFailed,
                "the input encloses no volume at this base size: nothing to wrap from inside (try a smaller --base-size)");
  return best;
}

}  // namespace vdbwrap::grid
