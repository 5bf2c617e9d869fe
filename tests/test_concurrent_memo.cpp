// The memo shared by stage 4's and feature insertion's threads: every stored key found with
// its first value, nothing found that was never stored, while threads fill it at once.
#include <gtest/gtest.h>

#include <cstdint>
#include <vector>

#include <tbb/global_control.h>
#include <tbb/parallel_for.h>

#include "common/bitwise_key.h"
#include "common/concurrent_memo.h"

using namespace vdbwrap;

TEST(ConcurrentMemo, KeepsTheFirstValueOfEveryKeyWhileThreadsFillIt) {
  tbb::global_control threads(tbb::global_control::max_allowed_parallelism, 2);
  ConcurrentMemo<BitwiseKey<3>, uint64_t, BitwiseKeyHash> memo;
  auto key = [](uint64_t i) { return bitwise_key<3>({double(i), 0.5 * double(i), -double(i)}); };
  constexpr uint64_t n = 200000;  // every shard grows many times
  uint64_t v = 0;
  EXPECT_FALSE(memo.find(key(1), v));
  // Each key is inserted twice, from different places of the loop, with different values:
  // the first stored one must stay, and be what every later find sees.
  tbb::parallel_for(uint64_t(0), 2 * n, [&](uint64_t i) {
    const uint64_t k = i % n;
    uint64_t seen = 0;
    if (memo.find(key(k), seen)) {
      EXPECT_TRUE(seen == k || seen == k + n) << k;
      return;
    }
    memo.insert(key(k), i);
  });
  EXPECT_EQ(memo.size(), n);
  std::vector<uint64_t> first(n);
  for (uint64_t k = 0; k < n; ++k) {
    ASSERT_TRUE(memo.find(key(k), first[k])) << k;
    EXPECT_TRUE(first[k] == k || first[k] == k + n) << k;
    memo.insert(key(k), 7);  // a later insert changes nothing
    uint64_t again = 0;
    ASSERT_TRUE(memo.find(key(k), again));
    EXPECT_EQ(again, first[k]);
  }
  EXPECT_FALSE(memo.find(key(n), v));
  EXPECT_FALSE(memo.find(bitwise_key<3>({-0.0, 0.0, 0.0}), v)) << "keys are compared bit for bit";
  EXPECT_TRUE(memo.find(bitwise_key<3>({0.0, 0.0, -0.0}), v)) << "key(0) itself";
}
