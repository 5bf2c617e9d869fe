// The broad phase of the pair search: candidate pairs of triangles whose boxes overlap, by a
// uniform grid, with CGAL's box intersection for the few boxes the grid does not suit.
#pragma once
#include <CGAL/Bbox_3.h>
#include <CGAL/box_intersection_d.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_sort.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <vector>

#include "common/dense_numbers.h"
#include "common/fill_vector.h"
#include "common/radix_sort.h"

namespace vdbwrap::check::pair_search {

using Box = CGAL::Box_intersection_d::Box_with_handle_d<double, 3, size_t, CGAL::Box_intersection_d::ID_EXPLICIT>;

// A box as the pair search keeps it: plain doubles, so that millions of them are filled in
// parallel without constructing CGAL boxes (each takes a number from a shared counter).
struct Bounds {
  double lo[3], hi[3];
  double min_coord(int axis) const { return lo[axis]; }
  double max_coord(int axis) const { return hi[axis]; }
  CGAL::Bbox_3 bbox() const { return CGAL::Bbox_3(lo[0], lo[1], lo[2], hi[0], hi[1], hi[2]); }
  bool overlaps(const Bounds& o) const {
    return lo[0] <= o.hi[0] && o.lo[0] <= hi[0] && lo[1] <= o.hi[1] && o.lo[1] <= hi[1] && lo[2] <= o.hi[2] &&
           o.lo[2] <= hi[2];
  }
  static Bounds of(const CGAL::Bbox_3& b) { return {{b.xmin(), b.ymin(), b.zmin()}, {b.xmax(), b.ymax(), b.zmax()}}; }
};

// Candidate pairs by a uniform grid. Most triangle sets checked here are wraps: triangles of a
// few sizes, spread over a surface. With cells about twice the typical triangle, a cell holds a
// handful of triangles, and sorting (cell, box) entries is cheaper than CGAL's box
// intersection, which sorts and scans all boxes along each axis at each level of its segment
// tree. A pair is tested only in the cell holding the low corner of the two boxes' overlap, so once. Boxes spanning
// many cells go to CGAL's box intersection instead.
struct GridEntry {
  uint64_t cell;
  uint32_t group;  // boxes of one group are never paired (kNoGroup: paired with all)
  uint32_t box;
};
constexpr uint32_t kNoGroup = UINT32_MAX;

// `group` (per box): pairs within one group are left out (see star_shaped_pieces).
template <typename Test>
void grid_candidate_pairs(const FillVector<Bounds>& boxes, const std::vector<uint32_t>& group, Test&& test) {
  if (boxes.size() < 2) return;
  std::vector<double> extents;
  extents.reserve(boxes.size());
  CGAL::Bbox_3 all;
  for (const Bounds& b : boxes) {
    extents.push_back(
        std::max({b.max_coord(0) - b.min_coord(0), b.max_coord(1) - b.min_coord(1), b.max_coord(2) - b.min_coord(2)}));
    all += b.bbox();
  }
  std::nth_element(extents.begin(), extents.begin() + extents.size() / 2, extents.end());
  double cell = 2 * extents[extents.size() / 2];
  const double span = std::max({all.xmax() - all.xmin(), all.ymax() - all.ymin(), all.zmax() - all.zmin()});
  cell = std::max(cell, span / double(1 << 20));  // 21 bits per axis in a cell key
  if (!(cell > 0) || !std::isfinite(cell)) {
    std::vector<Box> all_boxes;
    for (size_t n = 0; n < boxes.size(); ++n) all_boxes.emplace_back(boxes[n].bbox(), n);
    CGAL::box_self_intersection_d<CGAL::Parallel_if_available_tag>(
        all_boxes.begin(), all_boxes.end(),
        [&](const Box& a, const Box& b) { test(uint32_t(a.handle()), uint32_t(b.handle())); });
    return;
  }
  const double inv = 1.0 / cell;
  auto index = [&](double x, int axis) { return int64_t((x - all.min(axis)) * inv); };  // >= 0: truncation is floor
  std::array<uint64_t, 3> cells_along;
  for (int a = 0; a < 3; ++a) cells_along[a] = uint64_t(index(all.max(a), a)) + 1;
  const DenseNumbers numbers({0, 0, 0}, cells_along);
  auto key = [&](int64_t i, int64_t j, int64_t k) { return numbers.number(i, j, k); };
  constexpr int64_t max_cells = 27;  // more, and the triangle goes to the box intersection
  auto cell_range = [&](const Bounds& b, int64_t lo[3], int64_t hi[3]) {
    for (int a = 0; a < 3; ++a) lo[a] = index(b.min_coord(a), a), hi[a] = index(b.max_coord(a), a);
    const int64_t cells = (hi[0] - lo[0] + 1) * (hi[1] - lo[1] + 1) * (hi[2] - lo[2] + 1);
    return cells > max_cells ? 0 : size_t(cells);  // 0: a large box
  };
  // The (cell, triangle) entries in parallel, in chunks of boxes joined in order, then sorted
  // by (cell, group) with a stable radix sort, so each run of one group keeps its boxes in
  // order (the order the pair loop needs; the same on any number of threads). The keys are
  // short, so a radix sort beats a comparison sort on this many entries.
  constexpr size_t kChunk = 4096;
  const size_t chunks = (boxes.size() + kChunk - 1) / kChunk;
  std::vector<std::vector<GridEntry>> chunk_entries(chunks);
  std::vector<uint8_t> is_large(boxes.size(), 0);
  uint32_t groups = 0;  // one more than the largest group other than kNoGroup
  for (uint32_t g : group)
    if (g != kNoGroup) groups = std::max(groups, g + 1);
  tbb::parallel_for(size_t(0), chunks, [&](size_t chunk) {
    int64_t lo[3], hi[3];
    for (size_t n = chunk * kChunk; n < std::min(boxes.size(), (chunk + 1) * kChunk); ++n) {
      if (cell_range(boxes[n], lo, hi) == 0) {
        is_large[n] = 1;
        continue;
      }
      for (int64_t i = lo[0]; i <= hi[0]; ++i)
        for (int64_t j = lo[1]; j <= hi[1]; ++j)
          for (int64_t k = lo[2]; k <= hi[2]; ++k)
            chunk_entries[chunk].push_back({key(i, j, k), group[n], uint32_t(n)});
    }
  });
  std::vector<Box> large;
  for (size_t n = 0; n < boxes.size(); ++n)
    if (is_large[n]) large.emplace_back(boxes[n].bbox(), n);
  // kNoGroup sorts after every group, as its number does.
  const int group_bits = bits_for(uint64_t(groups) + 1), cell_bits = bits_for(numbers.count);
  const uint64_t no_group = (uint64_t(1) << group_bits) - 1;
  FillVector<GridEntry> entries;
  if (group_bits + cell_bits <= 64) {
    entries = radix_sort_joined(
        chunk_entries,
        [&](const GridEntry& e) {
          return (e.cell << group_bits) | (e.group == kNoGroup ? no_group : uint64_t(e.group));
        },
        group_bits + cell_bits);
  } else {  // a key too wide for one word
    size_t total = 0;
    for (const auto& c : chunk_entries) total += c.size();
    entries = FillVector<GridEntry>(total);
    size_t e = 0;
    for (auto& c : chunk_entries) {
      for (const GridEntry& x : c) entries[e++] = x;
      std::vector<GridEntry>().swap(c);
    }
    tbb::parallel_sort(entries.begin(), entries.end(), [](const GridEntry& x, const GridEntry& y) {
      return x.cell != y.cell ? x.cell < y.cell : x.group != y.group ? x.group < y.group : x.box < y.box;
    });
  }
  std::vector<size_t> starts;
  for (size_t e = 0; e < entries.size(); ++e)
    if (e == 0 || entries[e].cell != entries[e - 1].cell) starts.push_back(e);
  starts.push_back(entries.size());
  tbb::parallel_for(tbb::blocked_range<size_t>(0, starts.size() - 1, 64), [&](const tbb::blocked_range<size_t>& r) {
    for (size_t c = r.begin(); c != r.end(); ++c) {
      const uint64_t here = entries[starts[c]].cell;
      size_t group_end = starts[c];  // end of x's run of one group in the cell
      for (size_t x = starts[c]; x < starts[c + 1]; ++x) {
        if (x == group_end)
          while (group_end < starts[c + 1] && entries[group_end].group == entries[x].group) ++group_end;
        for (size_t y = entries[x].group == kNoGroup ? x + 1 : group_end; y < starts[c + 1]; ++y) {
          const Bounds &a = boxes[entries[x].box], &b = boxes[entries[y].box];
          if (!a.overlaps(b)) continue;
          const double cx = std::max(a.min_coord(0), b.min_coord(0)), cy = std::max(a.min_coord(1), b.min_coord(1)),
                       cz = std::max(a.min_coord(2), b.min_coord(2));
          if (key(index(cx, 0), index(cy, 1), index(cz, 2)) != here) continue;  // tested in that cell
          test(entries[x].box, entries[y].box);
        }
      }
    }
  });
  if (large.empty()) return;
  // A few large boxes (a wrap's coarse triangles) are tested against every box directly, in
  // parallel: CGAL's box intersection would sort all the small boxes for them.
  constexpr size_t few = 64;
  if (large.size() <= few) {
    std::vector<uint32_t> large_ids;
    for (const Box& b : large) large_ids.push_back(uint32_t(b.handle()));
    for (size_t i = 0; i < large_ids.size(); ++i)
      for (size_t j = i + 1; j < large_ids.size(); ++j)
        if (boxes[large_ids[i]].overlaps(boxes[large_ids[j]])) test(large_ids[i], large_ids[j]);
    tbb::parallel_for(tbb::blocked_range<size_t>(0, boxes.size(), 4096), [&](const tbb::blocked_range<size_t>& r) {
      for (size_t n = r.begin(); n != r.end(); ++n) {
        if (is_large[n]) continue;
        for (uint32_t l : large_ids)
          if (boxes[l].overlaps(boxes[n])) test(l, uint32_t(n));
      }
    });
    return;
  }
  std::vector<Box> small;
  small.reserve(boxes.size() - large.size());
  for (size_t n = 0; n < boxes.size(); ++n)
    if (!is_large[n]) small.emplace_back(boxes[n].bbox(), n);
  auto report = [&](const Box& a, const Box& b) { test(uint32_t(a.handle()), uint32_t(b.handle())); };
  // Below this many boxes CGAL's segment tree scans instead of splitting further. Its default
  // (10) splits the long triangles of CAD cylinders, which share their ends' coordinates, over
  // and over, sorting them each time; a few hundred stops that, and scanning that many is
  // still cheap (far larger cutoffs scan too much).
  constexpr std::ptrdiff_t cutoff = 300;
  CGAL::box_self_intersection_d<CGAL::Parallel_if_available_tag>(large.begin(), large.end(), report, cutoff);
  CGAL::box_intersection_d<CGAL::Parallel_if_available_tag>(large.begin(), large.end(), small.begin(), small.end(),
                                                            report, cutoff);
}

}  // namespace vdbwrap::check::pair_search
