// Bit-identical points merged (+0 and -0 alike), by a parallel sort of point hashes. STL
// facets carry their own three points each, so a million-facet file has three million
// points and about half a million distinct ones; a hash map filled point by point was the
// serial bulk of diagnosing and welding such inputs.
#pragma once
#include <cstdint>
#include <algorithm>
#include <cstring>
#include <functional>
#include <utility>
#include <vector>

#include <tbb/parallel_for.h>

#include "common/fill_vector.h"
#include "common/radix_sort.h"
#include "vdbwrap/mesh.h"

namespace vdbwrap {

inline uint64_t point_hash(const Vec3& p) {
  uint64_t h = 1469598103934665603ULL;
  for (double d : p) {
    uint64_t bits;
    const double z = d == 0 ? 0.0 : d;  // +0 and -0 alike
    std::memcpy(&bits, &z, 8);
    h = (h ^ bits) * 1099511628211ULL;
  }
  return h ^ (h >> 29);
}

// remap[i]: the index in `unique` of point i. `unique` holds each point once, in the order of
// first appearance (what inserting the points one by one into a map would give). Points
// compare with == (a point with a NaN coordinate equals nothing, not even itself).
inline std::vector<uint32_t> exact_weld(const std::vector<Vec3>& points, std::vector<Vec3>& unique) {
  const size_t n = points.size();
  struct Key {
    uint64_t hash;
    uint32_t point;
    bool operator<(const Key& o) const { return hash != o.hash ? hash < o.hash : point < o.point; }
  };
  // Sorted by (hash, point): radix-sorted by the hash's top 24 bits, then each bucket (about
  // one distinct point's copies) sorted on its own.
  constexpr size_t kChunk = 65536;
  std::vector<std::vector<Key>> parts((n + kChunk - 1) / kChunk);
  tbb::parallel_for(size_t(0), parts.size(), [&](size_t k) {
    const size_t end = std::min(n, (k + 1) * kChunk);
    parts[k].reserve(end - k * kChunk);
    for (size_t i = k * kChunk; i < end; ++i) parts[k].push_back({point_hash(points[i]), uint32_t(i)});
  });
  const FillVector<Key> keys = radix_then_sort(
      parts, [](const Key& k) { return k.hash >> 40; }, 24, std::less<Key>());
  // first[i]: the first point equal to point i (itself when none is before it). Within a run
  // of one hash the points come in input order; runs are short (a point's copies, and the rare
  // collision), so each is compared with the earlier firsts of its run. Runs are independent:
  // the sorted keys are cut into slices at run starts, one task each.
  FillVector<uint32_t> first(n);  // every entry written below (each point is in one run)
  auto run_start_at_or_after = [&](size_t k) {
    while (k > 0 && k < n && keys[k].hash == keys[k - 1].hash) ++k;
    return k;
  };
  const size_t slices = std::max<size_t>(1, n / 65536);
  tbb::parallel_for(tbb::blocked_range<size_t>(0, slices, 1), [&](const tbb::blocked_range<size_t>& r) {
    std::vector<uint32_t> firsts;
    for (size_t slice = r.begin(); slice != r.end(); ++slice) {
      const size_t end = run_start_at_or_after(n * (slice + 1) / slices);
      for (size_t s = run_start_at_or_after(n * slice / slices); s < end;) {
        size_t e = s + 1;
        while (e < n && keys[e].hash == keys[s].hash) ++e;
        firsts.clear();
        for (size_t k = s; k < e; ++k) {
          const uint32_t i = keys[k].point;
          uint32_t match = i;
          for (uint32_t f : firsts)
            if (points[f] == points[i]) {
              match = f;
              break;
            }
          if (match == i) firsts.push_back(i);
          first[i] = match;
        }
        s = e;
      }
    }
  });
  // The firsts numbered in input order, then every copy takes its first's number.
  std::vector<uint32_t> remap(n);
  unique.clear();
  for (size_t i = 0; i < n; ++i)
    if (first[i] == i) remap[i] = uint32_t(unique.size()), unique.push_back(points[i]);
  tbb::parallel_for(tbb::blocked_range<size_t>(0, n, 8192), [&](const tbb::blocked_range<size_t>& r) {
    for (size_t i = r.begin(); i != r.end(); ++i)
      if (first[i] != i) remap[i] = remap[first[i]];
  });
  return remap;
}

// A point set's exact weld: its distinct points, and each point's index among them.
struct ExactWeld {
  std::vector<Vec3> unique;
  std::vector<uint32_t> remap;
};
inline ExactWeld exact_weld(const std::vector<Vec3>& points) {
  ExactWeld w;
  w.remap = exact_weld(points, w.unique);
  return w;
}

}  // namespace vdbwrap
