// Items run in parallel after the items they wait for (the feature tracing's schedule): every
// item once, never before one it waits for, on two threads.
#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <memory>
#include <random>
#include <vector>

#include <tbb/global_control.h>

#include "common/dependency_order.h"

using namespace vdbwrap;

TEST(DependencyOrder, EveryItemRunsOnceAndAfterEveryItemItWaitsFor) {
  tbb::global_control threads(tbb::global_control::max_allowed_parallelism, 2);
  std::mt19937 rng(3);
  for (int round = 0; round < 10; ++round) {
    // Many cheap items, most free at the start and the others waiting for up to three
    // earlier ones: the early items finish and release later ones while the ready ones are
    // still being listed, which is when an item could be started twice.
    constexpr uint32_t n = 50000;
    std::vector<std::vector<uint32_t>> successors(n), waits_for(n);
    std::vector<uint32_t> waits(n, 0);
    for (uint32_t i = 1; i < n; ++i) {
      if (rng() % 4 != 0) continue;
      const uint32_t count = 1 + rng() % 3;
      for (uint32_t k = 0; k < count; ++k) waits_for[i].push_back(i - 1 - rng() % std::min<uint32_t>(i, 20000));
      std::sort(waits_for[i].begin(), waits_for[i].end());
      waits_for[i].erase(std::unique(waits_for[i].begin(), waits_for[i].end()), waits_for[i].end());
      for (uint32_t b : waits_for[i]) successors[b].push_back(i);
      waits[i] = uint32_t(waits_for[i].size());
    }
    std::unique_ptr<std::atomic<int>[]> runs(new std::atomic<int>[n]);
    std::unique_ptr<std::atomic<bool>[]> done(new std::atomic<bool>[n]);
    for (uint32_t i = 0; i < n; ++i) runs[i] = 0, done[i] = false;
    std::atomic<size_t> too_early{0};
    run_in_dependency_order(successors, waits, [&](uint32_t i) {
      for (uint32_t b : waits_for[i]) too_early += done[b].load() ? 0 : 1;
      runs[i].fetch_add(1);
      done[i] = true;
    });
    size_t not_once = 0;
    for (uint32_t i = 0; i < n; ++i) not_once += runs[i].load() != 1;
    ASSERT_EQ(not_once, 0u) << "round " << round;
    ASSERT_EQ(too_early.load(), 0u) << "round " << round;
  }
}
