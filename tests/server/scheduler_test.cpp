#include "server/scheduler.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <chrono>
#include <filesystem>
#include <mutex>
#include <thread>
#include <vector>

#include "absl/strings/str_cat.h"
#include "server/outdoor_cache.h"
#include "server/store/store.h"

namespace fenestra {
namespace {

using Clock = std::chrono::steady_clock;

// A store in a SQLite file of its own (a second Open of the same folder: another replica).
std::unique_ptr<Store> OpenStore(const std::string& dir) {
  absl::StatusOr<std::unique_ptr<Store>> store = OpenStoreUrl("sqlite:" + dir);
  EXPECT_TRUE(store.ok()) << store.status();
  return store.ok() ? *std::move(store) : nullptr;
}

std::string FreshDir(const std::string& name) {
  const std::string dir = testing::TempDir() + "/scheduler_test_" + name;
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  return dir;
}

v1::Limits Limits() {
  v1::Limits limits;
  limits.set_max_queued_jobs(100);
  limits.set_max_queued_jobs_per_user(100);
  limits.set_max_sites(100);
  limits.set_max_sites_per_user(100);
  limits.set_max_upload_bytes_per_user(1 << 20);
  return limits;
}

std::string Queue(Store& store, const std::string& owner) {
  Store::NewJob job;
  job.info.set_owner(owner);
  job.weather_epw = "weather";
  absl::StatusOr<v1::JobInfo> info = store.InsertJob(job, Limits());
  EXPECT_TRUE(info.ok()) << info.status();
  return info.ok() ? info->id() : "";
}

// Ends a claimed job as its runner would.
void Finish(Store& store, const Claim& claim) {
  absl::StatusOr<v1::JobInfo> info = store.GetJob(claim.lease.id, false);
  ASSERT_TRUE(info.ok());
  info->set_state(v1::JOB_STATE_SUCCEEDED);
  info->set_last_sequence(info->last_sequence() + 1);
  v1::JobEvent end;
  end.set_sequence(info->last_sequence());
  ASSERT_TRUE(store.FinishJob(claim.lease, *info, end).ok());
}

// Polls `done` for up to 10 s.
bool Eventually(const std::function<bool()>& done) {
  const auto deadline = Clock::now() + std::chrono::seconds(10);
  while (!done() && Clock::now() < deadline) {
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  return done();
}

TEST(SchedulerTest, WorkersTakeJobsAndSiteComputationsInTurnAcrossUsers) {
  const std::string dir = FreshDir("turns");
  std::unique_ptr<Store> store = OpenStore(dir);
  OutdoorCache cache(dir + "/outdoor");
  const std::string a1 = Queue(*store, "ann"), a2 = Queue(*store, "ann"), b1 = Queue(*store, "bob");
  v1::SiteInfo site;
  site.set_owner("carl");
  site.set_state(v1::SITE_STATE_COMPUTING);
  ASSERT_TRUE(store->InsertSite(site, v1::Scene(), "", Limits()).ok());

  std::mutex mutex;
  std::vector<std::string> ran;
  Scheduler scheduler(*store, cache, "replica-a", /*workers=*/1, /*lease_seconds=*/10, 0.05);
  scheduler.Start(
      [&](std::shared_ptr<Scheduler::Held> held) {
        EXPECT_EQ(scheduler.Find(held->claim.lease.id), held);  // held while it runs
        Finish(*store, held->claim);
        std::lock_guard lock(mutex);
        ran.push_back(held->claim.lease.id);
      },
      [&](std::shared_ptr<Scheduler::Held> held) {
        ASSERT_TRUE(
            store
                ->UpdateSite(held->claim.lease.id, &held->claim.lease,
                             [](v1::SiteInfo& info) { info.set_state(v1::SITE_STATE_READY); })
                .ok());
        std::lock_guard lock(mutex);
        ran.push_back(held->claim.lease.id);
      });
  ASSERT_TRUE(Eventually([&] {
    std::lock_guard lock(mutex);
    return ran.size() == 4;
  }));
  // A job queued now, through another handle (another replica's submission), is taken too
  std::unique_ptr<Store> other = OpenStore(dir);
  const std::string late = Queue(*other, "dora");
  ASSERT_TRUE(Eventually([&] {
    std::lock_guard lock(mutex);
    return ran.size() == 5;
  }));
  scheduler.Join();
  EXPECT_THAT(ran, testing::ElementsAre(a1, b1, "site-1", a2, late));
  EXPECT_EQ(scheduler.Running(), 0);
}

TEST(SchedulerTest, TheRenewerTellsARunnerOfACancelAndOfALostLease) {
  const std::string dir = FreshDir("renewer");
  std::unique_ptr<Store> store = OpenStore(dir);
  std::unique_ptr<Store> other = OpenStore(dir);  // another replica's
  OutdoorCache cache(dir + "/outdoor");
  const std::string cancelled = Queue(*store, "ann");
  const std::string lost = Queue(*store, "bob");

  std::mutex mutex;
  std::vector<std::string> heard;
  // A lease of 0.3 s, renewed every 0.1 s
  Scheduler scheduler(*store, cache, "replica-a", 1, /*lease_seconds=*/0.3, 0.05);
  scheduler.Start(
      [&](std::shared_ptr<Scheduler::Held> held) {
        const std::string& id = held->claim.lease.id;
        if (id == cancelled) {
          // Cancelled through another replica: the renewer brings it here
          EXPECT_TRUE(other->CancelJob(id, nullptr).ok());
          EXPECT_TRUE(Eventually([&] { return held->cancel_requested.load(); }));
          EXPECT_FALSE(held->lost);
          Finish(*store, held->claim);
          held->done = true;
        } else {
          // Renewed while held: nobody else gets it
          std::this_thread::sleep_for(std::chrono::milliseconds(600));
          EXPECT_FALSE(other->ClaimWork("replica-b", 60'000, {}, {})->has_value());
          // Taken over by another replica (as after an outage longer than the lease)
          EXPECT_TRUE(
              other->database()
                  .Transact(
                      {},
                      [&](SqlSession& s) {
                        return s.Run("UPDATE jobs SET lease_expires_unix_ms = 0 WHERE id = ?", {id})
                            .status();
                      })
                  .ok());
          absl::StatusOr<std::optional<Claim>> taken =
              other->ClaimWork("replica-b", 60'000, {}, {});
          EXPECT_TRUE(taken.ok() && *taken && (*taken)->lease.id == id);
          EXPECT_TRUE(Eventually([&] { return held->lost.load(); }));
        }
        std::lock_guard lock(mutex);
        heard.push_back(id);
      },
      [](std::shared_ptr<Scheduler::Held>) {});
  ASSERT_TRUE(Eventually([&] {
    std::lock_guard lock(mutex);
    return heard.size() == 2;
  }));
  scheduler.Join();
}

TEST(SchedulerTest, AClaimHeldAfterItsRunIsRenewedAndNotTakenAgain) {
  const std::string dir = FreshDir("hold");
  std::unique_ptr<Store> store = OpenStore(dir);
  OutdoorCache cache(dir + "/outdoor");
  const std::string id = Queue(*store, "ann");
  std::mutex mutex;
  std::shared_ptr<Scheduler::Held> kept;  // an end waiting to be stored
  std::atomic<int> runs = 0;
  Scheduler scheduler(*store, cache, "replica-a", 1, /*lease_seconds=*/0.3, 0.05);
  scheduler.Start(
      [&](std::shared_ptr<Scheduler::Held> held) {
        std::lock_guard lock(mutex);
        kept = held;
        ++runs;
      },
      [](std::shared_ptr<Scheduler::Held>) {});
  ASSERT_TRUE(Eventually([&] { return runs.load() == 1; }));
  // Well past the lease: still this replica's, and not run again
  std::this_thread::sleep_for(std::chrono::milliseconds(900));
  EXPECT_EQ(runs.load(), 1);
  EXPECT_FALSE(store->ClaimWork("replica-b", 60'000, {}, {})->has_value());
  // Let go: the lease runs out and the job is work again (this replica takes it over)
  {
    std::lock_guard lock(mutex);
    EXPECT_FALSE(kept->lost);
    kept.reset();
  }
  EXPECT_TRUE(Eventually([&] { return runs.load() == 2; }));
  scheduler.Join();
  EXPECT_EQ(id, "job-1");
}

}  // namespace
}  // namespace fenestra
