// Items appended by many threads at once, then gathered into one array in parallel.
#pragma once
#include <algorithm>
#include <cstddef>
#include <vector>

#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include "common/fill_vector.h"

namespace vdbwrap {

// One thread's items, in blocks of a fixed size. A growing vector copies itself again and
// again, and the copies were seconds with tens of millions of items (a 2M-triangle
// assembly's cell hits); gathering the blocks of every thread is a parallel copy.
template <typename T>
struct Blocks {
  static constexpr size_t kBlock = size_t(1) << 16;
  std::vector<std::vector<T>> blocks;
  void push_back(const T& item) {
    if (blocks.empty() || blocks.back().size() == kBlock) blocks.emplace_back().reserve(kBlock);
    blocks.back().push_back(item);
  }
};

template <typename T>
using ThreadBlocks = tbb::enumerable_thread_specific<Blocks<T>>;

// Every item of every thread in one array (in no particular order: callers sort), the blocks
// freed as they are copied.
template <typename T>
FillVector<T> gather(ThreadBlocks<T>& items) {
  std::vector<std::vector<T>*> parts;
  std::vector<size_t> offsets{0};
  for (Blocks<T>& local : items)
    for (std::vector<T>& block : local.blocks) parts.push_back(&block), offsets.push_back(offsets.back() + block.size());
  FillVector<T> out(offsets.back());
  tbb::parallel_for(size_t(0), parts.size(), [&](size_t i) {
    std::copy(parts[i]->begin(), parts[i]->end(), out.begin() + ptrdiff_t(offsets[i]));
    std::vector<T>().swap(*parts[i]);
  });
  return out;
}

}  // namespace vdbwrap
