#include "server/work_queue.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <atomic>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "absl/strings/str_cat.h"

namespace fenestra {
namespace {

using ::testing::HasSubstr;

TEST(WorkQueueTest, BoundsWaitingJobsButNotOtherTasks) {
  // What the tasks use outlives the queue, whose workers may still run them as it goes
  std::atomic<bool> release = false;
  std::atomic<int> done = 0;
  WorkQueue queue(1, 2, 100);
  auto block = [&] {
    while (!release) std::this_thread::sleep_for(std::chrono::milliseconds(5));
    ++done;
  };
  ASSERT_TRUE(queue.Push("running", "ann", block).ok());
  while (queue.Running() == 0) std::this_thread::sleep_for(std::chrono::milliseconds(5));
  ASSERT_TRUE(queue.Push("a", "ann", block).ok());
  ASSERT_TRUE(queue.Push("site", "ann", block, /*is_job=*/false).ok());
  ASSERT_TRUE(queue.Push("b", "ann", block).ok());
  const absl::Status full = queue.Push("c", "ann", block);
  EXPECT_EQ(full.code(), absl::StatusCode::kResourceExhausted);
  EXPECT_THAT(full.message(), HasSubstr("max_queued_jobs = 2"));
  EXPECT_TRUE(queue.Push("forced", "ann", block, true, /*force=*/true).ok());
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

// Holds the only worker of `queue` with a task of `owner` until `release`.
void HoldWorker(WorkQueue& queue, const std::string& owner, std::atomic<bool>& release) {
  ASSERT_TRUE(queue
                  .Push("gate", owner,
                        [&] {
                          while (!release)
                            std::this_thread::sleep_for(std::chrono::milliseconds(2));
                        })
                  .ok());
  while (queue.Running() == 0) std::this_thread::sleep_for(std::chrono::milliseconds(2));
}

TEST(WorkQueueTest, UsersTakeTurnsEachWithTheirOldestTask) {
  std::atomic<bool> release = false;  // these outlive the queue
  std::mutex mutex;
  std::vector<std::string> ran;
  WorkQueue queue(1, 100, 100);
  HoldWorker(queue, "ann", release);  // ann was served last; bob and cy never
  auto record = [&](const std::string& id) {
    return [&, id] {
      std::lock_guard lock(mutex);
      ran.push_back(id);
    };
  };
  for (const char* id : {"a1", "a2", "a3"}) ASSERT_TRUE(queue.Push(id, "ann", record(id)).ok());
  for (const char* id : {"b1", "b2"}) ASSERT_TRUE(queue.Push(id, "bob", record(id)).ok());
  ASSERT_TRUE(queue.Push("c1", "cy", record("c1"), /*is_job=*/false).ok());

  // Never served first (ties to the older task), then whoever waited longest since served
  const std::vector<std::string> expected = {"b1", "c1", "a1", "b2", "a2", "a3"};
  EXPECT_EQ(queue.Position("b1"), 0);
  EXPECT_EQ(queue.Position("c1"), 1);  // the site task is not a job: b1 alone is ahead
  EXPECT_EQ(queue.Position("a1"), 1);
  EXPECT_EQ(queue.Position("b2"), 2);
  EXPECT_EQ(queue.Position("a3"), 4);
  release = true;
  while (queue.QueuedJobs() > 0 || queue.Running() > 0) {
    std::this_thread::sleep_for(std::chrono::milliseconds(2));
  }
  std::lock_guard lock(mutex);
  EXPECT_EQ(ran, expected);
}

TEST(WorkQueueTest, BoundsWaitingJobsPerUser) {
  std::atomic<bool> release = false;  // outlives the queue
  WorkQueue queue(1, 10, 2);
  HoldWorker(queue, "ann", release);
  ASSERT_TRUE(queue.Push("a1", "ann", [] {}).ok());
  ASSERT_TRUE(queue.Push("a2", "ann", [] {}).ok());
  const absl::Status full = queue.Push("a3", "ann", [] {});
  EXPECT_EQ(full.code(), absl::StatusCode::kResourceExhausted);
  EXPECT_THAT(full.message(), HasSubstr("limits.max_queued_jobs_per_user (2) reached"));
  EXPECT_TRUE(queue.Push("b1", "bob", [] {}).ok());
  EXPECT_TRUE(queue
                  .Push(
                      "site", "ann", [] {}, /*is_job=*/false)
                  .ok());
  EXPECT_TRUE(queue
                  .Push(
                      "restored", "ann", [] {}, true, /*force=*/true)
                  .ok());
  // A place frees when one of ann's jobs leaves the queue
  EXPECT_TRUE(queue.Remove("a1"));
  EXPECT_TRUE(queue.Remove("restored"));
  EXPECT_TRUE(queue.Push("a3", "ann", [] {}).ok());
  release = true;
}

TEST(WorkQueueTest, StopLeavesWaitingTasksAndJoinWaitsForRunningOnes) {
  std::atomic<bool> finished = false, started_second = false;
  WorkQueue queue(1, 10, 100);
  ASSERT_TRUE(queue
                  .Push("first", "ann",
                        [&] {
                          std::this_thread::sleep_for(std::chrono::milliseconds(200));
                          finished = true;
                        })
                  .ok());
  while (queue.Running() == 0) std::this_thread::sleep_for(std::chrono::milliseconds(5));
  ASSERT_TRUE(queue.Push("second", "ann", [&] { started_second = true; }).ok());
  queue.Stop();
  EXPECT_FALSE(queue.WaitIdle(0.01));
  EXPECT_EQ(queue.Push("third", "ann", [] {}).code(), absl::StatusCode::kFailedPrecondition);
  queue.Join();
  EXPECT_TRUE(finished);
  EXPECT_FALSE(started_second);
}

TEST(WorkQueueTest, WorkersRunTasksConcurrently) {
  std::atomic<int> running = 0, peak = 0;
  WorkQueue queue(2, 10, 100);
  for (int i = 0; i < 4; ++i) {
    ASSERT_TRUE(queue
                    .Push(absl::StrCat("t", i), "ann",
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
