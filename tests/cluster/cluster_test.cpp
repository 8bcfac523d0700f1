// Many fenestrad on one PostgreSQL: a throwaway server on loopback, three replicas with the
// CPU backend, quick jobs from several users through different replicas, a replica killed
// while it runs a job and started again, PostgreSQL stopped for a few seconds; and the
// single SQLite daemon killed and restarted. Every job must succeed once, with the result
// of the same job run in this process, a job taken over going on from its checkpoint.
#include <gmock/gmock.h>
#include <grpcpp/grpcpp.h>
#include <gtest/gtest.h>
#include <signal.h>

#include <atomic>
#include <chrono>
#include <filesystem>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <regex>
#include <set>
#include <string>
#include <thread>
#include <vector>

#include "absl/strings/str_cat.h"
#include "core/common/json_proto.h"
#include "fenestra/v1/service.grpc.pb.h"
#include "tests/child_process.h"
#include "tests/postgres_server.h"
#include "tests/quick_job.h"

namespace fenestra {
namespace {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;
using ::testing::HasSubstr;

// Quick jobs: 4 evaluations; the one killed mid-run: 24. No final check (it would only
// add time). Seeds 1-3 make three different jobs.
constexpr int kQuickEvaluations = 4;
constexpr int kLongEvaluations = 24;
constexpr int kSeeds = 3;

v1::Job ClusterJob(int evaluations, int seed) {
  v1::Job job = QuickJob(evaluations);
  job.mutable_sampling()->set_seed(seed);
  job.mutable_sampling()->set_final_check(false);
  job.mutable_budget()->set_failed_cycles_to_stop(-1);
  return job;
}

// What `fenestra job submit` sends for `job`: its scene inline, its weather's bytes.
v1::SubmitJobRequest Request(const v1::Job& job) {
  const std::string dir = FENESTRA_SOURCE_DIR "/examples/city_office/";
  v1::SubmitJobRequest request;
  *request.mutable_job() = job;
  request.mutable_job()->clear_scene_file();
  v1::Scene& scene = *request.mutable_job()->mutable_scene();
  EXPECT_TRUE(ReadJsonProtoFile(dir + job.scene_file(), "scene", &scene).ok());
  scene.mutable_site()->clear_weather_file();
  std::ifstream weather(FENESTRA_SOURCE_DIR "/examples/weather/URY_Montevideo.865800_IWEC.epw",
                        std::ios::binary);
  std::stringstream bytes;
  bytes << weather.rdbuf();
  request.set_weather_epw(bytes.str());
  return request;
}

// The registration of `job`'s site (its scene, outdoor sampling and weather).
v1::RegisterSiteRequest SiteRequest(const v1::Job& job) {
  const v1::SubmitJobRequest submit = Request(job);
  v1::RegisterSiteRequest request;
  *request.mutable_scene() = submit.job().scene();
  *request.mutable_sampling() = job.sampling();
  request.set_weather_epw(submit.weather_epw());
  return request;
}

// A job on a site: its scene inline, the site's weather.
v1::SubmitJobRequest OnSite(const v1::Job& job, const std::string& site) {
  v1::SubmitJobRequest request = Request(job);
  request.clear_weather_epw();
  request.set_site_id(site);
  return request;
}

// A client of one replica with one user's token.
class Client {
 public:
  Client(const std::string& address, std::string token)
      : channel_(grpc::CreateChannel(address, grpc::InsecureChannelCredentials())),
        stub_(v1::JobService::NewStub(channel_)),
        sites_(v1::SiteService::NewStub(channel_)),
        token_(std::move(token)) {}

  grpc::Status Submit(const v1::SubmitJobRequest& request, v1::JobInfo* info) {
    auto context = Context();
    return stub_->Submit(context.get(), request, info);
  }
  grpc::Status Cancel(const std::string& id) {
    auto context = Context();
    v1::CancelJobRequest request;
    request.set_id(id);
    v1::JobInfo info;
    return stub_->Cancel(context.get(), request, &info);
  }
  grpc::Status Register(const v1::RegisterSiteRequest& request, v1::SiteInfo* info) {
    auto context = Context();
    return sites_->Register(context.get(), request, info);
  }
  // Polls until the site is no longer computing, or 60 s.
  v1::SiteInfo WaitSite(const std::string& id) {
    const auto deadline = Clock::now() + std::chrono::seconds(60);
    v1::SiteInfo info;
    while (Clock::now() < deadline) {
      auto context = Context();
      v1::GetSiteRequest request;
      request.set_id(id);
      if (sites_->Get(context.get(), request, &info).ok() &&
          info.state() != v1::SITE_STATE_COMPUTING) {
        break;
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(100));
    }
    return info;
  }
  grpc::Status Get(const std::string& id, v1::JobInfo* info) {
    auto context = Context();
    v1::GetJobRequest request;
    request.set_id(id);
    return stub_->Get(context.get(), request, info);
  }
  // Polls until the job satisfies `done`, riding out UNAVAILABLE (the store away), or
  // `seconds` pass.
  v1::JobInfo Wait(const std::string& id, const std::function<bool(const v1::JobInfo&)>& done,
                   double seconds = 120) {
    const auto deadline = Clock::now() + std::chrono::duration<double>(seconds);
    v1::JobInfo info;
    while (Clock::now() < deadline) {
      const grpc::Status status = Get(id, &info);
      if (status.ok() && done(info)) return info;
      EXPECT_TRUE(status.ok() || status.error_code() == grpc::StatusCode::UNAVAILABLE)
          << status.error_message();
      std::this_thread::sleep_for(std::chrono::milliseconds(100));
    }
    ADD_FAILURE() << id << " did not get there in " << seconds << " s: " << info.DebugString();
    return info;
  }
  // A Watch stream of `id`; its events are collected by a thread until the stream ends.
  void Watch(const std::string& id) {
    watch_context_ = Context();
    v1::WatchJobRequest request;
    request.set_id(id);
    watch_ = stub_->Watch(watch_context_.get(), request);
    watcher_ = std::thread([this] {
      v1::JobEvent event;
      while (watch_->Read(&event)) {
        std::lock_guard lock(mutex_);
        events_.push_back(event);
      }
      watch_status_ = watch_->Finish();
    });
  }
  // The events watched, once the stream ended.
  std::vector<v1::JobEvent> Watched() {
    if (watcher_.joinable()) watcher_.join();
    EXPECT_TRUE(watch_status_.ok()) << watch_status_.error_message();
    return events_;
  }

 private:
  std::unique_ptr<grpc::ClientContext> Context() const {
    auto context = std::make_unique<grpc::ClientContext>();
    context->AddMetadata("authorization", "Bearer " + token_);
    return context;
  }

  std::shared_ptr<grpc::Channel> channel_;
  std::unique_ptr<v1::JobService::Stub> stub_;
  std::unique_ptr<v1::SiteService::Stub> sites_;
  std::string token_;
  std::unique_ptr<grpc::ClientContext> watch_context_;
  std::unique_ptr<grpc::ClientReader<v1::JobEvent>> watch_;
  std::thread watcher_;
  std::mutex mutex_;
  std::vector<v1::JobEvent> events_;
  grpc::Status watch_status_;
};

bool Ended(const v1::JobInfo& j) {
  return j.state() == v1::JOB_STATE_SUCCEEDED || j.state() == v1::JOB_STATE_FAILED ||
         j.state() == v1::JOB_STATE_CANCELLED || j.state() == v1::JOB_STATE_INTERRUPTED;
}

// The result of `job` run in this process (the outdoor matrix traced here too).
const v1::JobResult& Reference(int evaluations, int seed) {
  static std::map<std::pair<int, int>, v1::JobResult> results;
  auto [it, added] = results.try_emplace({evaluations, seed});
  if (added) {
    absl::StatusOr<v1::JobResult> run = RunQuickJob(ClusterJob(evaluations, seed));
    EXPECT_TRUE(run.ok()) << run.status();
    if (run.ok()) it->second = *std::move(run);
  }
  return it->second;
}

// Checks a job's result against the same job run in this process: the same best design and
// value, the same steps with the same values (times aside).
void ExpectSameResult(const v1::JobResult& got, const v1::JobResult& want, const std::string& id) {
  EXPECT_EQ(got.best_value().value(), want.best_value().value()) << id;
  EXPECT_EQ(got.best_value().standard_error(), want.best_value().standard_error()) << id;
  using Design = std::map<std::string, double>;
  EXPECT_EQ(Design(got.best_design().begin(), got.best_design().end()),
            Design(want.best_design().begin(), want.best_design().end()))
      << id;
  ASSERT_EQ(got.history_size(), want.history_size()) << id;
  for (int k = 0; k < got.history_size(); ++k) {
    EXPECT_EQ(got.history(k).index(), k) << id;
    EXPECT_EQ(got.history(k).value().value(), want.history(k).value().value())
        << id << " step " << k;
    EXPECT_EQ(got.history(k).cached(), want.history(k).cached()) << id << " step " << k;
  }
}

// How many times `text` occurs in `log`.
int Count(const std::string& log, const std::string& text) {
  int n = 0;
  for (size_t at = log.find(text); at != std::string::npos; at = log.find(text, at + 1)) ++n;
  return n;
}

// The log `read` gives once it holds every one of `texts`, or after 30 s: a daemon logs a
// job's end just after storing it, so a client may see the end before the log does.
std::string LogHolding(const std::function<std::string()>& read,
                       const std::vector<std::string>& texts) {
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(30);
  std::string log = read();
  const auto holds = [&] {
    for (const std::string& text : texts) {
      if (log.find(text) == std::string::npos) return false;
    }
    return true;
  };
  while (!holds() && std::chrono::steady_clock::now() < deadline) {
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
    log = read();
  }
  return log;
}

std::string Dir() {
  const auto* info = testing::UnitTest::GetInstance()->current_test_info();
  const std::string dir =
      testing::TempDir() + "/cluster_" + info->name() + "." + std::to_string(getpid());
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

// The replica name (host:pid:tag) a fenestrad log says it runs as.
std::string ReplicaOf(const std::string& log) {
  std::smatch match;
  static const std::regex pattern("replica ([^ \n]+)");
  std::string last;
  for (auto it = std::sregex_iterator(log.begin(), log.end(), pattern);
       it != std::sregex_iterator(); ++it) {
    last = (*it)[1];
  }
  return last;
}

class ClusterTest : public testing::Test {
 protected:
  void SetUp() override { dir_ = Dir(); }
  void TearDown() override {
    if (!HasFailure()) fs::remove_all(dir_);
  }
  std::string dir_;
};

TEST_F(ClusterTest, ReplicasRunEveryJobOnceThroughAKilledReplicaAndAStoreOutage) {
  PostgresServer postgres(dir_ + "/postgresql");
  ASSERT_TRUE(postgres.ok()) << postgres.error();
  const std::string store = postgres.Url();
  // Three users, made through the store; ann, an administrator, sees which replica runs a
  // job
  std::vector<std::string> tokens;
  for (const char* user : {"ann", "bob", "carl"}) {
    std::vector<std::string> add = {FENESTRAD, "user", "add", user, "--store", store};
    if (tokens.empty()) add.push_back("--admin");
    const CommandResult added = RunCommand(add);
    ASSERT_EQ(added.exit_code, 0) << added.output;
    std::smatch token;
    ASSERT_TRUE(std::regex_search(added.output, token, std::regex("\\b[0-9a-f]{64}\\b")));
    tokens.push_back(token.str());
  }
  const std::vector<std::string> flags = {"--auth",
                                          "token",
                                          "--store",
                                          store,
                                          "--backend",
                                          "cpu",
                                          "--workers",
                                          "1",
                                          "--lease-seconds",
                                          "4",
                                          "--max-queued-jobs-per-user",
                                          "16",
                                          "--shutdown-grace",
                                          "0.5"};
  std::vector<std::unique_ptr<FenestradProcess>> replicas;
  for (int i = 0; i < 3; ++i) {
    replicas.push_back(
        std::make_unique<FenestradProcess>(FENESTRAD, absl::StrCat(dir_, "/replica", i), flags));
    ASSERT_FALSE(replicas.back()->address().empty()) << replicas.back()->Log();
  }
  // clients[user][replica]
  std::vector<std::vector<std::unique_ptr<Client>>> clients(3);
  for (int u = 0; u < 3; ++u) {
    for (int i = 0; i < 3; ++i) {
      clients[u].push_back(std::make_unique<Client>(replicas[i]->address(), tokens[u]));
    }
  }

  // Each user's sites, one per seed, registered through one replica, ready for all: their
  // matrices are traced once per seed, by one replica or another
  std::vector<std::vector<std::string>> sites(3);  // sites[user][seed - 1]
  for (int u = 0; u < 3; ++u) {
    for (int seed = 1; seed <= kSeeds; ++seed) {
      v1::SiteInfo site;
      const grpc::Status status =
          clients[u][u]->Register(SiteRequest(ClusterJob(kQuickEvaluations, seed)), &site);
      ASSERT_TRUE(status.ok()) << status.error_message();
      sites[u].push_back(site.id());
    }
  }
  for (int u = 0; u < 3; ++u) {
    for (const std::string& site : sites[u]) {
      EXPECT_EQ(clients[u][(u + 1) % 3]->WaitSite(site).state(), v1::SITE_STATE_READY) << site;
    }
  }

  // The job to be killed first, then 30 quick ones: each user through each replica in turn
  v1::JobInfo long_job;
  ASSERT_TRUE(
      clients[0][0]->Submit(OnSite(ClusterJob(kLongEvaluations, 1), sites[0][0]), &long_job).ok());
  struct Quick {
    v1::JobInfo info;
    int seed;
    int user;
  };
  std::vector<Quick> quick;
  std::vector<std::thread> submitters;
  std::mutex mutex;
  for (int u = 0; u < 3; ++u) {
    submitters.emplace_back([&, u] {
      for (int k = 0; k < 10; ++k) {
        const int seed = 1 + (u + k) % kSeeds;
        v1::JobInfo info;
        const grpc::Status status = clients[u][(u + k) % 3]->Submit(
            OnSite(ClusterJob(kQuickEvaluations, seed), sites[u][seed - 1]), &info);
        ASSERT_TRUE(status.ok()) << status.error_message();
        std::lock_guard lock(mutex);
        quick.push_back({info, seed, u});
      }
    });
  }
  for (std::thread& t : submitters) t.join();
  ASSERT_EQ(quick.size(), 30u);
  std::set<std::string> ids = {long_job.id()};
  for (const Quick& q : quick) ids.insert(q.info.id());
  EXPECT_EQ(ids.size(), 31u);  // ids unique across replicas

  // The long job runs somewhere: watch it through another replica, kill the one running it
  const v1::JobInfo running = clients[0][0]->Wait(long_job.id(), [](const v1::JobInfo& j) {
    return j.state() == v1::JOB_STATE_RUNNING && j.progress().evaluations() >= 4;
  });
  int runner = -1;
  for (int i = 0; i < 3; ++i) {
    if (ReplicaOf(replicas[i]->Log()) == running.replica()) runner = i;
  }
  ASSERT_GE(runner, 0) << running.replica();
  const int watcher = (runner + 1) % 3;
  Client watch(replicas[watcher]->address(), tokens[0]);
  watch.Watch(long_job.id());
  std::this_thread::sleep_for(std::chrono::milliseconds(300));
  replicas[runner].reset();  // SIGKILL
  replicas[runner] =
      std::make_unique<FenestradProcess>(FENESTRAD, absl::StrCat(dir_, "/replica", runner), flags);
  ASSERT_FALSE(replicas[runner]->address().empty()) << replicas[runner]->Log();
  for (int u = 0; u < 3; ++u) {
    clients[u][runner] = std::make_unique<Client>(replicas[runner]->address(), tokens[u]);
  }

  // The store goes away for a few seconds while jobs run
  std::this_thread::sleep_for(std::chrono::seconds(2));
  ASSERT_TRUE(postgres.Stop());
  {
    v1::JobInfo info;
    const grpc::Status away = clients[1][1]->Get(long_job.id(), &info);
    EXPECT_EQ(away.error_code(), grpc::StatusCode::UNAVAILABLE);
    EXPECT_THAT(away.error_message(), HasSubstr("job store (PostgreSQL) cannot be reached"));
  }
  std::this_thread::sleep_for(std::chrono::seconds(3));
  ASSERT_TRUE(postgres.Start()) << postgres.Log();

  // Every job ends, succeeded, with the result it has when run alone
  const v1::JobInfo long_done = clients[0][2]->Wait(long_job.id(), Ended, 150);
  EXPECT_EQ(long_done.state(), v1::JOB_STATE_SUCCEEDED) << long_done.error();
  ExpectSameResult(long_done.result(), Reference(kLongEvaluations, 1), long_job.id());
  for (const Quick& q : quick) {
    const v1::JobInfo done = clients[q.user][2]->Wait(q.info.id(), Ended, 150);
    EXPECT_EQ(done.state(), v1::JOB_STATE_SUCCEEDED) << q.info.id() << " " << done.error();
    ExpectSameResult(done.result(), Reference(kQuickEvaluations, q.seed), q.info.id());
  }

  // Once: one replica's end of each job was stored, the killed one's run fenced off
  std::vector<std::string> ends;
  for (const std::string& id : ids) ends.push_back("job " + id + " succeeded");
  const std::string logs = LogHolding(
      [&] {
        std::string all;
        for (const auto& replica : replicas) all += replica->Log();
        return all;
      },
      ends);
  for (const std::string& id : ids) {
    EXPECT_EQ(Count(logs, "job " + id + " succeeded"), 1) << id;
  }
  EXPECT_THAT(logs, HasSubstr("cannot be reached"));
  EXPECT_THAT(logs, HasSubstr("can be reached again"));

  // The watcher saw the job taken over from its checkpoint, then its end
  const std::vector<v1::JobEvent> events = watch.Watched();
  ASSERT_FALSE(events.empty());
  EXPECT_TRUE(events.back().has_finished());
  // What was stored before the job was taken over, and what its taking over went on from
  int before_takeover = 0, resumed = -1;
  for (const v1::JobEvent& e : events) {
    if (e.has_started() && e.started().resumed_evaluations() > 0) {
      resumed = e.started().resumed_evaluations();
      break;
    }
    if (e.has_snapshot()) before_takeover = e.snapshot().progress().evaluations();
    if (e.has_progress()) before_takeover = e.progress().evaluations();
  }
  EXPECT_GE(before_takeover, 4);
  // No evaluation stored before the kill was done again: the checkpoint held them all
  EXPECT_GE(resumed, before_takeover);
  EXPECT_THAT(logs,
              HasSubstr("job " + long_job.id() + ": taken over from replica " + running.replica()));

  // A cancel through a replica that does not run the job reaches the one that does
  v1::JobInfo cancelled;
  ASSERT_TRUE(clients[1][0]->Submit(OnSite(ClusterJob(400, 1), sites[1][0]), &cancelled).ok());
  const v1::JobInfo runs = clients[0][0]->Wait(cancelled.id(), [](const v1::JobInfo& j) {
    return j.state() == v1::JOB_STATE_RUNNING && j.progress().evaluations() >= 1;
  });
  {
    v1::JobInfo seen_by_owner;  // not an administrator: no replica names
    ASSERT_TRUE(clients[1][0]->Get(cancelled.id(), &seen_by_owner).ok());
    EXPECT_EQ(seen_by_owner.state(), v1::JOB_STATE_RUNNING);
    EXPECT_EQ(seen_by_owner.replica(), "");
    EXPECT_NE(runs.replica(), "");
  }
  int other = 0;
  while (ReplicaOf(replicas[other]->Log()) == runs.replica()) ++other;
  const auto asked = Clock::now();
  ASSERT_TRUE(clients[1][other]->Cancel(cancelled.id()).ok());
  const v1::JobInfo stopped = clients[1][other]->Wait(cancelled.id(), Ended, 20);
  EXPECT_EQ(stopped.state(), v1::JOB_STATE_CANCELLED);
  EXPECT_LT(stopped.result().evaluations(), 400);
  std::cout << "cancel through another replica: the job stopped after "
            << std::chrono::duration<double>(Clock::now() - asked).count() << " s\n";
}

TEST_F(ClusterTest, TheSingleSqliteDaemonResumesAJobAfterSigkill) {
  const std::vector<std::string> flags = {"--backend", "cpu", "--workers", "1"};
  auto daemon = std::make_unique<FenestradProcess>(FENESTRAD, dir_ + "/data", flags);
  ASSERT_FALSE(daemon->address().empty()) << daemon->Log();
  auto client = std::make_unique<Client>(daemon->address(), "");
  v1::JobInfo job;
  ASSERT_TRUE(client->Submit(Request(ClusterJob(kLongEvaluations, 2)), &job).ok());
  const v1::JobInfo running = client->Wait(job.id(), [](const v1::JobInfo& j) {
    return j.state() == v1::JOB_STATE_RUNNING && j.progress().evaluations() >= 4;
  });
  daemon.reset();  // SIGKILL

  daemon = std::make_unique<FenestradProcess>(FENESTRAD, dir_ + "/data", flags);
  ASSERT_FALSE(daemon->address().empty()) << daemon->Log();
  client = std::make_unique<Client>(daemon->address(), "");
  const v1::JobInfo done = client->Wait(job.id(), Ended);
  EXPECT_EQ(done.state(), v1::JOB_STATE_SUCCEEDED) << done.error();
  ExpectSameResult(done.result(), Reference(kLongEvaluations, 2), job.id());
  // It went on after the steps its checkpoint held: at least those stored before the kill
  const std::string log =
      LogHolding([&] { return daemon->Log(); }, {"job " + job.id() + " succeeded"});
  std::smatch match;
  ASSERT_TRUE(std::regex_search(log, match,
                                std::regex("job " + job.id() +
                                           ": taken over .* goes on after its last "
                                           "checkpoint \\(([0-9]+) steps\\)")))
      << log;
  EXPECT_GE(std::stoi(match[1]), running.progress().evaluations());
  EXPECT_EQ(Count(log, "job " + job.id() + " succeeded"), 1);
}

TEST_F(ClusterTest, MigrateCopiesADataDirectoryIntoPostgresql) {
  // A single daemon's data directory: a user, a site, a job that ran on it
  const std::string data = dir_ + "/data";
  const CommandResult added = RunCommand({FENESTRAD, "user", "add", "ann", "--data-dir", data});
  ASSERT_EQ(added.exit_code, 0) << added.output;
  std::smatch token;
  ASSERT_TRUE(std::regex_search(added.output, token, std::regex("\\b[0-9a-f]{64}\\b")));
  const std::vector<std::string> flags = {"--auth", "token", "--backend", "cpu"};
  auto daemon = std::make_unique<FenestradProcess>(FENESTRAD, data, flags);
  ASSERT_FALSE(daemon->address().empty()) << daemon->Log();
  Client before(daemon->address(), token.str());
  const v1::Job job = ClusterJob(kQuickEvaluations, 3);
  v1::SiteInfo site;
  ASSERT_TRUE(before.Register(SiteRequest(job), &site).ok());
  ASSERT_EQ(before.WaitSite(site.id()).state(), v1::SITE_STATE_READY);
  v1::JobInfo ran;
  ASSERT_TRUE(before.Submit(OnSite(job, site.id()), &ran).ok());
  ran = before.Wait(ran.id(), Ended);
  ASSERT_EQ(ran.state(), v1::JOB_STATE_SUCCEEDED) << ran.error();

  PostgresServer postgres(dir_ + "/postgresql");
  ASSERT_TRUE(postgres.ok()) << postgres.error();
  const std::string store = postgres.Url();
  const auto migrate = [&](std::vector<std::string> extra) {
    std::vector<std::string> argv = {FENESTRAD,        "migrate", "--from",
                                     "sqlite:" + data, "--to",    store};
    argv.insert(argv.end(), extra.begin(), extra.end());
    return RunCommand(argv);
  };
  // Not while a daemon uses the directory
  CommandResult migrated = migrate({});
  EXPECT_EQ(migrated.exit_code, 1);
  EXPECT_THAT(migrated.output, HasSubstr("in use by another process"));
  daemon.reset();
  migrated = migrate({});
  ASSERT_EQ(migrated.exit_code, 0) << migrated.output;
  EXPECT_THAT(migrated.output, HasSubstr("users: 1 rows"));
  EXPECT_THAT(migrated.output, HasSubstr("jobs: 1 rows"));
  EXPECT_THAT(migrated.output, HasSubstr("sites: 1 rows"));
  EXPECT_THAT(migrated.output, HasSubstr("outdoor matrices: 1 files"));
  // A target that holds something only when told
  migrated = migrate({});
  EXPECT_EQ(migrated.exit_code, 1);
  EXPECT_THAT(migrated.output, HasSubstr("--overwrite"));
  migrated = migrate({"--overwrite"});
  ASSERT_EQ(migrated.exit_code, 0) << migrated.output;

  // A replica on the store serves them all: the user's token, the job's result, the site
  // with its matrix, which a new job reuses
  FenestradProcess replica(FENESTRAD, dir_ + "/replica",
                           {"--auth", "token", "--backend", "cpu", "--store", store});
  ASSERT_FALSE(replica.address().empty()) << replica.Log();
  Client after(replica.address(), token.str());
  v1::JobInfo copied;
  ASSERT_TRUE(after.Get(ran.id(), &copied).ok());
  EXPECT_EQ(copied.state(), v1::JOB_STATE_SUCCEEDED);
  ExpectSameResult(copied.result(), ran.result(), ran.id());
  EXPECT_EQ(after.WaitSite(site.id()).state(), v1::SITE_STATE_READY);
  v1::JobInfo next;
  ASSERT_TRUE(after.Submit(OnSite(job, site.id()), &next).ok());
  EXPECT_NE(next.id(), ran.id());
  next = after.Wait(next.id(), Ended);
  EXPECT_EQ(next.state(), v1::JOB_STATE_SUCCEEDED) << next.error();
  EXPECT_TRUE(next.outdoor_reused());
  ExpectSameResult(next.result(), ran.result(), next.id());
}

}  // namespace
}  // namespace fenestra
