// Lists of indices for items 0..n-1 in one array (compressed rows): the neighbours of every
// node of a wrap, the triangles around every vertex. A vector per item is a heap block per
// item, and allocating them is serial: one array filled in parallel instead.
#pragma once
#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <vector>

#include <tbb/parallel_for.h>

#include "common/fill_vector.h"

namespace vdbwrap {

struct CompressedLists {
  std::vector<uint32_t> first{0};  // list i: items[first[i] .. first[i + 1])
  FillVector<uint32_t> items;

  struct Range {
    const uint32_t *b, *e;
    const uint32_t* begin() const { return b; }
    const uint32_t* end() const { return e; }
    size_t size() const { return size_t(e - b); }
    bool empty() const { return b == e; }
  };
  size_t size() const { return first.size() - 1; }
  Range operator[](size_t i) const { return {items.data() + first[i], items.data() + first[i + 1]}; }
};

// Lists for n items from the pairs for_each_pair(emit) gives as emit(list, item). It is
// called twice, counting then placing, and must give the same pairs both times; each list
// keeps the order its pairs came in.
template <typename ForEachPair>
CompressedLists compressed_lists(size_t n, ForEachPair&& for_each_pair) {
  CompressedLists out;
  out.first.assign(n + 1, 0);
  for_each_pair([&](uint32_t list, uint32_t) { ++out.first[list + 1]; });
  for (size_t i = 0; i < n; ++i) out.first[i + 1] += out.first[i];
  out.items.resize(out.first[n]);
  std::vector<uint32_t> next(out.first.begin(), out.first.end() - 1);
  for_each_pair([&](uint32_t list, uint32_t item) { out.items[next[list]++] = item; });
  return out;
}

// The triangles around each of n vertices, in increasing order (a triangle with a repeated
// vertex is listed once for each corner).
template <typename Triangles>
CompressedLists vertex_triangle_lists(size_t n, const Triangles& triangles) {
  return compressed_lists(n, [&](auto&& emit) {
    for (uint32_t f = 0; f < triangles.size(); ++f)
      for (uint32_t v : triangles[f]) emit(v, f);
  });
}

// The lists as one vector each, for lists that change afterwards: each made at its final
// size, in parallel (pushing item by item reallocated most lists a few times, serially).
inline std::vector<std::vector<uint32_t>> to_vectors(const CompressedLists& lists) {
  std::vector<std::vector<uint32_t>> out(lists.size());
  tbb::parallel_for(tbb::blocked_range<size_t>(0, lists.size(), 4096), [&](const tbb::blocked_range<size_t>& r) {
    for (size_t i = r.begin(); i != r.end(); ++i) out[i].assign(lists[i].begin(), lists[i].end());
  });
  return out;
}

// Every list sorted and its repeats dropped (in parallel), then the arrays closed up.
inline void sort_and_unique(CompressedLists& lists) {
  const size_t n = lists.size();
  std::vector<uint32_t> kept(n + 1, 0);
  tbb::parallel_for(tbb::blocked_range<size_t>(0, n, 4096), [&](const tbb::blocked_range<size_t>& r) {
    for (size_t i = r.begin(); i != r.end(); ++i) {
      uint32_t *b = lists.items.data() + lists.first[i], *e = lists.items.data() + lists.first[i + 1];
      std::sort(b, e);
      kept[i + 1] = uint32_t(std::unique(b, e) - b);
    }
  });
  for (size_t i = 0; i < n; ++i) kept[i + 1] += kept[i];
  FillVector<uint32_t> items(kept[n]);
  tbb::parallel_for(tbb::blocked_range<size_t>(0, n, 4096), [&](const tbb::blocked_range<size_t>& r) {
    for (size_t i = r.begin(); i != r.end(); ++i)
      std::copy_n(lists.items.data() + lists.first[i], kept[i + 1] - kept[i], items.data() + kept[i]);
  });
  lists.items.swap(items);
  lists.first.swap(kept);
}

}  // namespace vdbwrap
