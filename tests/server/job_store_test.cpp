#include "server/job_store.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <sqlite3.h>

#include <filesystem>

#include "absl/strings/str_cat.h"

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

// Runs SQL on a store's file while no JobStore holds it.
void Sql(const std::string& path, const std::string& sql) {
  sqlite3* db = nullptr;
  ASSERT_EQ(sqlite3_open(path.c_str(), &db), SQLITE_OK);
  EXPECT_EQ(sqlite3_exec(db, sql.c_str(), nullptr, nullptr, nullptr), SQLITE_OK)
      << sqlite3_errmsg(db);
  sqlite3_close(db);
}

TEST(JobStoreTest, AFinishedJobKeepsOnlyItsFinalEvent) {
  auto store = JobStore::Open(FreshDb("finish"));
  ASSERT_TRUE(store.ok());
  v1::JobInfo info;
  v1::JobEvent queued;
  queued.set_sequence(1);
  queued.set_queued(0);
  ASSERT_TRUE((*store)->InsertJob(info, v1::Job(), &queued).ok());
  v1::JobEvent progress;
  progress.set_sequence(2);
  progress.mutable_progress()->set_evaluations(1);
  info.set_state(v1::JOB_STATE_RUNNING);
  ASSERT_TRUE((*store)->UpdateJob(info, &progress, /*durable=*/false).ok());
  EXPECT_EQ((*store)->LoadEvents(info.id())->size(), 2u);
  v1::JobEvent finished;
  finished.set_sequence(3);
  finished.mutable_finished()->set_evaluations(1);
  info.set_state(v1::JOB_STATE_SUCCEEDED);
  ASSERT_TRUE((*store)->FinishJob(info, finished).ok());
  auto events = (*store)->LoadEvents(info.id());
  ASSERT_EQ(events->size(), 1u);
  EXPECT_TRUE((*events)[0].has_finished());
  EXPECT_EQ((*store)->LoadJobs()->jobs[0].last_sequence(), 3);
  // An event whose sequence is taken fails, and its whole transaction with it
  info.set_name("renamed");
  EXPECT_FALSE((*store)->UpdateJob(info, &finished).ok());
  EXPECT_EQ((*store)->LoadJobs()->jobs[0].name(), "");
}

TEST(JobStoreTest, RecordsThatDoNotParseAreQuarantined) {
  const std::string path = FreshDb("quarantine");
  {
    auto store = JobStore::Open(path);
    ASSERT_TRUE(store.ok());
    for (int k = 0; k < 3; ++k) {
      v1::JobInfo info;
      ASSERT_TRUE((*store)->InsertJob(info, v1::Job()).ok());
      v1::SiteInfo site;
      ASSERT_TRUE((*store)->InsertSite(site, "", v1::Scene()).ok());
    }
  }
  Sql(path,
      "UPDATE jobs SET info = x'ff01' WHERE id = 'job-2'; "
      "UPDATE jobs SET job = x'ff01' WHERE id = 'job-3'; "
      "UPDATE sites SET info = x'0a057369746533' WHERE id = 'site-1'");  // names site3
  auto store = JobStore::Open(path);
  ASSERT_TRUE(store.ok());
  auto jobs = (*store)->LoadJobs();
  ASSERT_TRUE(jobs.ok()) << jobs.status();
  ASSERT_EQ(jobs->jobs.size(), 2u);
  EXPECT_EQ(jobs->jobs[0].id(), "job-1");
  ASSERT_EQ(jobs->quarantined.size(), 1u);
  EXPECT_EQ(jobs->quarantined[0].id, "job-2");
  EXPECT_EQ(jobs->quarantined[0].reason, "its JobInfo does not parse");
  // A job's submitted form is read when it runs
  EXPECT_EQ((*store)->LoadJob("job-3").status().code(), absl::StatusCode::kDataLoss);
  ASSERT_TRUE((*store)->Quarantine("jobs", "job-3", "its Job does not parse").ok());
  auto sites = (*store)->LoadSites();
  ASSERT_TRUE(sites.ok());
  EXPECT_EQ(sites->sites.size(), 2u);
  ASSERT_EQ(sites->quarantined.size(), 1u);
  EXPECT_EQ(sites->quarantined[0].id, "site-1");
  EXPECT_EQ(sites->quarantined[0].reason, "its SiteInfo names another site");
  // Moved, not lost: the next start finds only the sound ones
  EXPECT_EQ((*store)->LoadJobs()->jobs.size(), 1u);
  EXPECT_TRUE((*store)->LoadJobs()->quarantined.empty());
  EXPECT_EQ((*store)->LoadSites()->sites.size(), 2u);
  store->reset();
  sqlite3* db = nullptr;
  ASSERT_EQ(sqlite3_open(path.c_str(), &db), SQLITE_OK);
  sqlite3_stmt* count = nullptr;
  ASSERT_EQ(sqlite3_prepare_v2(db, "SELECT COUNT(*) FROM quarantine WHERE info IS NOT NULL", -1,
                               &count, nullptr),
            SQLITE_OK);
  ASSERT_EQ(sqlite3_step(count), SQLITE_ROW);
  EXPECT_EQ(sqlite3_column_int(count, 0), 3);
  sqlite3_finalize(count);
  sqlite3_close(db);
}

TEST(JobStoreTest, SitesStoredWithTheSceneInTheirInfoAreRead) {
  const std::string path = FreshDb("legacy");
  v1::SiteInfo info;
  info.set_id("site-1");
  info.set_name("old");
  info.mutable_scene()->set_name("courtyard");
  std::string hex;
  for (unsigned char c : info.SerializeAsString())
    absl::StrAppend(&hex, absl::Hex(c, absl::kZeroPad2));
  Sql(path,
      "CREATE TABLE sites (number INTEGER PRIMARY KEY AUTOINCREMENT, id TEXT UNIQUE, info BLOB "
      "NOT NULL, weather_path TEXT NOT NULL); INSERT INTO sites (id, info, weather_path) VALUES "
      "('site-1', x'" +
          hex + "', '')");
  auto store = JobStore::Open(path);
  ASSERT_TRUE(store.ok()) << store.status();
  auto sites = (*store)->LoadSites();
  ASSERT_EQ(sites->sites.size(), 1u);
  EXPECT_EQ(sites->sites[0].info.name(), "old");
  EXPECT_FALSE(sites->sites[0].info.has_scene());
  EXPECT_EQ((*store)->LoadSiteScene("site-1")->name(), "courtyard");
  // A site stored now keeps its scene in its own column
  v1::SiteInfo fresh;
  v1::Scene scene;
  scene.set_name("street");
  ASSERT_EQ(*(*store)->InsertSite(fresh, "", scene), "site-2");
  EXPECT_EQ((*store)->LoadSiteScene("site-2")->name(), "street");
}

TEST(JobStoreTest, ASharedStoreSeesTheUsersAnotherAddsAnExclusiveOneKeepsOthersOut) {
  const std::string path = FreshDb("sharing");
  {
    // The daemon's store and `fenestrad user add` beside it
    auto daemon = JobStore::Open(path);
    ASSERT_TRUE(daemon.ok()) << daemon.status();
    ASSERT_TRUE((*daemon)->LoadJobs().ok());
    auto command = JobStore::Open(path);
    ASSERT_TRUE(command.ok()) << command.status();
    ASSERT_TRUE((*command)->InsertUser(UserRecord{"ann", std::string(32, 'a'), false, 5, 0}).ok());
    auto users = (*daemon)->LoadUsers();
    ASSERT_TRUE(users.ok()) << users.status();
    ASSERT_EQ(users->size(), 1u);
    EXPECT_EQ((*users)[0].name, "ann");
    ASSERT_TRUE((*command)->RevokeUser("ann", 9).ok());
    EXPECT_EQ((*(*daemon)->LoadUsers())[0].revoked_unix_ms, 9);
  }
  auto first = JobStore::Open(path, JobStore::Sharing::kExclusive);
  ASSERT_TRUE(first.ok()) << first.status();
  ASSERT_TRUE((*first)->LoadJobs().ok());
  EXPECT_FALSE(std::filesystem::exists(path + "-shm"));
  auto second = JobStore::Open(path);
  EXPECT_EQ(second.status().code(), absl::StatusCode::kFailedPrecondition);
  EXPECT_THAT(std::string(second.status().message()), testing::HasSubstr("in use by another"));
}

}  // namespace
}  // namespace fenestra
