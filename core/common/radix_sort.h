// A stable radix sort by an unsigned integer key, in parallel: for the tens of millions of
// (cell, triangle) entries of a large input, where a comparison sort took seconds.
#pragma once
#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <vector>

#include <tbb/parallel_for.h>

#include "common/fill_vector.h"

namespace vdbwrap {

// The number of bits needed to hold values below `count`.
inline int bits_for(uint64_t count) {
  int bits = 0;
  while (bits < 64 && (uint64_t(1) << bits) < count) ++bits;
  return bits;
}

// The items of `parts` joined in order, then sorted by key(item), items with equal keys kept
// in order. Only the low key_bits bits of the keys are looked at (all higher bits must be
// zero). Least significant digit first, at most 12 bits a pass; each pass counts digits per
// part in parallel, then each part moves its items to their places in parallel. The first
// pass reads the parts themselves (and frees them), so they are never copied into one array
// first. The result does not depend on the number of threads.
template <typename T, typename Key>
FillVector<T> radix_sort_joined(std::vector<std::vector<T>>& parts, Key&& key, int key_bits) {
  const int passes = std::max(1, (key_bits + 11) / 12);
  const int digit_bits = std::max(1, (key_bits + passes - 1) / passes);
  const size_t buckets = size_t(1) << digit_bits;
  // Long parts are read in slices, so that both threads have work in every pass.
  struct Slice {
    size_t part, begin, end;
  };
  size_t n = 0;
  for (const auto& p : parts) n += p.size();
  if (n == 0) {
    std::vector<std::vector<T>>().swap(parts);
    return {};
  }
  const size_t slice = std::max<size_t>(size_t(1) << 15, n / 256 + 1);
  std::vector<Slice> slices;
  for (size_t p = 0; p < parts.size(); ++p)
    for (size_t b = 0; b < parts[p].size(); b += slice) slices.push_back({p, b, std::min(parts[p].size(), b + slice)});
  FillVector<T> items(n), moved;
  std::vector<size_t> place(std::max<size_t>(1, slices.size()) * buckets);
  auto plan = [&](size_t s_count) {  // counts -> first places: by digit, then by slice
    size_t next = 0;
    for (size_t d = 0; d < buckets; ++d)
      for (size_t s = 0; s < s_count; ++s) {
        const size_t count = place[s * buckets + d];
        place[s * buckets + d] = next;
        next += count;
      }
  };
  for (int pass = 0; pass < passes; ++pass) {
    const int shift = pass * digit_bits;
    auto digit = [&](const T& item) { return size_t(uint64_t(key(item)) >> shift) & (buckets - 1); };
    if (pass == 0) {
      tbb::parallel_for(size_t(0), slices.size(), [&](size_t s) {
        size_t* count = &place[s * buckets];
        std::fill(count, count + buckets, 0);
        const auto& p = parts[slices[s].part];
        for (size_t i = slices[s].begin; i < slices[s].end; ++i) ++count[digit(p[i])];
      });
      plan(slices.size());
      tbb::parallel_for(size_t(0), slices.size(), [&](size_t s) {
        size_t* at = &place[s * buckets];
        const auto& p = parts[slices[s].part];
        for (size_t i = slices[s].begin; i < slices[s].end; ++i) items[at[digit(p[i])]++] = p[i];
      });
      std::vector<std::vector<T>>().swap(parts);
      continue;
    }
    const size_t chunks = (n + slice - 1) / slice;
    if (moved.size() != n) moved.resize(n);
    tbb::parallel_for(size_t(0), chunks, [&](size_t c) {
      size_t* count = &place[c * buckets];
      std::fill(count, count + buckets, 0);
      for (size_t i = c * slice, end = std::min(n, i + slice); i < end; ++i) ++count[digit(items[i])];
    });
    plan(chunks);
    tbb::parallel_for(size_t(0), chunks, [&](size_t c) {
      size_t* at = &place[c * buckets];
      for (size_t i = c * slice, end = std::min(n, i + slice); i < end; ++i) moved[at[digit(items[i])]++] = items[i];
    });
    items.swap(moved);
  }
  return items;
}

// The items of `parts` joined and sorted by `less`, for keys too wide for a radix sort alone:
// Where each run of equal keys starts in sorted items, then the end: run r is
// [starts[r], starts[r + 1]).
template <typename Items, typename Key>
std::vector<size_t> run_starts(const Items& sorted, Key&& key) {
  std::vector<size_t> starts;
  for (size_t i = 0; i < sorted.size(); ++i)
    if (i == 0 || key(sorted[i]) != key(sorted[i - 1])) starts.push_back(i);
  starts.push_back(sorted.size());
  return starts;
}

// `bucket(item)` (below 2^bucket_bits) must follow `less` (less(a, b) implies bucket(a) <=
// bucket(b)), so a stable radix sort by bucket and then a sort of each bucket by `less`
// give the order of one sort by `less`. Buckets are cut into slices at bucket starts and
// sorted in parallel: for many small buckets (the high bits of a hash, the smaller vertex
// of an edge), where a parallel comparison sort of millions of items took most of a second.
template <typename T, typename Bucket, typename Less>
FillVector<T> radix_then_sort(std::vector<std::vector<T>>& parts, Bucket&& bucket, int bucket_bits, Less&& less) {
  FillVector<T> items = radix_sort_joined(parts, bucket, bucket_bits);
  const size_t n = items.size();
  auto bucket_start_at_or_after = [&](size_t k) {
    while (k > 0 && k < n && bucket(items[k]) == bucket(items[k - 1])) ++k;
    return k;
  };
  const size_t slices = std::max<size_t>(1, n / 65536);
  tbb::parallel_for(size_t(0), slices, [&](size_t slice) {
    const size_t end = bucket_start_at_or_after(n * (slice + 1) / slices);
    for (size_t s = bucket_start_at_or_after(n * slice / slices); s < end;) {
      size_t e = s + 1;
      while (e < end && bucket(items[e]) == bucket(items[s])) ++e;
      if (e - s > 1) std::sort(items.begin() + s, items.begin() + e, less);
      s = e;
    }
  });
  return items;
}

}  // namespace vdbwrap
