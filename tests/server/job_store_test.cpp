#include "server/job_store.h"

#include <gtest/gtest.h>

#include <filesystem>

namespace fenestra {
namespace {

std::string FreshDb(const std::string& name) {
  const std::string path = testing::TempDir() + "/job_store_test_" + name + ".db";
  for (const char* suffix : {"", "-wal", "-shm"}) std::filesystem::remove(path + suffix);
  return path;
}

TEST(JobStoreTest, JobsAndEventsSurviveReopening) {
  const std::string path = FreshDb("jobs");
  {
    auto store = JobStore::Open(path);
    ASSERT_TRUE(store.ok()) << store.status();
    v1::Job job;
    job.set_name("tilt");
    v1::JobInfo first, second;
    first.set_state(v1::JOB_STATE_QUEUED);
    ASSERT_EQ(*(*store)->InsertJob(first, job), "job-1");
    ASSERT_EQ(*(*store)->InsertJob(second, job), "job-2");
    EXPECT_EQ(first.id(), "job-1");
    first.set_state(v1::JOB_STATE_RUNNING);
    ASSERT_TRUE((*store)->UpdateJob(first).ok());
    for (int s = 1; s <= 3; ++s) {
      v1::JobEvent event;
      event.set_sequence(s);
      event.mutable_progress()->set_evaluations(s);
      ASSERT_TRUE((*store)->AppendEvent("job-1", event).ok());
    }
    v1::JobEvent duplicate;
    duplicate.set_sequence(2);
    EXPECT_FALSE((*store)->AppendEvent("job-1", duplicate).ok());
    ASSERT_TRUE((*store)->DeleteJob("job-2").ok());
  }
  auto store = JobStore::Open(path);
  ASSERT_TRUE(store.ok());
  auto jobs = (*store)->LoadJobs();
  ASSERT_TRUE(jobs.ok()) << jobs.status();
  ASSERT_EQ(jobs->size(), 1u);
  EXPECT_EQ((*jobs)[0].info.id(), "job-1");
  EXPECT_EQ((*jobs)[0].info.state(), v1::JOB_STATE_RUNNING);
  EXPECT_EQ((*jobs)[0].info.last_sequence(), 3);
  EXPECT_EQ((*jobs)[0].job.name(), "tilt");
  auto events = (*store)->LoadEvents("job-1");
  ASSERT_TRUE(events.ok());
  ASSERT_EQ(events->size(), 3u);
  EXPECT_EQ((*events)[2].progress().evaluations(), 3);
  // Ids are never reused, not even a deleted job's
  v1::JobInfo third;
  EXPECT_EQ(*(*store)->InsertJob(third, v1::Job()), "job-3");
}

TEST(JobStoreTest, Sites) {
  auto store = JobStore::Open(FreshDb("sites"));
  ASSERT_TRUE(store.ok());
  v1::SiteInfo a, b;
  a.set_name("montevideo");
  ASSERT_EQ(*(*store)->InsertSite(a, "/data/weather/x.epw"), "site-1");
  ASSERT_EQ(*(*store)->InsertSite(b, ""), "site-2");
  a.set_state(v1::SITE_STATE_READY);
  ASSERT_TRUE((*store)->UpdateSite(a).ok());
  ASSERT_TRUE((*store)->DeleteSite("site-2").ok());
  auto sites = (*store)->LoadSites();
  ASSERT_TRUE(sites.ok());
  ASSERT_EQ(sites->size(), 1u);
  EXPECT_EQ((*sites)[0].info.state(), v1::SITE_STATE_READY);
  EXPECT_EQ((*sites)[0].info.name(), "montevideo");
  EXPECT_EQ((*sites)[0].weather_path, "/data/weather/x.epw");
}

TEST(JobStoreTest, UsersSurviveReopening) {
  const std::string path = FreshDb("users");
  {
    auto store = JobStore::Open(path);
    ASSERT_TRUE(store.ok());
    ASSERT_TRUE((*store)->InsertUser(UserRecord{"ann", std::string(32, 'a'), false, 5, 0}).ok());
    ASSERT_TRUE((*store)->InsertUser(UserRecord{"root", std::string(32, 'r'), true, 6, 0}).ok());
    ASSERT_TRUE((*store)->RevokeUser("ann", 7).ok());
  }
  auto store = JobStore::Open(path);
  ASSERT_TRUE(store.ok());
  auto users = (*store)->LoadUsers();
  ASSERT_TRUE(users.ok()) << users.status();
  ASSERT_EQ(users->size(), 2u);
  EXPECT_EQ((*users)[0].name, "ann");
  EXPECT_EQ((*users)[0].token_sha256, std::string(32, 'a'));
  EXPECT_EQ((*users)[0].created_unix_ms, 5);
  EXPECT_EQ((*users)[0].revoked_unix_ms, 7);
  EXPECT_TRUE((*users)[1].admin);
  EXPECT_EQ((*users)[1].revoked_unix_ms, 0);
  EXPECT_EQ((*store)->InsertUser(UserRecord{"ann", std::string(32, 'b'), false, 8, 0}).code(),
            absl::StatusCode::kAlreadyExists);
}

TEST(JobStoreTest, UnwritablePathIsAnError) {
  EXPECT_FALSE(JobStore::Open("/nonexistent/dir/fenestra.db").ok());
}

}  // namespace
}  // namespace fenestra
