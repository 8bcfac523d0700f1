#include "server/work_queue.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <atomic>
#include <thread>

#include "absl/strings/str_cat.h"

namespace fenestra {
namespace {

using ::testing::HasSubstr;

TEST(WorkQueueTest, BoundsWaitingJobsButNotOtherTasks) {
  WorkQueue queue(1, 2);
  std::atomic<bool> release = false;
  std::atomic<int> done = 0;
  auto block = [&] {
    while (!release) std::this_thread::sleep_for(std::chrono::milliseconds(5));
    ++done;
  };
  ASSERT_TRUE(queue.Push("running", block).ok());
  while (queue.Running() == 0) std::this_thread::sleep_for(std::chrono::milliseconds(5));
  ASSERT_TRUE(queue.Push("a", block).ok());
  ASSERT_TRUE(queue.Push("site", block, /*is_job=*/false).ok());
  ASSERT_TRUE(queue.Push("b", block).ok());
  const absl::Status full = queue.Push("c", block);
  EXPECT_EQ(full.code(), absl::StatusCode::kResourceExhausted);
  EXPECT_THAT(full.message(), HasSubstr("max_queued_jobs = 2"));
  EXPECT_TRUE(queue.Push("forced", block, true, /*force=*/true).ok());
  EXPECT_EQ(queue.QueuedJobs(), 3);
  EXPECT_EQ(queue.Position("a"), 0);
  EXPECT_EQ(queue.Position("b"), 1);  // the site task does not count
  EXPECT_EQ(queue.Position("running"), -1);
  EXPECT_TRUE(queue.Remove("b"));
  EXPECT_FALSE(queue.Remove("b"));
  EXPECT_EQ(queue.Position("forced"), 1);
  release = true;
  while (done < 4) std::this_thread::sleep_for(std::chrono::milliseconds(5));
  EXPECT_TRUE(queue.WaitIdle(5));
}

TEST(WorkQueueTest, StopLeavesWaitingTasksAndJoinWaitsForRunningOnes) {
  WorkQueue queue(1, 10);
  std::atomic<bool> finished = false, started_second = false;
  ASSERT_TRUE(queue
                  .Push("first",
                        [&] {
                          std::this_thread::sleep_for(std::chrono::milliseconds(200));
                          finished = true;
                        })
                  .ok());
  while (queue.Running() == 0) std::this_thread::sleep_for(std::chrono::milliseconds(5));
  ASSERT_TRUE(queue.Push("second", [&] { started_second = true; }).ok());
  queue.Stop();
  EXPECT_FALSE(queue.WaitIdle(0.01));
  EXPECT_EQ(queue.Push("third", [] {}).code(), absl::StatusCode::kFailedPrecondition);
  queue.Join();
  EXPECT_TRUE(finished);
  EXPECT_FALSE(started_second);
}

TEST(WorkQueueTest, WorkersRunTasksConcurrently) {
  WorkQueue queue(2, 10);
  std::atomic<int> running = 0, peak = 0;
  for (int i = 0; i < 4; ++i) {
    ASSERT_TRUE(queue
                    .Push(absl::StrCat("t", i),
                          [&] {
                            peak = std::max(peak.load(), ++running);
                            std::this_thread::sleep_for(std::chrono::milliseconds(100));
                            --running;
                          })
                    .ok());
  }
  std::this_thread::sleep_for(std::chrono::milliseconds(50));
  EXPECT_TRUE(queue.WaitIdle(5));
  while (queue.QueuedJobs() > 0 || queue.Running() > 0) {
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  EXPECT_EQ(peak, 2);
}

}  // namespace
}  // namespace fenestra
