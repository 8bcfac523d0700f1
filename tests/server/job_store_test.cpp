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
  ASSERT_EQ(jobs->jobs.size(), 1u);
  EXPECT_TRUE(jobs->quarantined.empty());
  EXPECT_EQ(jobs->jobs[0].id(), "job-1");
  EXPECT_EQ(jobs->jobs[0].state(), v1::JOB_STATE_RUNNING);
  EXPECT_EQ(jobs->jobs[0].last_sequence(), 3);
  EXPECT_EQ((*store)->LoadJob("job-1")->name(), "tilt");
  EXPECT_EQ((*store)->LoadJob("job-2").status().code(), absl::StatusCode::kNotFound);
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
  v1::Scene scene;
  scene.set_name("courtyard");
  ASSERT_EQ(*(*store)->InsertSite(a, "/data/weather/x.epw", scene), "site-1");
  ASSERT_EQ(*(*store)->InsertSite(b, "", v1::Scene()), "site-2");
  a.set_state(v1::SITE_STATE_READY);
  ASSERT_TRUE((*store)->UpdateSite(a).ok());
  ASSERT_TRUE((*store)->DeleteSite("site-2").ok());
  auto sites = (*store)->LoadSites();
  ASSERT_TRUE(sites.ok());
  ASSERT_EQ(sites->sites.size(), 1u);
  EXPECT_EQ(sites->sites[0].info.state(), v1::SITE_STATE_READY);
  EXPECT_EQ(sites->sites[0].info.name(), "montevideo");
  EXPECT_FALSE(sites->sites[0].info.has_scene());
  EXPECT_EQ(sites->sites[0].weather_path, "/data/weather/x.epw");
  EXPECT_EQ((*store)->LoadSiteScene("site-1")->name(), "courtyard");
}

TEST(JobStoreTest, UnwritablePathIsAnError) {
  EXPECT_FALSE(JobStore::Open("/nonexistent/dir/fenestra.db").ok());
}

}  // namespace
}  // namespace fenestra
