#include "core/common/thread_pool.h"

#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <set>
#include <thread>
#include <vector>

namespace fenestra {
namespace {

TEST(ParallelForTest, RunsEveryIndexOnce) {
  std::vector<std::atomic<int>> runs(1000);
  ParallelFor(runs.size(), 4, [&](uint64_t i) { ++runs[i]; });
  for (const std::atomic<int>& r : runs) EXPECT_EQ(r.load(), 1);
}

// Each worker runs on the same thread in every round (worker 0 on the caller's), and a
// round returns only when every worker is done.
TEST(StandingThreadsTest, EachWorkerKeepsItsThread) {
  StandingThreads threads(4);
  ASSERT_EQ(threads.count(), 4);
  std::vector<std::thread::id> first(4);
  for (int round = 0; round < 50; ++round) {
    std::vector<std::thread::id> seen(4);
    std::atomic<int> done{0};
    threads.Run([&](int w) {
      seen[w] = std::this_thread::get_id();
      if (w == 3) std::this_thread::sleep_for(std::chrono::microseconds(200));
      ++done;
    });
    EXPECT_EQ(done.load(), 4);
    EXPECT_EQ(std::set<std::thread::id>(seen.begin(), seen.end()).size(), 4u);
    EXPECT_EQ(seen[0], std::this_thread::get_id());
    if (round == 0) first = seen;
    EXPECT_EQ(seen, first);
  }
  StandingThreads alone(1);
  int calls = 0;
  alone.Run([&](int w) { calls += w == 0 ? 1 : 100; });
  EXPECT_EQ(calls, 1);
}

}  // namespace
}  // namespace fenestra
