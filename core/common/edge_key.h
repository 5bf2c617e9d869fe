// One key per undirected edge of a triangle mesh: the smaller vertex index in the high word.
#pragma once
#include <cstdint>
#include <utility>

namespace vdbwrap {

inline uint64_t edge_key(uint32_t a, uint32_t b) {
  if (a > b) std::swap(a, b);
  return (uint64_t(a) << 32) | b;
}

}  // namespace vdbwrap
