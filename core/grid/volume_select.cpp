#include "grid/volume_select.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <optional>
#include <queue>
#include <unordered_map>

#include "common/vec.h"
#include "vdbwrap/errors.h"

namespace vdbwrap::grid {
namespace {

// The free leaves of the grid, numbered, with their centres and (on demand) their clearance
// from the input.
class FreeLeaves {
 public:
  // The leaves that are free: not yet labelled (kFree), or labelled (>= 1) by the flood fill.
  explicit FreeLeaves(const AdaptiveGrid& g) : g_(g) {
    g.for_each_leaf([&](int level, const Coord& c, int32_t v) {
      if (v != kFree && v < 1) return;
      index_.emplace(key(level, c), uint32_t(leaves_.size()));
      leaves_.push_back({level, c});
    });
  }
  size_t size() const { return leaves_.size(); }
  int level(uint32_t i) const { return leaves_[i].level; }
  const Coord& coord(uint32_t i) const { return leaves_[i].c; }
  Vec3 centre(uint32_t i) const {
    const double h = g_.cell_size(leaves_[i].level);
    const Coord& c = leaves_[i].c;
    return g_.origin() + Vec3{(c.x() + 0.5) * h, (c.y() + 0.5) * h, (c.z() + 0.5) * h};
  }
  double half_diagonal(uint32_t i) const { return 0.5 * std::sqrt(3.0) * g_.cell_size(leaves_[i].level); }
  int64_t find(int level, const Coord& c) const {
    auto it = index_.find(key(level, c));
    return it == index_.end() ? -1 : int64_t(it->second);
  }
  // The padded box's outermost level-0 layer: always open, so the outside stays one volume.
  bool on_box_boundary(uint32_t i) const {
    if (leaves_[i].level != 0) return false;
    const Coord& c = leaves_[i].c;
    const Coord& d = g_.dims0();
    return c.x() == 0 || c.y() == 0 || c.z() == 0 || c.x() == d.x() - 1 || c.y() == d.y() - 1 || c.z() == d.z() - 1;
  }

  // Per leaf, whether its centre lies behind the input (see DistanceToInput); after clearance().
  const std::vector<uint8_t>& behind() const { return behind_; }
  const std::vector<float>& clearance(const DistanceToInput& distance, ProgressSink* progress) {
    if (!clearance_.empty() || leaves_.empty()) return clearance_;
    if (progress)
      progress->progress("flood fill", 0.2,
                         "measuring the clearance of " + std::to_string(leaves_.size()) + " free cells");
    clearance_.resize(leaves_.size());
    behind_.resize(leaves_.size());
    tbb::parallel_for(tbb::blocked_range<size_t>(0, leaves_.size(), 1024), [&](const tbb::blocked_range<size_t>& r) {
      if (progress && progress->cancelled()) return;
      for (size_t i = r.begin(); i != r.end(); ++i) {
        const double d = distance(centre(uint32_t(i)));
        clearance_[i] = float(std::abs(d)), behind_[i] = d < 0;
      }
    });
    if (progress && progress->cancelled()) throw Error(ErrorKind::Cancelled, "cancelled");
    return clearance_;
  }

 private:
  struct Leaf {
    int level;
    Coord c;
  };
  static uint64_t key(int level, const Coord& c) {
    return (uint64_t(level) << 60) | (uint64_t(uint32_t(c.x()) & 0xFFFFF) << 40) |
           (uint64_t(uint32_t(c.y()) & 0xFFFFF) << 20) | uint64_t(uint32_t(c.z()) & 0xFFFFF);
  }
  const AdaptiveGrid& g_;
  std::vector<Leaf> leaves_;
  std::unordered_map<uint64_t, uint32_t> index_;
  std::vector<float> clearance_;
  std::vector<uint8_t> behind_;
};

std::string point_text(const Vec3& p) {
  char buf[128];
  std::snprintf(buf, sizeof buf, "(%.6g, %.6g, %.6g)", p[0], p[1], p[2]);
  return buf;
}

// The widest way (largest smallest clearance) from `from` through cells labelled `label` to
// the outside of the box (target < 0) or to cell `target`: the leak's path and its narrowest
// passage.
LeakReport widest_path(const AdaptiveGrid& g, FreeLeaves& leaves, const std::vector<float>& clearance, int32_t label,
                       uint32_t from, int64_t target) {
  const size_t n = leaves.size();
  std::vector<float> best(n, -1.0f);
  std::vector<int64_t> parent(n, -1);
  std::vector<uint8_t> done(n, 0);
  std::priority_queue<std::pair<float, uint32_t>> heap;
  best[from] = clearance[from];
  heap.push({best[from], from});
  int64_t end = -1;
  while (!heap.empty() && end < 0) {
    // Plain variables, not a structured binding: the lambda below captures them (clang 14).
    const float width = heap.top().first;
    const uint32_t i = heap.top().second;
    heap.pop();
    if (done[i]) continue;
    done[i] = 1;
    if (int64_t(i) == target) {
      end = i;
      break;
    }
    for (int axis = 0; axis < 3 && end < 0; ++axis)
      for (int dir = -1; dir <= 1 && end < 0; dir += 2)
        g.for_each_face_neighbour(leaves.level(i), leaves.coord(i), axis, dir, [&](const LeafRef& r) {
          if (r.outside_box) {
            if (target < 0) end = i;
            return;
          }
          if (r.value != label) return;
          int64_t j = leaves.find(r.level, r.ijk);
          if (j < 0 || done[size_t(j)]) return;
          float w = std::min(width, clearance[size_t(j)]);
          if (w > best[size_t(j)]) {
            best[size_t(j)] = w;
            parent[size_t(j)] = i;
            heap.push({w, uint32_t(j)});
          }
        });
  }
  LeakReport leak;
  leak.detected = true;
  if (end < 0) return leak;  // cannot happen: the component was found to connect them
  std::vector<uint32_t> chain;
  for (int64_t k = end; k >= 0; k = parent[size_t(k)]) chain.push_back(uint32_t(k));
  std::reverse(chain.begin(), chain.end());
  // The narrowest passage: the smallest clearance on the way, the seed's own cell aside.
  size_t narrowest = chain.size() > 1 ? 1 : 0;
  for (size_t k = narrowest; k < chain.size(); ++k)
    if (clearance[chain[k]] < clearance[chain[narrowest]]) narrowest = k;
  leak.location = leaves.centre(chain[narrowest]);
  leak.width = 2.0 * clearance[chain[narrowest]];
  const size_t step = std::max<size_t>(1, chain.size() / 256);
  for (size_t k = 0; k < chain.size(); ++k)
    if (k % step == 0 || k == narrowest || k + 1 == chain.size()) leak.path.push_back(leaves.centre(chain[k]));
  return leak;
}

// Gap closure, last part: the detail the opening took, given back away from the openings. The
// narrow cells still left are flooded, most open first, from every free volume and from the
// pockets behind a passage (narrow cells more open than the narrowest place on the widest way
// to them from the chosen volume: a space between parts reached through a narrower gap); the
// fronts meet at the narrowest places between them. The chosen volume's front keeps to its
// own side of the input: through a hole in a surface it would reach the surface's other face,
// and the hole is an opening. A groove or a slot narrower than the gap that leads nowhere is
// wrapped as without gap closure.
void reclaim_narrow_cells(AdaptiveGrid& g, const FreeLeaves& leaves, const std::vector<float>& clearance,
                          double half_gap, int32_t chosen, bool outside) {
  const size_t n = leaves.size();
  // The cells that take part: the narrow ones and the labelled ones beside them (none farther
  // from the input than the narrow ones by more than two of the largest cells), with their
  // values and their narrow face neighbours (read once, in parallel).
  const float beyond = float(half_gap + 2 * g.cell_size(0));
  std::vector<uint32_t> near;
  for (uint32_t i = 0; i < n; ++i)
    if (clearance[i] <= beyond) near.push_back(i);
  std::vector<int32_t> value(near.size());
  std::vector<uint32_t> first(near.size() + 1, 0), pos(n, UINT32_MAX);
  for (uint32_t k = 0; k < near.size(); ++k) pos[near[k]] = k;
  auto for_narrow_neighbours_in_grid = [&](uint32_t i, auto&& visit) {
    for (int axis = 0; axis < 3; ++axis)
      for (int dir = -1; dir <= 1; dir += 2)
        g.for_each_face_neighbour(leaves.level(i), leaves.coord(i), axis, dir, [&](const LeafRef& r) {
          if (r.outside_box || r.value != kNarrow) return;
          const int64_t j = leaves.find(r.level, r.ijk);
          if (j >= 0) visit(uint32_t(j));
        });
  };
  tbb::parallel_for(tbb::blocked_range<size_t>(0, near.size(), 256), [&](const tbb::blocked_range<size_t>& r) {
    for (size_t k = r.begin(); k != r.end(); ++k) {
      const uint32_t i = near[k];
      value[k] = g.get(leaves.level(i), leaves.coord(i));
      if (value[k] != kNarrow && value[k] < 1) continue;
      uint32_t count = 0;
      for_narrow_neighbours_in_grid(i, [&](uint32_t) { ++count; });
      first[k + 1] = count;
    }
  });
  for (size_t k = 0; k < near.size(); ++k) first[k + 1] += first[k];
  std::vector<uint32_t> neighbours(first.back());
  tbb::parallel_for(tbb::blocked_range<size_t>(0, near.size(), 256), [&](const tbb::blocked_range<size_t>& r) {
    for (size_t k = r.begin(); k != r.end(); ++k) {
      uint32_t at = first[k];
      if (at != first[k + 1]) for_narrow_neighbours_in_grid(near[k], [&](uint32_t j) { neighbours[at++] = j; });
    }
  });
  auto narrow = [&](uint32_t i) { return value[pos[i]] == kNarrow; };
  auto for_narrow_neighbours = [&](uint32_t i, auto&& visit) {
    for (uint32_t k = first[pos[i]]; k < first[pos[i] + 1]; ++k) visit(neighbours[k]);
  };
  // Cells of a labelled volume beside a narrow cell: where the fronts start.
  std::vector<uint32_t> starts;
  for (uint32_t k = 0; k < near.size(); ++k)
    if (value[k] >= 1 && first[k + 1] > first[k]) starts.push_back(near[k]);
  // The chosen volume's side of the input: in front of it for the outside (which may get
  // round to the back of open sheets, through their openings); for an enclosed volume, where
  // most of its cells beside the narrow ones lie (behind the input inside a solid, in front of
  // it in a cavity among parts).
  size_t behind = 0, in_front = 0;
  for (uint32_t i : starts)
    if (value[pos[i]] == chosen) ++(leaves.behind()[i] ? behind : in_front);
  const uint8_t other_side = !outside && behind > in_front ? 0 : 1;
  // The widest way from the chosen volume to each narrow cell: its narrowest clearance.
  std::vector<float> widest(n, -1.0f);
  {
    std::vector<uint8_t> done(n, 0);
    std::priority_queue<std::pair<float, uint32_t>> heap;
    for (uint32_t i : starts)
      if (value[pos[i]] == chosen) widest[i] = clearance[i], heap.push({clearance[i], i});
    while (!heap.empty()) {
      const float w = heap.top().first;
      const uint32_t i = heap.top().second;
      heap.pop();
      if (done[i]) continue;
      done[i] = 1;
      for_narrow_neighbours(i, [&](uint32_t j) {
        const float next = std::min(w, clearance[j]);
        if (!done[j] && next > widest[j]) widest[j] = next, heap.push({next, j});
      });
    }
  }
  // The flood: from every labelled volume, and from each narrow cell more open (by more than
  // its own size) than the way to it, narrow cells are taken most open first, each by the
  // front beside it; the fronts meet at the narrowest places between them, the openings.
  constexpr int32_t kPocket = 0;
  std::vector<int32_t> owner(n, kPocket);
  std::vector<uint8_t> taken(n, 0);
  std::priority_queue<std::pair<float, uint32_t>> heap;
  for (uint32_t i : starts) taken[i] = 1, owner[i] = value[pos[i]], heap.push({clearance[i], i});
  for (uint32_t i : near)
    if (narrow(i) && clearance[i] > widest[i] + g.cell_size(leaves.level(i)))
      taken[i] = 1, heap.push({clearance[i], i});
  while (!heap.empty()) {
    const float level = heap.top().first;
    const uint32_t i = heap.top().second;
    heap.pop();
    const int32_t label = owner[i];
    if (label == chosen && narrow(i)) g.set(leaves.level(i), leaves.coord(i), chosen);
    for_narrow_neighbours(i, [&](uint32_t j) {
      if (taken[j]) return;
      if (label == chosen && leaves.behind()[j] == other_side) return;
      taken[j] = 1, owner[j] = label;
      heap.push({std::min(level, clearance[j]), j});
    });
  }
}

}  // namespace

VolumeSelection select_volume(AdaptiveGrid& g, const VolumeRequest& req, const DistanceToInput& distance,
                              ProgressSink* progress) {
  VolumeSelection sel;
  sel.report.gap_closure = req.gap_closure;
  if (progress) progress->progress("flood fill", 0.0, "labelling free cells");
  const double r = 0.5 * req.gap_closure;
  // Every free cell numbered, with its clearance from the input: only for gap closure and
  // leak tracing. On a fine grid the free cells are most of the box (millions), and listing
  // them was most of this stage's time and the wrap's peak memory.
  std::optional<FreeLeaves> free_leaves;
  auto leaves = [&]() -> FreeLeaves& {
    if (!free_leaves) free_leaves.emplace(g);
    return *free_leaves;
  };

  // Gap closure: cells too close to the input for a ball of the gap's diameter stay out of
  // the flood (a narrow opening then does not connect two volumes); they are grown back below.
  if (r > 0) {
    const auto& clearance = leaves().clearance(distance, progress);
    for (uint32_t i = 0; i < leaves().size(); ++i)
      if (clearance[i] < r && !leaves().on_box_boundary(i)) g.set(leaves().level(i), leaves().coord(i), kNarrow);
  }
  Components comps = label_components(
      g, [](int32_t v) { return v == kFree; }, 1, progress);

  const double hf = g.fine_size();
  const double fine_volume = hf * hf * hf;
  sel.report.free_volumes = comps.count();
  // An enclosed volume counts when it holds at least one whole base cell: faces lying
  // exactly on cell faces touch the cells on both sides and can seal slivers of finer free
  // cells along edges, which enclose nothing the user would call a volume.
  for (size_t i = 0; i < comps.count(); ++i)
    if (!comps.touches_outside[i] && comps.holds_level0[i]) {
      ++sel.report.enclosed_volumes;
      sel.report.largest_enclosed = std::max(sel.report.largest_enclosed, comps.volume[i] * fine_volume);
    }
  sel.report.encloses_volume = sel.report.enclosed_volumes > 0;
  if (progress)
    progress->progress("flood fill", 0.5,
                       std::to_string(comps.count()) + " free volume(s), " +
                           std::to_string(sel.report.enclosed_volumes) + " enclosed by the input");

  std::vector<int32_t> chosen;
  const std::string gap_note = r > 0 ? " with this gap closure" : "";
  if (req.choice == VolumeChoice::Outside) {
    chosen.push_back(1);
  } else if (req.choice == VolumeChoice::Inside) {
    // Not a pocket under a base cell's volume, sealed along an open scan's bumps or pinched
    // off by a gap closure; a thin wall's material, all finer cells, is a volume.
    const int32_t best = largest_enclosed_label(comps, std::pow(double(g.fine_units(0)), 3));
    if (best < 0)
      throw Error(ErrorKind::WrapFailed,
                  "the input encloses no volume at this base size" + gap_note +
                      ": nothing to wrap from inside (try a smaller --base-size, a --gap-closure "
                      "larger than the holes, or a seed point to find the leak)");
    chosen.push_back(best);
  } else {
    if (req.seeds.empty()) throw Error(ErrorKind::InvalidArgument, "volume by seed points, but no seed point given");
    const int L = g.max_level();
    std::vector<LeafRef> seed_leaf;
    for (size_t s = 0; s < req.seeds.size(); ++s) {
      const Vec3 q = (req.seeds[s] - g.origin()) * (1.0 / hf);
      const std::string name = "seed point " + std::to_string(s + 1);
      Coord cell(int(std::floor(q[0])), int(std::floor(q[1])), int(std::floor(q[2])));
      const int32_t fu0 = g.fine_units(0);
      bool inside_box = true;
      for (int k = 0; k < 3; ++k) inside_box = inside_box && q[k] >= 0 && q[k] < double(g.dims0()[k]) * fu0;
      if (!inside_box)
        throw Error(ErrorKind::InvalidArgument,
                    name + " lies outside the model's bounding box: use --volume outside to wrap the outside");
      sel.anchors.push_back(cell);
      LeafRef leaf = g.leaf_at(L, cell);
      if (leaf.value == kTouched)
        throw Error(ErrorKind::InvalidArgument, name + " lies in a cell the input passes through (cells there are " +
                                                    std::to_string(g.cell_size(leaf.level)) +
                                                    " wide): move it farther into the volume");
      if (leaf.value == kNarrow)
        throw Error(ErrorKind::InvalidArgument,
                    name + " lies closer to the input than half the gap closure: move it farther into the volume");
      if (leaf.value < 1) throw Error(ErrorKind::Internal, name + ": its cell is not a free cell");
      seed_leaf.push_back(leaf);
      const int32_t label = leaf.value;
      // A leak: this seed's volume is the outside's, or another seed's.
      auto leak_to = [&](const LeafRef* target, const std::string& what) {
        if (progress) progress->progress("flood fill", 0.8, name + " " + what + ": tracing the leak");
        FreeLeaves& all = leaves();
        const auto& clearance = all.clearance(distance, progress);
        const int64_t from = all.find(leaf.level, leaf.ijk), to = target ? all.find(target->level, target->ijk) : -1;
        if (from < 0 || (target && to < 0)) throw Error(ErrorKind::Internal, name + ": its cell is not a free cell");
        sel.leak = widest_path(g, all, clearance, label, uint32_t(from), to);
        sel.leak.description = name + " " + point_text(req.seeds[s] + req.world_offset) + " " + what;
        sel.label = 0;
        return sel;
      };
      if (comps.touches_outside[size_t(label - comps.first_label)]) return leak_to(nullptr, "reaches the outside");
      for (size_t t = 0; t + 1 < seed_leaf.size(); ++t)
        if (g.get(seed_leaf[t].level, seed_leaf[t].ijk) == label)
          return leak_to(&seed_leaf[t], "reaches the volume of seed point " + std::to_string(t + 1));
      chosen.push_back(label);
    }
  }

  // One label for the whole chosen volume.
  sel.label = chosen.front();
  if (chosen.size() > 1) {
    g.relabel([&](int32_t v) { return std::find(chosen.begin(), chosen.end(), v) != chosen.end() ? sel.label : v; });
  }

  // Gap closure, second half: grow the volume back into the narrow cells within reach of a
  // ball of radius r centred in the volume (a cell centre within r of a chosen cell, give or
  // take the two cells' half diagonals).
  double volume = 0;
  if (r > 0) {
    FreeLeaves& leaves = *free_leaves;
    if (progress) progress->progress("flood fill", 0.9, "growing the volume back toward the input");
    struct Front {
      uint32_t cell;
      Vec3 source;
      double source_half_diagonal;
    };
    std::vector<Front> queue;
    for (uint32_t i = 0; i < leaves.size(); ++i)
      if (g.get(leaves.level(i), leaves.coord(i)) == sel.label)
        queue.push_back({i, leaves.centre(i), leaves.half_diagonal(i)});
    for (size_t q = 0; q < queue.size(); ++q) {
      const Front f = queue[q];
      for (int axis = 0; axis < 3; ++axis)
        for (int dir = -1; dir <= 1; dir += 2)
          g.for_each_face_neighbour(leaves.level(f.cell), leaves.coord(f.cell), axis, dir, [&](const LeafRef& n) {
            if (n.outside_box || n.value != kNarrow) return;
            int64_t j = leaves.find(n.level, n.ijk);
            if (j < 0) return;
            if (norm(leaves.centre(uint32_t(j)) - f.source) >
                r + f.source_half_diagonal + leaves.half_diagonal(uint32_t(j)))
              return;
            g.set(n.level, n.ijk, sel.label);
            queue.push_back({uint32_t(j), f.source, f.source_half_diagonal});
          });
    }
    reclaim_narrow_cells(g, leaves, leaves.clearance(distance, progress), r, sel.label,
                         req.choice == VolumeChoice::Outside);
    for (uint32_t i = 0; i < leaves.size(); ++i)
      if (g.get(leaves.level(i), leaves.coord(i)) == sel.label) {
        double h = g.cell_size(leaves.level(i));
        volume += h * h * h;
      }
  } else {
    // Without gap closure the chosen volume is the chosen components, as labelled.
    for (int32_t label : chosen) volume += comps.volume[size_t(label - comps.first_label)] * fine_volume;
  }
  sel.report.chosen_volume = volume;
  if (progress) progress->progress("flood fill", 1.0, std::to_string(comps.count()) + " free volume(s) found");
  return sel;
}

}  // namespace vdbwrap::grid
