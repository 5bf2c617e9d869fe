// Keys of a few doubles compared bit for bit, for memos of values that are a function of
// those coordinates alone (a query on the fixed input): a repeated question is answered from
// the memo with exactly the value asking again would give.
#pragma once
#include <array>
#include <cstddef>
#include <cstdint>
#include <cstring>

namespace vdbwrap {

template <size_t N>
using BitwiseKey = std::array<uint64_t, N>;

template <size_t N>
BitwiseKey<N> bitwise_key(const std::array<double, N>& values) {
  BitwiseKey<N> key;
  std::memcpy(key.data(), values.data(), sizeof(double) * N);
  return key;
}

struct BitwiseKeyHash {
  template <size_t N>
  size_t operator()(const BitwiseKey<N>& key) const {
    uint64_t h = 0x9e3779b97f4a7c15ULL;
    for (uint64_t x : key) h = (h ^ x) * 0xff51afd7ed558ccdULL, h ^= h >> 32;
    return size_t(h);
  }
};

}  // namespace vdbwrap
