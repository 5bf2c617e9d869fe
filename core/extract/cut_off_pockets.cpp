// Stage 2c, within the manifold fix: the pieces of the volume that taking cells out has cut
// off, found by searches near those cells instead of a full labelling of the volume.
#include "extract/extract_surface.h"

#include <algorithm>
#include <map>
#include <unordered_map>
#include <utility>
#include <vector>

#include "common/cell_lists.h"
#include "common/grid_key.h"

namespace vdbwrap::extract {

using grid::AdaptiveGrid;

bool drop_cut_off_pockets(AdaptiveGrid& g, int32_t label, const std::vector<std::pair<int, Coord>>& taken_out,
                          double pocket_share, size_t total_budget, size_t& dropped,
                          std::vector<std::pair<int, Coord>>* dropped_cells) {
  // Why looking near the taken-out cells is enough: the volume was one piece before. A path
  // through it that crossed taken-out cells entered and left a cluster of them through
  // volume cells next to it; when those are joined without the taken-out cells, the path
  // can go round. A search from each of them that ends without meeting the others has found
  // all of a piece that was cut off. Clusters: taken-out cells within a cell's size of each
  // other (adjacent ones always share one: their corners differ by at most the larger one's
  // size, half the span).
  int32_t span = 1;
  for (const auto& cell : taken_out) span = std::max(span, 2 * g.fine_units(cell.first));
  auto fine_corner = [&](const std::pair<int, Coord>& cell) {
    const int32_t s = g.fine_units(cell.first);
    return Coord(cell.second.x() * s, cell.second.y() * s, cell.second.z() * s);
  };
  std::vector<uint32_t> parent(taken_out.size());
  for (uint32_t i = 0; i < parent.size(); ++i) parent[i] = i;
  auto find = [](std::vector<uint32_t>& up, uint32_t x) {
    while (up[x] != x) x = up[x] = up[up[x]];
    return x;
  };
  {
    CellLists<> near;  // keys made here, on the fine lattice
    auto key_of = [&](const Coord& c) { return GridKey{c.x() / span, c.y() / span, c.z() / span}; };
    for (uint32_t i = 0; i < taken_out.size(); ++i) near.add(key_of(fine_corner(taken_out[i])), i);
    for (uint32_t i = 0; i < taken_out.size(); ++i) {
      const GridKey k = key_of(fine_corner(taken_out[i]));
      near.for_lists(GridKey{k.x - 1, k.y - 1, k.z - 1}, GridKey{k.x + 1, k.y + 1, k.z + 1},
                     [&](const std::vector<uint32_t>& list) {
                       for (uint32_t j : list) parent[find(parent, i)] = find(parent, j);
                     });
    }
  }
  std::map<uint32_t, std::vector<uint32_t>> clusters;  // ordered: the same drops on every run
  for (uint32_t i = 0; i < taken_out.size(); ++i) clusters[find(parent, i)].push_back(i);

  auto cell_key = [](int level, const Coord& c) {
    return GridKey{int64_t(c.x()) + (int64_t(level) << 32), c.y(), c.z()};
  };
  constexpr size_t budget_base = 50000, budget_per_seed = 200;  // per cluster, before leaving it to a full labelling
  std::vector<std::vector<std::pair<int, Coord>>> pockets;
  double pocket_limit = -1;  // pocket_share of the volume, measured when a first pocket is found
  auto limit = [&] {
    if (pocket_limit < 0) {
      double volume = 0;
      const double side0 = g.fine_units(0), cell0 = side0 * side0 * side0;
      g.for_each_level0_block(
          [&](const AdaptiveGrid::Block& b, int32_t v) { volume += v == label ? double(b.cells()) * cell0 : 0.0; },
          [&](const Coord&, int32_t v) { volume += v == label ? cell0 : 0.0; });
      g.for_each_fine_leaf([&](int level, const Coord&, int32_t v) {
        const double side = g.fine_units(level);
        if (v == label) volume += side * side * side;
      });
      pocket_limit = pocket_share * volume;
    }
    return pocket_limit;
  };
  size_t queued = 0;  // by all clusters' searches
  for (const auto& [root, members] : clusters) {
    // One search per volume cell next to the cluster, run together (breadth first); searches
    // that meet are joined. pending[g]: cells queued and not yet expanded by joined search g.
    std::vector<std::pair<int, Coord>> queue;
    std::vector<uint32_t> from;  // the search that queued each cell
    std::unordered_map<GridKey, uint32_t, GridKeyHash> owner;
    for (uint32_t i : members)
      for (int axis = 0; axis < 3; ++axis)
        for (int dir = -1; dir <= 1; dir += 2)
          g.for_each_face_neighbour(taken_out[i].first, taken_out[i].second, axis, dir, [&](const grid::LeafRef& n) {
            if (n.outside_box || n.value != label) return;
            if (owner.emplace(cell_key(n.level, n.ijk), uint32_t(queue.size())).second)
              from.push_back(uint32_t(queue.size())), queue.emplace_back(n.level, n.ijk);
          });
    if (queue.size() <= 1) continue;
    const size_t budget = budget_base + budget_per_seed * queue.size();
    std::vector<uint32_t> up(queue.size()), pending(queue.size(), 1);
    for (uint32_t i = 0; i < up.size(); ++i) up[i] = i;
    size_t open = queue.size();  // searches not yet joined to another nor finished
    std::vector<uint32_t> finished;
    for (size_t q = 0; q < queue.size() && open > 1; ++q) {
      if (queue.size() > budget || queued + queue.size() > total_budget) return false;
      const auto [level, c] = queue[q];
      const uint32_t mine = find(up, from[q]);
      for (int axis = 0; axis < 3; ++axis)
        for (int dir = -1; dir <= 1; dir += 2)
          g.for_each_face_neighbour(level, c, axis, dir, [&](const grid::LeafRef& n) {
            if (n.outside_box || n.value != label) return;
            const uint32_t me = find(up, mine);
            auto [it, added] = owner.emplace(cell_key(n.level, n.ijk), me);
            if (added) {
              from.push_back(me), queue.emplace_back(n.level, n.ijk);
              ++pending[me];
              return;
            }
            const uint32_t other = find(up, it->second);
            if (other != me) up[other] = me, pending[me] += pending[other], --open;
          });
      const uint32_t me = find(up, mine);
      if (--pending[me] == 0) finished.push_back(me), --open;  // all of a cut-off piece
    }
    queued += queue.size();
    // Undecided within the budget, or every search ended (no piece reached beyond: a tiny
    // volume): a full labelling decides.
    if (open != 1) return false;
    for (uint32_t f : finished) {
      std::vector<std::pair<int, Coord>> cells;
      double volume = 0;
      for (size_t k = 0; k < queue.size(); ++k)
        if (find(up, from[k]) == f) {
          cells.push_back(queue[k]);
          const double side = g.fine_units(queue[k].first);
          volume += side * side * side;
        }
      if (volume >= limit()) return false;  // not clearly smaller than the rest: a full labelling decides
      pockets.push_back(std::move(cells));
    }
  }
  for (const auto& cells : pockets)
    for (const auto& [level, c] : cells) {
      g.set(level, c, grid::kExcluded);
      if (dropped_cells) dropped_cells->emplace_back(level, c);
    }
  dropped = pockets.size();
  return true;
}

}  // namespace vdbwrap::extract
