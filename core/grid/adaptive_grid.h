// Stage 2 data: the structured 2x2x2 cell hierarchy of the spec, one OpenVDB Int32Grid per
// level. Level l has cells of size base/2^l; cell (i,j,k) at level l has the children
// (2i+a, 2j+b, 2k+c) at level l+1, so neighbours and parents are integer arithmetic.
// Positions are also given on the finest level's node lattice ("fine units").
#pragma once
#include <openvdb/openvdb.h>

#include <algorithm>
#include <cstdint>
#include <tuple>
#include <utility>
#include <vector>

#include "vdbwrap/mesh.h"

namespace vdbwrap::grid {

using openvdb::Coord;

// Cell values. Non-negative values >= 1 are component labels of free cells after the flood fill.
enum CellState : int32_t {
  kAbsent = 0,     // no cell at this level here (an ancestor is a leaf)
  kRefined = -1,   // split into 8 children one level down
  kTouched = -2,   // a leaf the input passes through
  kFree = -3,      // a leaf the input does not touch, not yet labelled
  kExcluded = -4,  // a free leaf taken out of the chosen volume (manifold repair)
  kNarrow = -5,    // a free leaf closer to the input than half the gap closure
};

struct LeafRef {
  int level = 0;
  Coord ijk;
  int32_t value = kAbsent;
  bool outside_box = false;  // beyond the padded level-0 box (always free, always outside)
};

class AdaptiveGrid {
 public:
  // origin: world position of lattice node (0,0,0); dims0: level-0 cells per axis.
  AdaptiveGrid(const Vec3& origin, double base_size, int levels, const Coord& dims0);

  int max_level() const { return levels_; }
  // Drops the levels below `levels` (they must hold no cell).
  void trim_levels(int levels) {
    levels_ = std::min(levels_, levels);
    grids_.resize(size_t(levels_) + 1);
  }
  double base_size() const { return base_size_; }
  double cell_size(int level) const { return base_size_ / double(1 << level); }
  double fine_size() const { return cell_size(levels_); }
  int32_t fine_units(int level) const { return 1 << (levels_ - level); }
  const Coord& dims0() const { return dims0_; }
  const Vec3& origin() const { return origin_; }

  bool in_box0(const Coord& c) const {
    return c.x() >= 0 && c.y() >= 0 && c.z() >= 0 && c.x() < dims0_.x() && c.y() < dims0_.y() && c.z() < dims0_.z();
  }
  // Value stored for cell c of `level` (level 0 reads kFree where nothing is stored).
  int32_t get(int level, const Coord& c) const;
  void set(int level, const Coord& c, int32_t value);

  // Reads through the trees (from the root each time; safe from any number of threads).
  struct TreeGet {
    const AdaptiveGrid* grid;
    int32_t operator()(int level, const Coord& c) const { return grid->get(level, c); }
  };
  // The leaf that contains cell c of `level` (c itself, or an ancestor). If c is refined,
  // returns c with value kRefined.
  LeafRef leaf_at(int level, const Coord& c) const { return leaf_at_by(TreeGet{this}, level, c); }

  // Calls f(LeafRef) for each leaf across face (axis, dir) of cell c: the same-or-coarser
  // neighbour, or all finer leaves of a refined neighbour that touch the face.
  template <typename F>
  void for_each_face_neighbour(int level, const Coord& c, int axis, int dir, F&& f) const {
    for_each_face_neighbour_by(TreeGet{this}, level, c, axis, dir, f);
  }

  // Cached access for a walk through neighbouring cells: VDB value accessors keep the nodes
  // last visited, where get() starts from the root every time. One per thread (or per chunk
  // of parallel work).
  template <typename Accessor>
  class Cached {
   public:
    int32_t get(int level, const Coord& c) { return acc_[size_t(level)].getValue(c); }
    LeafRef leaf_at(int level, const Coord& c) {
      return g_.leaf_at_by([this](int l, const Coord& x) { return get(l, x); }, level, c);
    }
    template <typename F>
    void for_each_face_neighbour(int level, const Coord& c, int axis, int dir, F&& f) {
      g_.for_each_face_neighbour_by([this](int l, const Coord& x) { return get(l, x); }, level, c, axis, dir, f);
    }
    bool uniform_block(const Coord& lo, int32_t& value) { return AdaptiveGrid::uniform_block(acc_[0], lo, value); }

   protected:
    explicit Cached(const AdaptiveGrid& g) : g_(g) {}
    const AdaptiveGrid& g_;
    std::vector<Accessor> acc_;
  };
  // Reads only, while nothing changes the grid.
  class Reader : public Cached<openvdb::Int32Grid::ConstAccessor> {
   public:
    explicit Reader(const AdaptiveGrid& g) : Cached(g) {
      for (const auto& grid : g.grids_) acc_.push_back(grid->getConstAccessor());
    }
  };
  // Reads and writes (the flood fill), while no other thread uses the grid.
  class Cursor : public Cached<openvdb::Int32Grid::Accessor> {
   public:
    explicit Cursor(AdaptiveGrid& g) : Cached(g) {
      for (auto& grid : g.grids_) acc_.push_back(grid->getAccessor());
    }
    void set(int level, const Coord& c, int32_t value) { acc_[size_t(level)].setValue(c, value); }
    // Every cell of the level-0 block at `lo` takes `value`: one VDB tile, no leaf node.
    // Putting a tile where a leaf node was deletes the leaf, but OpenVDB does not tell the
    // accessor, whose leaf cache would then hand out the freed node on the next read of that
    // block: the caches are dropped in that case.
    void set_block(const Coord& lo, int32_t value) {
      const bool had_leaf = acc_[0].probeConstLeaf(lo) != nullptr;
      acc_[0].addTile(1, lo, value, true);
      if (had_leaf) acc_[0].clear();
    }
  };

  // Level 0 is stored in blocks of a VDB leaf node's size. Most of the padded box is free
  // space far from the input, where a block has no leaf node: one value (the background, or
  // a tile the flood fill wrote) holds for all its cells, and whole blocks are read and
  // labelled at once instead of cell by cell.
  static constexpr int kBlock = int(openvdb::Int32Tree::LeafNodeType::DIM);
  struct Block {
    Coord lo, hi;  // cells lo .. hi - 1, clipped to the box
    size_t cells() const { return size_t(hi.x() - lo.x()) * size_t(hi.y() - lo.y()) * size_t(hi.z() - lo.z()); }
  };
  Block block_of(const Coord& c0) const {
    const Coord lo(c0.x() & ~(kBlock - 1), c0.y() & ~(kBlock - 1), c0.z() & ~(kBlock - 1));
    return {lo, Coord(std::min(lo.x() + kBlock, dims0_.x()), std::min(lo.y() + kBlock, dims0_.y()),
                      std::min(lo.z() + kBlock, dims0_.z()))};
  }
  // Does every cell of the level-0 block at `lo` hold the same value? (No leaf node there, or
  // a leaf whose cells all agree.)
  template <typename Accessor>
  static bool uniform_block(Accessor& level0, const Coord& lo, int32_t& value) {
    const auto* leaf = level0.probeConstLeaf(lo);
    if (!leaf) {
      value = level0.getValue(lo);
      return true;
    }
    value = leaf->getValue(0);
    for (openvdb::Index i = 1; i < openvdb::Int32Tree::LeafNodeType::SIZE; ++i)
      if (leaf->getValue(i) != value) return false;
    return true;
  }

  // Level 0 in the order z, y, x (the order of for_each_leaf), by rows of blocks: a uniform
  // block's cells in a row come as one run, on_run(first, length, value, block); the cells of
  // other blocks one by one, on_cell(c, value). Optionally only the planes z_begin <= z < z_end.
  template <typename OnRun, typename OnCell>
  void for_each_level0_run(OnRun&& on_run, OnCell&& on_cell, int z_begin = 0, int z_end = INT32_MAX) const {
    const Coord& d = dims0_;
    auto level0 = grids_[0]->getConstAccessor();
    for (int z = std::max(0, z_begin); z < std::min(d.z(), z_end); ++z)
      for (int y = 0; y < d.y(); ++y)
        for (int x0 = 0; x0 < d.x(); x0 += kBlock) {
          const Block b = block_of(Coord(x0, y, z));
          int32_t v;
          if (uniform_block(level0, b.lo, v)) {
            on_run(Coord(x0, y, z), b.hi.x() - x0, v, b);
            continue;
          }
          for (int x = x0; x < b.hi.x(); ++x) on_cell(Coord(x, y, z), level0.getValue(Coord(x, y, z)));
        }
  }
  // Level 0 by blocks, in no particular order: on_block(block, value) for a uniform block,
  // on_cell(c, value) for each cell of the others.
  template <typename OnBlock, typename OnCell>
  void for_each_level0_block(OnBlock&& on_block, OnCell&& on_cell) const {
    const Coord& d = dims0_;
    auto level0 = grids_[0]->getConstAccessor();
    for (int z0 = 0; z0 < d.z(); z0 += kBlock)
      for (int y0 = 0; y0 < d.y(); y0 += kBlock)
        for (int x0 = 0; x0 < d.x(); x0 += kBlock) {
          const Block b = block_of(Coord(x0, y0, z0));
          int32_t v;
          if (uniform_block(level0, b.lo, v)) {
            on_block(b, v);
            continue;
          }
          for (int z = z0; z < b.hi.z(); ++z)
            for (int y = y0; y < b.hi.y(); ++y)
              for (int x = x0; x < b.hi.x(); ++x) on_cell(Coord(x, y, z), level0.getValue(Coord(x, y, z)));
        }
  }
  // Calls f(level, coord, value) for every leaf cell of the levels above 0.
  template <typename F>
  void for_each_fine_leaf(F&& f) const {
    for (int l = 1; l <= levels_; ++l)
      for (auto it = grids_[l]->cbeginValueOn(); it; ++it)
        if (*it != kRefined && *it != kAbsent) f(l, it.getCoord(), *it);
  }

  // Calls f(level, coord, value) for every leaf cell in the box, level 0 first (in the order
  // z, y, x), then the finer levels.
  template <typename F>
  void for_each_leaf(F&& f) const {
    for_each_level0_run(
        [&](const Coord& first, int length, int32_t v, const Block&) {
          if (v == kRefined) return;
          for (int x = first.x(); x < first.x() + length; ++x) f(0, Coord(x, first.y(), first.z()), v);
        },
        [&](const Coord& c, int32_t v) {
          if (v != kRefined) f(0, c, v);
        });
    for_each_fine_leaf(f);
  }

  // Every leaf whose value v changes under new_value(v) takes the new value; a uniform level-0
  // block changes whole (one tile). (Collected first: changing while iterating a VDB tree
  // would invalidate the iterator.)
  template <typename F>
  void relabel(F&& new_value) {
    std::vector<std::pair<Coord, int32_t>> blocks;
    std::vector<std::tuple<int, Coord, int32_t>> cells;
    auto note = [&](int level, const Coord& c, int32_t v) {
      if (v == kRefined) return;
      const int32_t w = new_value(v);
      if (w != v) cells.emplace_back(level, c, w);
    };
    for_each_level0_block(
        [&](const Block& b, int32_t v) {
          if (v == kRefined) return;
          const int32_t w = new_value(v);
          if (w != v) blocks.emplace_back(b.lo, w);
        },
        [&](const Coord& c, int32_t v) { note(0, c, v); });
    for_each_fine_leaf(note);
    Cursor cursor(*this);
    for (const auto& [lo, w] : blocks) cursor.set_block(lo, w);
    for (const auto& [level, c, w] : cells) cursor.set(level, c, w);
  }

  // World position of a fine-lattice node.
  Vec3 node_position(const Coord& fine) const {
    double h = fine_size();
    return {origin_[0] + fine.x() * h, origin_[1] + fine.y() * h, origin_[2] + fine.z() * h};
  }

  openvdb::Int32Grid::Ptr level_grid(int level) const { return grids_[level]; }

 private:
  template <typename Get>
  LeafRef leaf_at_by(Get&& get, int level, const Coord& c) const {
    Coord c0(c.x() >> level, c.y() >> level, c.z() >> level);  // arithmetic shift = floor division
    if (!in_box0(c0)) return LeafRef{0, c0, 1, true};
    for (int l = 0; l <= level; ++l) {
      int s = level - l;
      Coord cl(c.x() >> s, c.y() >> s, c.z() >> s);
      int32_t v = get(l, cl);
      if (v != kRefined) return LeafRef{l, cl, v, false};
    }
    return LeafRef{level, c, kRefined, false};
  }
  template <typename Get, typename F>
  void for_each_face_neighbour_by(Get&& get, int level, const Coord& c, int axis, int dir, F& f) const {
    Coord n = c;
    n[axis] += dir;
    LeafRef r = leaf_at_by(get, level, n);
    if (r.value != kRefined) {
      f(r);
      return;
    }
    descend_face(get, level, n, axis, dir, f);
  }
  template <typename Get, typename F>
  void descend_face(Get& get, int level, const Coord& n, int axis, int dir, F& f) const {
    // Children of n on the side facing the cell we came from (dir>0: low side of n).
    int side = dir > 0 ? 0 : 1;
    for (int a = 0; a < 2; ++a)
      for (int b = 0; b < 2; ++b) {
        int bits[3];
        bits[axis] = side;
        bits[(axis + 1) % 3] = a;
        bits[(axis + 2) % 3] = b;
        Coord child(2 * n.x() + bits[0], 2 * n.y() + bits[1], 2 * n.z() + bits[2]);
        int32_t v = get(level + 1, child);
        if (v == kRefined)
          descend_face(get, level + 1, child, axis, dir, f);
        else
          f(LeafRef{level + 1, child, v, false});
      }
  }

  Vec3 origin_;
  double base_size_;
  int levels_;
  Coord dims0_;
  std::vector<openvdb::Int32Grid::Ptr> grids_;
};

}  // namespace vdbwrap::grid
