// Triangles bucketed by bounding box on a uniform grid: the neighbours of a few changed
// triangles, for local intersection checks (projection's validity loop, coarsening).
#pragma once
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <utility>
#include <vector>

#include <tbb/parallel_for.h>

#include "common/cell_lists.h"
#include "common/dense_numbers.h"
#include "common/fill_vector.h"
#include "common/grid_key.h"
#include "common/radix_sort.h"
#include "common/vec.h"

namespace vdbwrap {

// Triangles bucketed by bounding box on a uniform grid, so that the triangles around a few
// moved nodes are tested against their neighbours only. Buckets may hold stale entries
// (a triangle that moved away); bounding boxes are compared before any exact test.
class TriangleBuckets {
 public:
  TriangleBuckets(const std::vector<Vec3>& p, const std::vector<Tri>& tris, double cell)
      : p_(p), tris_(tris), inv_(1.0 / cell), cells_(cell) {
    // Room for the triangles feature insertion appends (tens of thousands on a large wrap),
    // reserved, not touched: each growth had copied every box into fresh pages.
    boxes_.reserve(tris.size() + tris.size() / 8 + 64);
    boxes_.resize(tris.size());  // written by build_sorted, in parallel
    if (!build_sorted()) {
      std::fill(boxes_.begin(), boxes_.end(), Box3{});  // none inserted yet
      for (uint32_t f = 0; f < tris.size(); ++f) insert(f);
    }
  }
  // After triangle f moved, or was appended to the triangle list.
  void update(uint32_t f) { insert(f); }
  // After triangle f changed: it leaves the cells its new box does not cover, so that every
  // entry is current. With add_cells false, every cell of the new box must exist already
  // (see covers): the map is then only read, and threads may move triangles in disjoint
  // regions at once (a cell holds only triangles whose boxes overlap it, so no thread reads
  // an entry another one writes).
  void move(uint32_t f, bool add_cells) {
    const Box3 old = boxes_[f];
    Box3 b;
    for (uint32_t v : tris_[f]) b.add(p_[v]);
    boxes_[f] = b;
    int64_t lo[3], hi[3], olo[3], ohi[3];
    cell_range(b, lo, hi);
    cell_range(old, olo, ohi);
    auto inside = [](const Key& k, const int64_t l[3], const int64_t h[3]) {
      return k.x >= l[0] && k.x <= h[0] && k.y >= l[1] && k.y <= h[1] && k.z >= l[2] && k.z <= h[2];
    };
    for_cells(old, [&](const Key& k) {
      if (inside(k, lo, hi)) return;
      auto& list = *cells_.find(k);
      auto it = std::find(list.begin(), list.end(), f);
      *it = list.back(), list.pop_back();
    });
    for_cells(b, [&](const Key& k) {
      if (inside(k, olo, ohi)) return;
      (add_cells ? cells_[k] : *cells_.find(k)).push_back(f);
    });
  }
  // Do all cells of box b exist already?
  bool covers(const Box3& b) const {
    bool all = true;
    for_cells(b, [&](const Key& k) { all = all && cells_.has(k); });
    return all;
  }
  // The bounding box of triangle f when it was last inserted or updated.
  const Box3& box(uint32_t f) const { return boxes_[f]; }
  // Triangles whose (bucketed) bounding box overlaps that of triangle f, f excluded.
  template <typename F>
  void for_each_candidate(uint32_t f, F&& fn) {
    for_each_in_box(boxes_[f], [&](uint32_t g) {
      if (g != f) fn(g);
    });
  }
  // Triangles whose (bucketed) bounding box overlaps b.
  template <typename F>
  void for_each_in_box(const Box3& b, F&& fn) {
    for_each_in_box(b, seen_, stamp_, std::forward<F>(fn));
  }

  // The same, const, with the caller's marks, so that several threads may query at once while
  // nothing is updated; each thread brings its own (`seen` and `stamp`, both start at 0).
  template <typename F>
  void for_each_in_box(const Box3& b, std::vector<uint32_t>& seen, uint32_t& stamp, F&& fn) const {
    if (seen.size() < boxes_.size()) seen.resize(boxes_.size(), 0);
    ++stamp;
    cells_.for_lists(b, [&](const std::vector<uint32_t>& list) {
      // The box first: most entries are beside b, and their marks are then never written
      // (a write to the marks, scattered over the whole surface, missed the cache each time).
      for (uint32_t g : list) {
        if (!boxes_[g].overlaps(b) || seen[g] == stamp) continue;
        seen[g] = stamp;
        fn(g);
      }
    });
  }

 private:
  using Key = GridKey;
  void cell_range(const Box3& b, int64_t lo[3], int64_t hi[3]) const {
    for (int k = 0; k < 3; ++k)
      lo[k] = int64_t(std::floor(b.lo[k] * inv_)), hi[k] = int64_t(std::floor(b.hi[k] * inv_));
  }
  template <typename F>
  void for_cells(const Box3& b, F&& fn) const {
    cells_.for_cells(b, std::forward<F>(fn));
  }
  // Entries are never removed, so f is already in every cell of the box it had: only cells new
  // to it get an entry. (Appending to all of them again made most entries duplicates, read
  // over and over.)
  void insert(uint32_t f) {
    if (f >= boxes_.size()) boxes_.resize(f + 1, Box3{});
    Box3 b;
    for (uint32_t v : tris_[f]) b.add(p_[v]);
    const bool had = !boxes_[f].empty();
    int64_t lo[3] = {0, 0, 0}, hi[3] = {-1, -1, -1};
    if (had) cell_range(boxes_[f], lo, hi);
    boxes_[f] = b;
    for_cells(b, [&](const Key& k) {
      if (had && k.x >= lo[0] && k.x <= hi[0] && k.y >= lo[1] && k.y <= hi[1] && k.z >= lo[2] && k.z <= hi[2]) return;
      auto& list = cells_[k];
      if (list.empty() || list.back() != f) list.push_back(f);
    });
  }
  // All triangles at once, as inserting them one by one in order would leave the cells (each
  // cell's list in increasing order): their (cell, triangle) entries made in parallel and
  // radix-sorted by cell, then one list per cell (inserting them one by one is serial).
  // False, with nothing done, when the cells' numbers would not fit in 64 bits.
  bool build_sorted() {
    const size_t n = tris_.size();
    constexpr size_t kChunk = 4096;
    const size_t chunks = (n + kChunk - 1) / kChunk;
    std::vector<Box3> chunk_box(chunks);
    tbb::parallel_for(size_t(0), chunks, [&](size_t c) {
      for (size_t f = c * kChunk; f < std::min(n, (c + 1) * kChunk); ++f) {
        Box3 b;
        for (uint32_t v : tris_[f]) b.add(p_[v]);
        boxes_[f] = b;
        if (!b.empty()) chunk_box[c].add(b.lo), chunk_box[c].add(b.hi);
      }
    });
    Box3 all;
    for (const Box3& b : chunk_box)
      if (!b.empty()) all.add(b.lo), all.add(b.hi);
    if (all.empty()) return true;  // no triangle has a box: no cells
    std::array<int64_t, 3> lo, hi;
    std::array<uint64_t, 3> cells;
    double count = 1;
    for (int k = 0; k < 3; ++k) {
      const double l = std::floor(all.lo[k] * inv_), h = std::floor(all.hi[k] * inv_);
      if (!(std::fabs(l) < 1e15 && std::fabs(h) < 1e15)) return false;  // far out, or not finite
      lo[k] = int64_t(l), hi[k] = int64_t(h);
      cells[k] = uint64_t(hi[k] - lo[k] + 1);
      count *= double(cells[k]);
    }
    if (!(count < 1e18)) return false;
    const DenseNumbers numbers(lo, cells);
    struct Entry {
      uint64_t cell;
      uint32_t triangle;
    };
    std::vector<std::vector<Entry>> parts(chunks);
    tbb::parallel_for(size_t(0), chunks, [&](size_t c) {
      for (size_t f = c * kChunk; f < std::min(n, (c + 1) * kChunk); ++f)
        if (!boxes_[f].empty())
          for_cells(boxes_[f], [&](const Key& k) { parts[c].push_back({numbers.number(k.x, k.y, k.z), uint32_t(f)}); });
    });
    const FillVector<Entry> sorted = radix_sort_joined(
        parts, [](const Entry& e) { return e.cell; }, bits_for(numbers.count));
    const std::vector<size_t> runs = run_starts(sorted, [](const Entry& e) { return e.cell; });
    std::vector<std::vector<uint32_t>> lists(runs.size() - 1);  // made in parallel, moved into the map
    tbb::parallel_for(tbb::blocked_range<size_t>(0, lists.size(), 1024), [&](const tbb::blocked_range<size_t>& r) {
      for (size_t k = r.begin(); k != r.end(); ++k) {
        lists[k].resize(runs[k + 1] - runs[k]);
        for (size_t i = runs[k]; i < runs[k + 1]; ++i) lists[k][i - runs[k]] = sorted[i].triangle;
      }
    });
    cells_.reserve(lists.size());
    for (size_t k = 0; k < lists.size(); ++k) {
      const std::array<int64_t, 3> at = numbers.point(sorted[runs[k]].cell);
      cells_.set(Key{at[0], at[1], at[2]}, std::move(lists[k]));
    }
    return true;
  }

  const std::vector<Vec3>& p_;
  const std::vector<Tri>& tris_;
  double inv_;
  RawFillVector<Box3> boxes_;
  std::vector<uint32_t> seen_;  // for_each_in_box's marks, sized when first used
  uint32_t stamp_ = 0;
  CellLists<> cells_;
};

}  // namespace vdbwrap
