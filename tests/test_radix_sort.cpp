// The radix sort behind the cell hits of refinement and the nearest-point index: the same
// order as a stable comparison sort of the joined parts, for any key width.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>
#include <functional>
#include <random>
#include <vector>

#include "common/radix_sort.h"

using namespace vdbwrap;

namespace {

struct Item {
  uint64_t key;
  uint32_t order;  // position in the joined parts: equal keys must keep it ascending
  bool operator==(const Item& o) const { return key == o.key && order == o.order; }
};

}  // namespace

TEST(RadixSort, JoinsAndSortsStablyForEveryKeyWidth) {
  std::mt19937_64 random(7);
  for (int bits : {0, 1, 5, 12, 13, 24, 25, 40, 63}) {
    // Parts of uneven sizes, some empty, some longer than a slice (32768 items).
    std::vector<std::vector<Item>> parts;
    uint32_t order = 0;
    for (size_t size : {size_t(0), size_t(1), size_t(70000), size_t(0), size_t(12345), size_t(40000)}) {
      std::vector<Item>& part = parts.emplace_back();
      for (size_t i = 0; i < size; ++i) {
        // Keys over the whole width, a quarter of them one value: ties everywhere.
        const uint64_t mask = bits == 0 ? 0 : ~uint64_t(0) >> (64 - bits);
        const uint64_t key = random() % 4 == 0 ? (5 & mask) : random() & mask;
        part.push_back({key, order++});
      }
    }
    std::vector<Item> expected;
    for (const auto& part : parts) expected.insert(expected.end(), part.begin(), part.end());
    std::stable_sort(expected.begin(), expected.end(), [](const Item& a, const Item& b) { return a.key < b.key; });
    const FillVector<Item> sorted = radix_sort_joined(
        parts, [](const Item& x) { return x.key; }, bits);
    ASSERT_EQ(sorted.size(), expected.size()) << bits << " bits";
    EXPECT_TRUE(std::equal(sorted.begin(), sorted.end(), expected.begin())) << bits << " bits";
    EXPECT_TRUE(parts.empty()) << "the parts are freed";
  }
}

TEST(RadixSort, NothingToSort) {
  std::vector<std::vector<Item>> parts(3);
  EXPECT_TRUE(radix_sort_joined(
                  parts, [](const Item& x) { return x.key; }, 20)
                  .empty());
  EXPECT_EQ(bits_for(0), 0);
  EXPECT_EQ(bits_for(1), 0);
  EXPECT_EQ(bits_for(2), 1);
  EXPECT_EQ(bits_for(4096), 12);
  EXPECT_EQ(bits_for(4097), 13);
}

// Radix sort by a key's top bits, then each bucket by the whole order: the order of one
// comparison sort, with buckets of one item, of many, and one bucket crossing slices.
TEST(RadixSort, TopBitsThenBucketsGiveTheFullOrder) {
  std::mt19937_64 random(11);
  for (int top_bits : {0, 4, 24}) {
    std::vector<std::vector<uint64_t>> parts;
    for (size_t size : {size_t(0), size_t(90000), size_t(3), size_t(200000)}) {
      std::vector<uint64_t>& part = parts.emplace_back();
      for (size_t i = 0; i < size; ++i)
        part.push_back(random() % 3 == 0 ? (uint64_t(7) << 40) | (random() & 0xFF) : random());
    }
    std::vector<uint64_t> expected;
    for (const auto& part : parts) expected.insert(expected.end(), part.begin(), part.end());
    std::sort(expected.begin(), expected.end());
    const int shift = 64 - top_bits;
    const FillVector<uint64_t> sorted = radix_then_sort(
        parts, [&](uint64_t x) { return top_bits == 0 ? uint64_t(0) : x >> shift; }, top_bits, std::less<uint64_t>());
    ASSERT_EQ(sorted.size(), expected.size()) << top_bits << " top bits";
    EXPECT_TRUE(std::equal(sorted.begin(), sorted.end(), expected.begin())) << top_bits << " top bits";
  }
}
