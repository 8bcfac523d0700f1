// The store on both of its databases: every typed test runs on SQLite (a temporary file)
// and on PostgreSQL (a fresh database of a throwaway server this process starts).
#include "server/store/store.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <sqlite3.h>

#include <atomic>
#include <filesystem>
#include <mutex>
#include <set>
#include <thread>

#include "absl/strings/cord.h"
#include "absl/strings/str_cat.h"
#include "server/store/migrations.h"
#include "server/store/postgres_database.h"
#include "server/store/sqlite_database.h"
#include "tests/postgres_server.h"

namespace fenestra {
namespace {

using ::testing::HasSubstr;

std::string TestName() {
  const auto* info = testing::UnitTest::GetInstance()->current_test_info();
  std::string name = absl::StrCat(info->test_suite_name(), "_", info->name());
  for (char& c : name) {
    if (!std::isalnum(static_cast<unsigned char>(c))) c = '_';
  }
  return name;
}

// SQLite: a file of its own per test.
struct SqliteBackend {
  static constexpr char kName[] = "Sqlite";
  std::string path;
  absl::StatusOr<std::unique_ptr<Store>> Open(const std::string& name) {
    path = testing::TempDir() + "/store_test_" + name + ".db";
    for (const char* suffix : {"", "-wal", "-shm"}) std::filesystem::remove(path + suffix);
    return Again();
  }
  // Another handle on the same database, as another process would open it.
  absl::StatusOr<std::unique_ptr<Store>> Again() {
    absl::StatusOr<std::unique_ptr<SqliteDatabase>> db =
        SqliteDatabase::Open(path, SqliteDatabase::Sharing::kShared);
    if (!db.ok()) return db.status();
    return Store::Open(*std::move(db));
  }
};

// The PostgreSQL server of this test process, started once, stopped at its exit.
PostgresServer& Server() {
  static PostgresServer server(absl::StrCat(testing::TempDir(), "/store_test_pg.", getpid()));
  return server;
}

// A database name not used before in this process (PostgreSQL cuts names at 63 bytes).
std::string FreshDatabaseName() {
  static std::atomic<int> count = 0;
  return absl::StrCat("store_test_", count++);
}

// PostgreSQL: a database of its own per test.
struct PostgresBackend {
  static constexpr char kName[] = "Postgres";
  std::string url;
  absl::StatusOr<std::unique_ptr<Store>> Open(const std::string& /*name*/) {
    if (!Server().ok()) return absl::UnavailableError(Server().error());
    url = Server().NewDatabase(FreshDatabaseName());
    if (url.empty()) return absl::InternalError(Server().error());
    return Again();
  }
  absl::StatusOr<std::unique_ptr<Store>> Again() { return OpenStoreUrl(url, 4); }
};

struct BackendNames {
  template <typename T>
  static std::string GetName(int) {
    return T::kName;
  }
};

// Runs SQL on a store's database, outside its API (to break records on purpose).
absl::Status Exec(Store& store, const std::string& sql,
                  std::initializer_list<SqlParam> params = {}) {
  return store.database().Transact(
      {}, [&](SqlSession& s) { return s.Run(store.database().Sql(sql), params).status(); });
}

v1::Limits TestLimits() {
  v1::Limits limits;
  limits.set_max_queued_jobs(1000);
  limits.set_max_queued_jobs_per_user(100);
  limits.set_max_sites(1000);
  limits.set_max_sites_per_user(100);
  limits.set_max_upload_bytes_per_user(int64_t{1} << 30);
  return limits;
}

// A job of `owner` with an uploaded weather file `epw` (its size counted as uploaded).
Store::NewJob NewJob(const std::string& owner, const std::string& key = "key-a",
                     const std::string& epw = "weather a") {
  Store::NewJob job;
  job.info.set_owner(owner);
  job.info.set_name(absl::StrCat("job of ", owner));
  job.info.set_outdoor_key(key);
  job.info.set_upload_bytes(static_cast<int64_t>(epw.size()));
  job.info.set_stage("queued");
  job.info.set_created_unix_ms(1000);
  job.job.set_name(absl::StrCat("job of ", owner));
  job.weather_epw = epw;
  return job;
}

// A site of `owner`, stored with a scene "courtyard" and `epw` as its weather file.
absl::StatusOr<v1::SiteInfo> InsertSite(Store& store, const std::string& owner,
                                        v1::SiteState state = v1::SITE_STATE_COMPUTING,
                                        const std::string& epw = "",
                                        const v1::Limits& limits = TestLimits()) {
  v1::SiteInfo info;
  info.set_owner(owner);
  info.set_name(absl::StrCat("site of ", owner));
  info.set_state(state);
  info.set_outdoor_key("site-key");
  info.set_upload_bytes(static_cast<int64_t>(epw.size()));
  v1::Scene scene;
  scene.set_name("courtyard");
  return store.InsertSite(info, scene, epw, limits);
}

v1::JobEvent Progress(int64_t sequence, int evaluations) {
  v1::JobEvent event;
  event.set_sequence(sequence);
  event.mutable_progress()->set_evaluations(evaluations);
  return event;
}

template <typename Backend>
class StoreTest : public testing::Test {
 protected:
  void SetUp() override {
    absl::StatusOr<std::unique_ptr<Store>> store = backend_.Open(TestName());
    ASSERT_TRUE(store.ok()) << store.status();
    store_ = *std::move(store);
  }
  // Another handle on the same database: another replica.
  std::unique_ptr<Store> Another() {
    absl::StatusOr<std::unique_ptr<Store>> store = backend_.Again();
    EXPECT_TRUE(store.ok()) << store.status();
    return store.ok() ? *std::move(store) : nullptr;
  }
  std::string Insert(const Store::NewJob& job, Store* store = nullptr) {
    absl::StatusOr<v1::JobInfo> info = (store ? *store : *store_).InsertJob(job, TestLimits());
    EXPECT_TRUE(info.ok()) << info.status();
    return info.ok() ? info->id() : "";
  }
  // The next claim of `replica`, which must exist.
  Claim Take(const std::string& replica, std::vector<std::string> preferred = {},
             int64_t lease_ms = 60'000, Store* store = nullptr) {
    absl::StatusOr<std::optional<Claim>> claim =
        (store ? *store : *store_).ClaimWork(replica, lease_ms, preferred, {});
    EXPECT_TRUE(claim.ok()) << claim.status();
    EXPECT_TRUE(claim.ok() && claim->has_value());
    return claim.ok() && *claim ? **claim : Claim{};
  }

  Backend backend_;
  std::unique_ptr<Store> store_;
};

using Backends = testing::Types<SqliteBackend, PostgresBackend>;
TYPED_TEST_SUITE(StoreTest, Backends, BackendNames);

TYPED_TEST(StoreTest, JobsAndEventsSurviveReopeningAndIdsAreNeverReused) {
  Store& store = *this->store_;
  EXPECT_EQ(this->Insert(NewJob("ann")), "job-1");
  EXPECT_EQ(this->Insert(NewJob("ann")), "job-2");
  absl::StatusOr<v1::JobInfo> queued = store.GetJob("job-2");
  ASSERT_TRUE(queued.ok()) << queued.status();
  EXPECT_EQ(queued->state(), v1::JOB_STATE_QUEUED);
  EXPECT_EQ(queued->queue_position(), 1);
  EXPECT_EQ(queued->owner(), "ann");
  EXPECT_EQ(queued->last_sequence(), 1);

  const Claim claim = this->Take("replica-a");
  EXPECT_EQ(claim.lease.id, "job-1");
  v1::JobInfo info = *store.GetJob("job-1");
  info.set_state(v1::JOB_STATE_RUNNING);
  for (int s = 2; s <= 4; ++s) {
    info.set_last_sequence(s);
    const v1::JobEvent event = Progress(s, s - 1);
    ASSERT_TRUE(store.UpdateJob(claim.lease, info, &event, /*durable=*/false).ok());
  }
  // An event whose sequence is taken fails, and its whole transaction with it
  info.set_name("renamed");
  const v1::JobEvent duplicate = Progress(3, 9);
  EXPECT_EQ(store.UpdateJob(claim.lease, info, &duplicate).code(),
            absl::StatusCode::kAlreadyExists);
  ASSERT_TRUE(store.DeleteJob("job-2").ok());

  this->store_ = this->Another();
  Store& reopened = *this->store_;
  absl::StatusOr<v1::JobInfo> running = reopened.GetJob("job-1");
  ASSERT_TRUE(running.ok()) << running.status();
  EXPECT_EQ(running->state(), v1::JOB_STATE_RUNNING);
  EXPECT_EQ(running->last_sequence(), 4);
  EXPECT_EQ(running->name(), "job of ann");
  EXPECT_EQ(running->replica(), "replica-a");
  absl::StatusOr<std::vector<v1::JobEvent>> events = reopened.LoadEvents("job-1");
  ASSERT_TRUE(events.ok()) << events.status();
  ASSERT_EQ(events->size(), 4u);
  EXPECT_EQ((*events)[0].queued(), 0);
  EXPECT_EQ((*events)[3].progress().evaluations(), 3);
  EXPECT_EQ(reopened.LoadEvents("job-1", 2)->size(), 2u);
  EXPECT_EQ(reopened.LoadJob("job-1")->name(), "job of ann");
  EXPECT_EQ(reopened.GetJob("job-2").status().code(), absl::StatusCode::kNotFound);
  EXPECT_EQ(this->Insert(NewJob("bob"), &reopened), "job-3");
  absl::StatusOr<std::vector<v1::JobInfo>> listed =
      reopened.ListJobs("", v1::JOB_STATE_UNSPECIFIED, 10);
  ASSERT_TRUE(listed.ok());
  ASSERT_EQ(listed->size(), 2u);
  EXPECT_EQ((*listed)[0].id(), "job-3");  // newest first
  EXPECT_EQ(reopened.ListJobs("bob", v1::JOB_STATE_UNSPECIFIED, 10)->size(), 1u);
  EXPECT_EQ(reopened.ListJobs("", v1::JOB_STATE_RUNNING, 10)->size(), 1u);
  EXPECT_EQ(reopened.ListJobs("", v1::JOB_STATE_UNSPECIFIED, 1)->size(), 1u);
}

TYPED_TEST(StoreTest, SitesKeepTheirScenesAndWeather) {
  Store& store = *this->store_;
  absl::StatusOr<v1::SiteInfo> a = InsertSite(store, "ann", v1::SITE_STATE_READY, "epw");
  ASSERT_TRUE(a.ok()) << a.status();
  EXPECT_EQ(a->id(), "site-1");
  EXPECT_TRUE(a->has_weather());
  ASSERT_EQ(InsertSite(store, "bob")->id(), "site-2");
  absl::StatusOr<Store::StoredSite> got = store.GetSite("site-1");
  ASSERT_TRUE(got.ok()) << got.status();
  EXPECT_EQ(got->info.name(), "site of ann");
  EXPECT_FALSE(got->info.has_scene());
  EXPECT_EQ(*store.ReadWeather(got->weather), "epw");
  EXPECT_EQ(store.LoadSiteScene("site-1")->name(), "courtyard");
  EXPECT_GT(*store.SiteSceneBytes("site-1"), 0);
  absl::StatusOr<v1::SiteInfo> updated =
      store.UpdateSite("site-1", nullptr, [](v1::SiteInfo& info) { info.set_jobs_reused(2); });
  ASSERT_TRUE(updated.ok()) << updated.status();
  EXPECT_EQ(store.GetSite("site-1")->info.jobs_reused(), 2);
  EXPECT_EQ(store.ListSites("")->size(), 2u);
  ASSERT_EQ(store.ListSites("bob")->size(), 1u);
  EXPECT_EQ((*store.ListSites("bob"))[0].owner(), "bob");
  EXPECT_TRUE(*store.KeyInUse("site-key"));
  EXPECT_FALSE(*store.KeyInUse("other"));

  // A job on the site shares its weather file; deleting the site leaves it to the job
  Store::NewJob on_site = NewJob("ann", "site-key", "");
  on_site.info.set_site_id("site-1");
  const std::string job = this->Insert(on_site);
  EXPECT_EQ(store.LoadJob(job)->weather_file(), got->weather);
  absl::StatusOr<Store::StoredSite> deleted = store.DeleteSite("site-1");
  ASSERT_TRUE(deleted.ok());
  store.ReleaseWeather(deleted->weather);
  EXPECT_EQ(*store.ReadWeather(got->weather), "epw");
  EXPECT_EQ(store.GetSite("site-1").status().code(), absl::StatusCode::kNotFound);
  // ... and a job on a site deleted meanwhile is refused
  EXPECT_EQ(store.InsertJob(on_site, TestLimits()).status().code(), absl::StatusCode::kNotFound);
}

TYPED_TEST(StoreTest, UsersSurviveReopening) {
  Store& store = *this->store_;
  ASSERT_TRUE(store.InsertUser(UserRecord{"ann", std::string(32, 'a'), false, 5, 0}).ok());
  ASSERT_TRUE(store.InsertUser(UserRecord{"root", std::string(32, '\0'), true, 6, 0}).ok());
  ASSERT_TRUE(store.RevokeUser("ann", 7).ok());
  ASSERT_TRUE(store.RevokeUser("ann", 8).ok());  // the first time stays
  EXPECT_EQ(store.RevokeUser("nobody", 8).code(), absl::StatusCode::kNotFound);
  this->store_ = this->Another();
  absl::StatusOr<std::vector<UserRecord>> users = this->store_->LoadUsers();
  ASSERT_TRUE(users.ok()) << users.status();
  ASSERT_EQ(users->size(), 2u);
  EXPECT_EQ((*users)[0].name, "ann");
  EXPECT_EQ((*users)[0].token_sha256, std::string(32, 'a'));
  EXPECT_EQ((*users)[0].created_unix_ms, 5);
  EXPECT_EQ((*users)[0].revoked_unix_ms, 7);
  EXPECT_TRUE((*users)[1].admin);
  EXPECT_EQ((*users)[1].token_sha256, std::string(32, '\0'));
  const absl::Status taken =
      this->store_->InsertUser(UserRecord{"ann", std::string(32, 'b'), false, 8, 0});
  EXPECT_EQ(taken.code(), absl::StatusCode::kAlreadyExists);
  EXPECT_EQ(taken.message(), "user 'ann' exists");
}

TYPED_TEST(StoreTest, AFinishedJobKeepsOnlyItsFinalEventAndNoCheckpoint) {
  Store& store = *this->store_;
  const std::string id = this->Insert(NewJob("ann"));
  const Claim claim = this->Take("a");
  v1::JobInfo info = *store.GetJob(id);
  info.set_state(v1::JOB_STATE_RUNNING);
  info.set_last_sequence(2);
  const v1::JobEvent progress = Progress(2, 1);
  ASSERT_TRUE(store.UpdateJob(claim.lease, info, &progress, false).ok());
  ASSERT_TRUE(store.SaveCheckpoint(claim.lease, std::string("\0\1\2", 3)).ok());
  EXPECT_EQ(**store.LoadCheckpoint(id), std::string("\0\1\2", 3));
  v1::JobEvent finished;
  finished.set_sequence(3);
  finished.mutable_finished()->set_evaluations(1);
  info.set_state(v1::JOB_STATE_SUCCEEDED);
  info.set_last_sequence(3);
  info.mutable_result()->set_evaluations(7);
  ASSERT_TRUE(store.FinishJob(claim.lease, info, finished).ok());
  // Its result comes with the job, not with the listing
  EXPECT_EQ(store.GetJob(id)->result().evaluations(), 7);
  absl::StatusOr<std::vector<v1::JobInfo>> listed = store.ListJobs("", v1::JOB_STATE_SUCCEEDED, 10);
  ASSERT_TRUE(listed.ok() && listed->size() == 1u) << listed.status();
  EXPECT_EQ((*listed)[0].id(), id);
  EXPECT_FALSE((*listed)[0].has_result());
  // Its events stay a while for watchers that lag behind, then only the final one
  EXPECT_EQ(store.LoadEvents(id)->size(), 3u);
  ASSERT_TRUE(Exec(store, "UPDATE jobs SET events_expire_unix_ms = {now} - 1").ok());
  this->Insert(NewJob("bob"));
  ASSERT_TRUE(store
                  .CancelJob("job-2",
                             [](v1::JobInfo& ended) {
                               ended.set_state(v1::JOB_STATE_CANCELLED);
                               v1::JobEvent event;
                               event.set_sequence(2);
                               return event;
                             })
                  .ok());
  absl::StatusOr<std::vector<v1::JobEvent>> events = store.LoadEvents(id);
  ASSERT_EQ(events->size(), 1u);
  EXPECT_TRUE((*events)[0].has_finished());
  EXPECT_EQ(store.LoadEvents("job-2")->size(), 2u);
  EXPECT_EQ(store.GetJob(id)->state(), v1::JOB_STATE_SUCCEEDED);
  EXPECT_EQ(store.GetJob(id)->replica(), "");
  EXPECT_FALSE(store.LoadCheckpoint(id)->has_value());
  // An ended job is no one's work, and its end is stored once
  EXPECT_FALSE(store.ClaimWork("b", 60'000, {}, {})->has_value());
  EXPECT_EQ(store.FinishJob(claim.lease, info, finished).code(), absl::StatusCode::kAborted);
}

TYPED_TEST(StoreTest, LimitsAreCountedInTheStore) {
  Store& store = *this->store_;
  v1::Limits limits = TestLimits();
  limits.set_max_queued_jobs(4);
  limits.set_max_queued_jobs_per_user(2);
  limits.set_max_upload_bytes_per_user(25);
  ASSERT_TRUE(store.InsertJob(NewJob("ann"), limits).ok());
  ASSERT_TRUE(store.InsertJob(NewJob("ann"), limits).ok());
  absl::Status refused = store.InsertJob(NewJob("ann"), limits).status();
  EXPECT_EQ(refused.code(), absl::StatusCode::kResourceExhausted);
  EXPECT_THAT(refused.message(), HasSubstr("limits.max_queued_jobs_per_user (2) reached"));
  ASSERT_TRUE(store.InsertJob(NewJob("bob"), limits).ok());
  ASSERT_TRUE(store.InsertJob(NewJob("carl"), limits).ok());
  refused = store.InsertJob(NewJob("dora"), limits).status();
  EXPECT_EQ(refused.code(), absl::StatusCode::kResourceExhausted);
  EXPECT_THAT(refused.message(), HasSubstr("max_queued_jobs = 4"));
  // A job that started waits no more; its upload counts until it ends
  this->Take("a");
  refused = store.InsertJob(NewJob("ann", "k", std::string(20, 'x')), limits).status();
  EXPECT_THAT(refused.message(), HasSubstr("limits.max_upload_bytes_per_user (25) reached"));
  ASSERT_TRUE(store.InsertJob(NewJob("ann", "k", std::string(7, 'x')), limits).ok());

  // Sites, in all and per user, and their uploads
  limits.set_max_sites(2);
  limits.set_max_sites_per_user(1);
  ASSERT_TRUE(InsertSite(store, "ann", v1::SITE_STATE_COMPUTING, "", limits).ok());
  refused = InsertSite(store, "ann", v1::SITE_STATE_COMPUTING, "", limits).status();
  EXPECT_THAT(refused.message(), HasSubstr("limits.max_sites_per_user (1) reached"));
  refused =
      InsertSite(store, "bob", v1::SITE_STATE_COMPUTING, std::string(20, 'b'), limits).status();
  EXPECT_THAT(refused.message(), HasSubstr("limits.max_upload_bytes_per_user (25) reached"));
  ASSERT_TRUE(InsertSite(store, "bob", v1::SITE_STATE_COMPUTING, "", limits).ok());
  refused = InsertSite(store, "dora", v1::SITE_STATE_COMPUTING, "", limits).status();
  EXPECT_THAT(refused.message(), HasSubstr("its limit max_sites"));
}

TYPED_TEST(StoreTest, ClaimsTakeTurnsAcrossUsersAndPreferMatricesHeldInMemory) {
  Store& store = *this->store_;
  const std::string a1 = this->Insert(NewJob("ann", "k1"));
  const std::string a2 = this->Insert(NewJob("ann", "k2"));
  const std::string a3 = this->Insert(NewJob("ann", "k1"));
  const std::string b1 = this->Insert(NewJob("bob", "k2"));
  ASSERT_TRUE(InsertSite(store, "carl").ok());
  // Nobody was served: oldest first, then each user in turn
  EXPECT_EQ(store.GetJob(a1)->queue_position(), 0);
  EXPECT_EQ(store.GetJob(b1)->queue_position(), 1);
  EXPECT_EQ(store.GetJob(a2)->queue_position(), 2);
  EXPECT_EQ(store.GetJob(a3)->queue_position(), 3);
  EXPECT_EQ(this->Take("r").lease.id, a1);
  EXPECT_EQ(this->Take("r").lease.id, b1);
  const Claim site = this->Take("r");
  EXPECT_EQ(site.kind, Claim::Kind::kSite);
  EXPECT_EQ(site.lease.id, "site-1");
  // ann's turn again: the job whose matrix this replica holds before the older one
  EXPECT_EQ(this->Take("r", {"k1"}).lease.id, a3);
  EXPECT_EQ(this->Take("r", {"k1"}).lease.id, a2);
  EXPECT_FALSE(store.ClaimWork("r", 60'000, {}, {})->has_value());
  // A site computation stores its end under its claim; a stale claim's is refused
  ASSERT_TRUE(Exec(store, "UPDATE sites SET lease_expires_unix_ms = 0").ok());
  const Claim again = this->Take("s");
  EXPECT_EQ(again.lease.id, "site-1");
  const auto ready = [](v1::SiteInfo& info) { info.set_state(v1::SITE_STATE_READY); };
  EXPECT_EQ(store.UpdateSite("site-1", &site.lease, ready).status().code(),
            absl::StatusCode::kAborted);
  ASSERT_TRUE(store.UpdateSite("site-1", &again.lease, ready).ok());
  EXPECT_EQ(store.GetSite("site-1")->info.state(), v1::SITE_STATE_READY);
  EXPECT_FALSE(store.ClaimWork("r", 60'000, {}, {})->has_value());
}

TYPED_TEST(StoreTest, AnExpiredLeaseIsTakenOverAndTheOldRunIsFenced) {
  Store& store = *this->store_;
  std::unique_ptr<Store> other = this->Another();
  const std::string id = this->Insert(NewJob("ann"));
  const Claim first = this->Take("replica-a", {}, /*lease_ms=*/60'000);
  // Held: another replica finds nothing
  EXPECT_FALSE(other->ClaimWork("replica-b", 60'000, {}, {})->has_value());
  ASSERT_TRUE(store.SaveCheckpoint(first.lease, "after 3 evaluations").ok());
  // The lease runs out (replica-a stopped renewing): replica-b takes the job over
  ASSERT_TRUE(Exec(store, "UPDATE jobs SET lease_expires_unix_ms = {now} - 1").ok());
  const Claim second = this->Take("replica-b", {}, 60'000, other.get());
  EXPECT_EQ(second.lease.id, id);
  EXPECT_TRUE(second.taken_over);
  EXPECT_EQ(second.previous_replica, "replica-a");
  EXPECT_EQ(second.lease.run, first.lease.run + 1);
  EXPECT_EQ(**other->LoadCheckpoint(id), "after 3 evaluations");
  // replica-a's writes are refused from now on; replica-b's go through
  v1::JobInfo info = *store.GetJob(id);
  info.set_state(v1::JOB_STATE_RUNNING);
  EXPECT_EQ(store.UpdateJob(first.lease, info, nullptr).code(), absl::StatusCode::kAborted);
  EXPECT_EQ(store.SaveCheckpoint(first.lease, "stale").code(), absl::StatusCode::kAborted);
  v1::JobEvent end;
  end.set_sequence(2);
  end.set_failed("stale");
  EXPECT_EQ(store.FinishJob(first.lease, info, end).code(), absl::StatusCode::kAborted);
  EXPECT_EQ(**store.LoadCheckpoint(id), "after 3 evaluations");
  ASSERT_TRUE(other->UpdateJob(second.lease, info, nullptr).ok());
  // Renewals tell who holds it, and a cancel asked from anywhere
  ASSERT_TRUE(store.CancelJob(id, [](v1::JobInfo&) { return v1::JobEvent(); }).ok());
  absl::StatusOr<std::vector<Store::Renewal>> renewed = store.RenewLeases(
      60'000, {{Claim::Kind::kJob, first.lease}, {Claim::Kind::kJob, second.lease}});
  ASSERT_TRUE(renewed.ok()) << renewed.status();
  EXPECT_FALSE((*renewed)[0].held);
  EXPECT_TRUE((*renewed)[1].held);
  EXPECT_TRUE((*renewed)[1].cancel_requested);
  // Given back (a replica that shuts down), or every lease ended (a single daemon's
  // restart): taken over at once
  ASSERT_TRUE(other->Release(Claim::Kind::kJob, second.lease).ok());
  const Claim third = this->Take("replica-c");
  EXPECT_TRUE(third.taken_over);
  ASSERT_TRUE(store.ExpireLeases().ok());
  EXPECT_EQ(this->Take("replica-d").lease.run, third.lease.run + 1);
}

TYPED_TEST(StoreTest, CancelEndsAQueuedJobAndFlagsARunningOne) {
  Store& store = *this->store_;
  const std::string running = this->Insert(NewJob("ann"));
  const std::string queued = this->Insert(NewJob("ann"));
  const Claim claim = this->Take("a");
  absl::StatusOr<Store::Cancelled> cancelled = store.CancelJob(queued, [](v1::JobInfo& info) {
    info.set_state(v1::JOB_STATE_CANCELLED);
    info.set_last_sequence(2);
    v1::JobEvent event;
    event.set_sequence(2);
    event.mutable_cancelled();
    return event;
  });
  ASSERT_TRUE(cancelled.ok()) << cancelled.status();
  EXPECT_TRUE(cancelled->ended);
  EXPECT_FALSE(cancelled->weather.empty());
  EXPECT_EQ(store.GetJob(queued)->state(), v1::JOB_STATE_CANCELLED);
  EXPECT_TRUE(store.LoadEvents(queued)->back().has_cancelled());
  cancelled = store.CancelJob(running, [](v1::JobInfo&) { return v1::JobEvent(); });
  ASSERT_TRUE(cancelled.ok());
  EXPECT_FALSE(cancelled->ended);
  EXPECT_TRUE(cancelled->info.cancel_requested());
  EXPECT_TRUE(store.GetJob(running)->cancel_requested());
  bool cancel_requested = false;
  v1::JobInfo info = *store.GetJob(running);
  ASSERT_TRUE(store.UpdateJob(claim.lease, info, nullptr, true, &cancel_requested).ok());
  EXPECT_TRUE(cancel_requested);
  EXPECT_EQ(store.CancelJob("job-9", nullptr).status().code(), absl::StatusCode::kNotFound);
}

TYPED_TEST(StoreTest, WeatherFilesAreSharedByContentAndGoWithTheirLastUser) {
  Store& store = *this->store_;
  const std::string first = this->Insert(NewJob("ann", "k", "same bytes"));
  const std::string second = this->Insert(NewJob("bob", "k", "same bytes"));
  const std::string weather = store.LoadJob(first)->weather_file();
  EXPECT_EQ(store.LoadJob(second)->weather_file(), weather);
  EXPECT_EQ(*store.ReadWeather(weather), "same bytes");
  for (const std::string& id : {first, second}) {
    const Claim claim = this->Take("a");
    v1::JobInfo info = *store.GetJob(claim.lease.id);
    info.set_state(v1::JOB_STATE_SUCCEEDED);
    info.set_last_sequence(2);
    v1::JobEvent end;
    end.set_sequence(2);
    ASSERT_TRUE(store.FinishJob(claim.lease, info, end).ok());
    store.ReleaseWeather(weather);
    EXPECT_EQ(store.ReadWeather(weather).ok(), id == first) << id;
  }
}

TYPED_TEST(StoreTest, MatricesAreCheckedWhenRead) {
  Store& store = *this->store_;
  const std::string bytes("matrix\0bytes", 12);
  ASSERT_TRUE(store.PutMatrix("key-1", bytes).ok());
  ASSERT_TRUE(store.PutMatrix("key-1", "again").ok());  // the first stays
  EXPECT_EQ(**store.GetMatrix("key-1"), bytes);
  EXPECT_TRUE(*store.HasMatrix("key-1"));
  EXPECT_FALSE(store.GetMatrix("key-2")->has_value());
  EXPECT_THAT(*store.MatrixKeys(), testing::ElementsAre("key-1"));
  ASSERT_TRUE(Exec(store, "UPDATE outdoor_matrices SET bytes = ?", {SqlBlob{"matrix bytes"}}).ok());
  const absl::Status corrupt = store.GetMatrix("key-1").status();
  EXPECT_EQ(corrupt.code(), absl::StatusCode::kDataLoss);
  EXPECT_THAT(corrupt.message(), HasSubstr("checksum"));
  EXPECT_FALSE(*store.HasMatrix("key-1"));  // removed, to be traced again
}

TYPED_TEST(StoreTest, RecordsThatDoNotParseAreQuarantined) {
  Store& store = *this->store_;
  for (int k = 0; k < 3; ++k) {
    this->Insert(NewJob("ann"));
    ASSERT_TRUE(InsertSite(store, "ann").ok());
  }
  ASSERT_TRUE(
      Exec(store, "UPDATE jobs SET info = ? WHERE id = 'job-2'", {SqlBlob{"\xff\x01"}}).ok());
  ASSERT_TRUE(
      Exec(store, "UPDATE jobs SET job = ? WHERE id = 'job-3'", {SqlBlob{"\xff\x01"}}).ok());
  v1::SiteInfo other;
  other.set_id("site3");
  const std::string names_another = other.SerializeAsString();
  ASSERT_TRUE(
      Exec(store, "UPDATE sites SET info = ? WHERE id = 'site-1'", {SqlBlob{names_another}}).ok());
  absl::StatusOr<std::vector<Store::Quarantined>> moved = store.QuarantineUnparsable();
  ASSERT_TRUE(moved.ok()) << moved.status();
  ASSERT_EQ(moved->size(), 2u);
  EXPECT_EQ((*moved)[0].id, "job-2");
  EXPECT_EQ((*moved)[0].reason, "its JobInfo does not parse");
  EXPECT_EQ((*moved)[1].id, "site-1");
  EXPECT_EQ((*moved)[1].reason, "its SiteInfo names another site");
  EXPECT_EQ(store.GetJob("job-2").status().code(), absl::StatusCode::kNotFound);
  // A job's submitted form is read when it runs
  const absl::Status unreadable = store.LoadJob("job-3").status();
  EXPECT_EQ(unreadable.code(), absl::StatusCode::kDataLoss);
  EXPECT_TRUE(IsUnparsableRecord(unreadable));
  EXPECT_EQ(unreadable.GetPayload(kUnparsableRecordUrl), absl::Cord("job-3"));
  EXPECT_FALSE(IsUnparsableRecord(absl::DataLossError("the job's stored weather file is missing")));
  ASSERT_TRUE(store.Quarantine("jobs", "job-3", "its Job does not parse").ok());
  // Moved, not lost: the next scan finds only the sound ones
  EXPECT_TRUE(store.QuarantineUnparsable()->empty());
  EXPECT_EQ(store.ListJobs("", v1::JOB_STATE_UNSPECIFIED, 10)->size(), 1u);
  EXPECT_EQ(store.ListSites("")->size(), 2u);
  absl::StatusOr<int64_t> kept = 0;
  ASSERT_TRUE(store.database()
                  .Transact({},
                            [&](SqlSession& s) -> absl::Status {
                              absl::StatusOr<SqlResult> rows =
                                  s.Run("SELECT COUNT(*) FROM quarantine WHERE info IS NOT NULL");
                              if (!rows.ok()) return rows.status();
                              kept = rows->rows[0].Int(0);
                              return absl::OkStatus();
                            })
                  .ok());
  EXPECT_EQ(*kept, 3);
}

TYPED_TEST(StoreTest, ASchemaNewerThanTheBinaryIsAClearError) {
  int from = 0, to = 0;
  ASSERT_TRUE(Migrate(this->store_->database(), &from, &to).ok());
  EXPECT_EQ(from, Migrations().back().version);
  EXPECT_EQ(to, Migrations().back().version);
  ASSERT_TRUE(Exec(*this->store_, "UPDATE schema_version SET version = 99").ok());
  absl::StatusOr<std::unique_ptr<Store>> newer = this->backend_.Again();
  EXPECT_EQ(newer.status().code(), absl::StatusCode::kFailedPrecondition);
  EXPECT_THAT(newer.status().message(),
              HasSubstr(absl::StrCat("schema is version 99, newer than this fenestrad knows (",
                                     Migrations().back().version, ")")));
}

TYPED_TEST(StoreTest, ReplicasClaimEveryJobExactlyOnce) {
  constexpr int kJobs = 40;
  for (int k = 0; k < kJobs; ++k) this->Insert(NewJob(absl::StrCat("user", k % 3)));
  std::vector<std::unique_ptr<Store>> replicas;
  replicas.push_back(this->Another());
  replicas.push_back(this->Another());
  std::mutex mutex;
  std::multiset<std::string> claimed;
  std::vector<std::thread> workers;
  for (int w = 0; w < 6; ++w) {
    workers.emplace_back([&, w] {
      Store& store = *replicas[w % 2];
      while (true) {
        absl::StatusOr<std::optional<Claim>> claim =
            store.ClaimWork(absl::StrCat("r", w), 60'000, {}, {});
        ASSERT_TRUE(claim.ok()) << claim.status();
        if (!*claim) return;
        std::lock_guard lock(mutex);
        claimed.insert((*claim)->lease.id);
      }
    });
  }
  for (std::thread& t : workers) t.join();
  EXPECT_EQ(claimed.size(), static_cast<size_t>(kJobs));
  EXPECT_EQ(std::set<std::string>(claimed.begin(), claimed.end()).size(),
            static_cast<size_t>(kJobs));
}

TYPED_TEST(StoreTest, CopyToAnotherStoreKeepsEverythingAndRunningJobsAreTakenOver) {
  Store& store = *this->store_;
  ASSERT_TRUE(store.InsertUser(UserRecord{"ann", std::string(32, 'a'), false, 5, 0}).ok());
  ASSERT_TRUE(InsertSite(store, "ann", v1::SITE_STATE_READY, "site epw").ok());
  const std::string running = this->Insert(NewJob("ann", "k", "job epw"));
  const std::string queued = this->Insert(NewJob("ann", "k", "job epw"));
  const Claim claim = this->Take("source-replica");
  ASSERT_TRUE(store.SaveCheckpoint(claim.lease, "checkpoint").ok());
  ASSERT_TRUE(store.PutMatrix("key-1", "matrix").ok());

  ASSERT_TRUE(Server().ok()) << Server().error();
  const std::string url = Server().NewDatabase(FreshDatabaseName());
  ASSERT_FALSE(url.empty()) << Server().error();
  absl::StatusOr<std::unique_ptr<Store>> target = OpenStoreUrl(url, 2);
  ASSERT_TRUE(target.ok()) << target.status();
  std::vector<std::string> lines;
  ASSERT_TRUE(
      store.CopyTo(**target, false, [&](const std::string& l) { lines.push_back(l); }).ok());
  EXPECT_THAT(lines, testing::Contains("jobs: 2 rows"));
  EXPECT_THAT(lines, testing::Contains("weather: 2 files"));
  Store& copy = **target;
  EXPECT_EQ((*copy.LoadUsers())[0].name, "ann");
  EXPECT_EQ(copy.GetJob(queued)->state(), v1::JOB_STATE_QUEUED);
  EXPECT_EQ(copy.LoadEvents(queued)->size(), 1u);
  EXPECT_EQ(*copy.ReadWeather(copy.LoadJob(queued)->weather_file()), "job epw");
  EXPECT_EQ(*copy.ReadWeather(copy.GetSite("site-1")->weather), "site epw");
  EXPECT_EQ(**copy.GetMatrix("key-1"), "matrix");
  // The running job is the target's replicas' to take over, from its checkpoint
  absl::StatusOr<std::optional<Claim>> taken = copy.ClaimWork("target-replica", 60'000, {}, {});
  ASSERT_TRUE(taken.ok() && *taken) << taken.status();
  EXPECT_EQ((*taken)->lease.id, running);
  EXPECT_TRUE((*taken)->taken_over);
  EXPECT_EQ(**copy.LoadCheckpoint(running), "checkpoint");
  // Ids go on after the copied ones
  EXPECT_EQ(this->Insert(NewJob("ann"), &copy), "job-3");
  ASSERT_TRUE(InsertSite(copy, "bob").ok());
  EXPECT_EQ(copy.GetSite("site-2")->info.owner(), "bob");
  // A target that holds something is refused unless told
  const absl::Status again = store.CopyTo(copy, false, nullptr);
  EXPECT_EQ(again.code(), absl::StatusCode::kFailedPrecondition);
  EXPECT_THAT(again.message(), HasSubstr("--overwrite"));
  ASSERT_TRUE(store.CopyTo(copy, true, nullptr).ok());
  EXPECT_EQ(copy.GetJob("job-3").status().code(), absl::StatusCode::kNotFound);
  EXPECT_EQ(copy.ListSites("")->size(), 1u);
}

// ---- SQLite only

// Runs SQL on a SQLite file while no store holds it.
void Sqlite(const std::string& path, const std::string& sql) {
  sqlite3* db = nullptr;
  ASSERT_EQ(sqlite3_open(path.c_str(), &db), SQLITE_OK);
  EXPECT_EQ(sqlite3_exec(db, sql.c_str(), nullptr, nullptr, nullptr), SQLITE_OK)
      << sqlite3_errmsg(db);
  sqlite3_close(db);
}

std::string Hex(const std::string& bytes) {
  std::string hex;
  for (unsigned char c : bytes) absl::StrAppend(&hex, absl::Hex(c, absl::kZeroPad2));
  return hex;
}

TEST(SqliteStoreTest, AFileOfFenestradBeforeSchemaVersionsIsMigrated) {
  const std::string path = testing::TempDir() + "/store_test_legacy.db";
  for (const char* suffix : {"", "-wal", "-shm"}) std::filesystem::remove(path + suffix);
  // The tables as the daemon made them before versions: sites without a scene column, no
  // owners, a job that was running when the daemon stopped
  v1::SiteInfo site;
  site.set_id("site-1");
  site.set_name("old");
  site.set_state(v1::SITE_STATE_READY);
  site.mutable_scene()->set_name("courtyard");
  v1::JobInfo job_info;
  job_info.set_id("job-1");
  job_info.set_state(v1::JOB_STATE_RUNNING);
  job_info.set_outdoor_key("k");
  v1::Job job;
  job.set_weather_file("/var/lib/fenestra/weather/" + std::string(64, 'e') + ".epw");
  // And one that had ended, its result inside its info
  v1::JobInfo ended;
  ended.set_id("job-2");
  ended.set_state(v1::JOB_STATE_SUCCEEDED);
  ended.mutable_result()->set_evaluations(9);
  Sqlite(path,
         "CREATE TABLE sites (number INTEGER PRIMARY KEY AUTOINCREMENT, id TEXT UNIQUE, info BLOB "
         "NOT NULL, weather_path TEXT NOT NULL); CREATE TABLE jobs (number INTEGER PRIMARY KEY "
         "AUTOINCREMENT, id TEXT UNIQUE, info BLOB NOT NULL, job BLOB NOT NULL); INSERT INTO sites "
         "(id, info, weather_path) VALUES ('site-1', x'" +
             Hex(site.SerializeAsString()) +
             "', ''); INSERT INTO jobs (id, info, job) VALUES "
             "('job-1', x'" +
             Hex(job_info.SerializeAsString()) + "', x'" + Hex(job.SerializeAsString()) +
             "'), ('job-2', x'" + Hex(ended.SerializeAsString()) + "', x'" +
             Hex(job.SerializeAsString()) + "')");
  absl::StatusOr<std::unique_ptr<Store>> store =
      OpenStoreUrl("sqlite:" + std::filesystem::path(path).parent_path().string() + "/unused");
  EXPECT_FALSE(store.ok());  // no such folder
  absl::StatusOr<std::unique_ptr<SqliteDatabase>> db =
      SqliteDatabase::Open(path, SqliteDatabase::Sharing::kShared);
  ASSERT_TRUE(db.ok());
  store = Store::Open(*std::move(db));
  ASSERT_TRUE(store.ok()) << store.status();
  absl::StatusOr<Store::StoredSite> migrated = (*store)->GetSite("site-1");
  ASSERT_TRUE(migrated.ok()) << migrated.status();
  EXPECT_EQ(migrated->info.owner(), "local");
  EXPECT_FALSE(migrated->info.has_scene());
  EXPECT_EQ((*store)->LoadSiteScene("site-1")->name(), "courtyard");
  EXPECT_EQ((*store)->GetJob("job-1")->owner(), "local");
  // The result moved to its own column: with the job, not in listings
  EXPECT_EQ((*store)->GetJob("job-2")->result().evaluations(), 9);
  absl::StatusOr<std::vector<v1::JobInfo>> listed =
      (*store)->ListJobs("", v1::JOB_STATE_SUCCEEDED, 10);
  ASSERT_TRUE(listed.ok() && listed->size() == 1u) << listed.status();
  EXPECT_FALSE((*listed)[0].has_result());
  // The job that was running is taken over, with its weather file found by content
  absl::StatusOr<std::optional<Claim>> claim = (*store)->ClaimWork("r", 60'000, {}, {});
  ASSERT_TRUE(claim.ok() && *claim) << claim.status();
  EXPECT_EQ((*claim)->lease.id, "job-1");
  EXPECT_TRUE((*claim)->taken_over);
  EXPECT_TRUE(*(*store)->KeyInUse("k"));
  // New sites keep their scenes in their own column; ids go on
  absl::StatusOr<v1::SiteInfo> fresh = InsertSite(**store, "ann");
  ASSERT_TRUE(fresh.ok()) << fresh.status();
  EXPECT_EQ(fresh->id(), "site-2");
  EXPECT_EQ((*store)->LoadSiteScene("site-2")->name(), "courtyard");
}

TEST(SqliteStoreTest, ASharedFileSeesTheUsersAnotherAddsAnExclusiveOneKeepsOthersOut) {
  const std::string path = testing::TempDir() + "/store_test_sharing.db";
  for (const char* suffix : {"", "-wal", "-shm"}) std::filesystem::remove(path + suffix);
  const auto open = [&](SqliteDatabase::Sharing sharing) -> absl::StatusOr<std::unique_ptr<Store>> {
    absl::StatusOr<std::unique_ptr<SqliteDatabase>> db = SqliteDatabase::Open(path, sharing);
    if (!db.ok()) return db.status();
    return Store::Open(*std::move(db));
  };
  {
    // The daemon's store and `fenestrad user add` beside it
    auto daemon = open(SqliteDatabase::Sharing::kShared);
    ASSERT_TRUE(daemon.ok()) << daemon.status();
    auto command = open(SqliteDatabase::Sharing::kShared);
    ASSERT_TRUE(command.ok()) << command.status();
    ASSERT_TRUE((*command)->InsertUser(UserRecord{"ann", std::string(32, 'a'), false, 5, 0}).ok());
    ASSERT_EQ((*daemon)->LoadUsers()->size(), 1u);
    ASSERT_TRUE((*command)->RevokeUser("ann", 9).ok());
    EXPECT_EQ((*(*daemon)->LoadUsers())[0].revoked_unix_ms, 9);
  }
  auto first = open(SqliteDatabase::Sharing::kExclusive);
  ASSERT_TRUE(first.ok()) << first.status();
  ASSERT_TRUE((*first)->ListJobs("", v1::JOB_STATE_UNSPECIFIED, 1).ok());
  EXPECT_FALSE(std::filesystem::exists(path + "-shm"));
  auto second = open(SqliteDatabase::Sharing::kShared);
  EXPECT_EQ(second.status().code(), absl::StatusCode::kFailedPrecondition);
  EXPECT_THAT(std::string(second.status().message()), HasSubstr("in use by another"));
}

TEST(SqliteStoreTest, AnUnwritablePathIsAnError) {
  EXPECT_FALSE(
      SqliteDatabase::Open("/nonexistent/dir/fenestra.db", SqliteDatabase::Sharing::kShared).ok());
}

// ---- PostgreSQL only

TEST(PostgresStoreTest, AServerThatGoesAwayIsUnavailableThenReconnected) {
  PostgresServer server(absl::StrCat(testing::TempDir(), "/store_test_pg_restart.", getpid()));
  ASSERT_TRUE(server.ok()) << server.error();
  absl::StatusOr<std::unique_ptr<Store>> store = OpenStoreUrl(server.Url(), 2);
  ASSERT_TRUE(store.ok()) << store.status();
  ASSERT_TRUE((*store)->InsertUser(UserRecord{"ann", std::string(32, 'a'), false, 5, 0}).ok());
  const uint64_t changes = (*store)->database().ChangeCount();

  ASSERT_TRUE(server.Stop());
  const absl::Status away = (*store)->LoadUsers().status();
  EXPECT_EQ(away.code(), absl::StatusCode::kUnavailable);
  EXPECT_EQ(away.message(),
            "the server's job store (PostgreSQL) cannot be reached; try again in a few seconds");
  EXPECT_THAT(std::string(away.message()), testing::Not(HasSubstr("127.0.0.1")));
  // Waiting for an answer: none while it is away, until the wait is stopped
  int polls = 0;
  EXPECT_FALSE((*store)->AwaitAnswer(std::chrono::milliseconds(10), [&] { return ++polls > 3; }));
  EXPECT_EQ(polls, 4);

  // An answer once it is back
  bool restarted = false;
  std::thread restart([&] { restarted = server.Start(); });
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(60);
  EXPECT_TRUE((*store)->AwaitAnswer(std::chrono::milliseconds(50),
                                    [&] { return std::chrono::steady_clock::now() > deadline; }));
  restart.join();
  ASSERT_TRUE(restarted) << server.Log();
  absl::StatusOr<std::vector<UserRecord>> users = (*store)->LoadUsers();
  ASSERT_TRUE(users.ok()) << users.status();
  EXPECT_EQ(users->size(), 1u);
  // The listener connected again too: another process's change reaches this one
  absl::StatusOr<std::unique_ptr<Store>> other = OpenStoreUrl(server.Url(), 1);
  ASSERT_TRUE(other.ok()) << other.status();
  const uint64_t before = (*store)->database().ChangeCount();
  EXPECT_GE(before, changes);
  ASSERT_TRUE((*other)->InsertJob(NewJob("ann"), TestLimits()).ok());
  EXPECT_TRUE((*store)->database().WaitForChange(before, std::chrono::seconds(10)));
}

TEST(PostgresStoreTest, AnUnreachableServerIsNamedWithoutItsPassword) {
  const absl::Status refused =
      OpenStoreUrl("postgresql://fenestra:secret@127.0.0.1:1/fenestra", 1).status();
  EXPECT_EQ(refused.code(), absl::StatusCode::kUnavailable);
  EXPECT_THAT(refused.message(), HasSubstr("postgresql://fenestra:***@127.0.0.1:1/fenestra"));
  EXPECT_THAT(refused.message(), testing::Not(HasSubstr("secret")));
  EXPECT_EQ(OpenStoreUrl("mysql://x").status().code(), absl::StatusCode::kInvalidArgument);
}

}  // namespace
}  // namespace fenestra
