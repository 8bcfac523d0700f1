// Many fenestrad on one PostgreSQL: how many jobs per second the shared queue gives, how
// long a claim takes, and how late a watcher on another replica hears an event.
//
//   replicas_bench store       the claim protocol alone (no physics): K "replicas" (each a
//                              Store with its own connections and one worker) claim, start,
//                              report and finish no-op jobs; K = 1, 2, 4, 8, then claims
//                              with 10^4 jobs queued; and SQLite's single daemon for scale
//   replicas_bench daemons     fenestrad processes (CPU backend, tiny jobs on one site):
//                              jobs per second with K = 1, 2, 4, 8 replicas; the time from
//                              submission to start on an idle cluster; Watch latency
//                              across replicas (LISTEN/NOTIFY)
//   replicas_bench watch       the Watch latency alone
//
// A throwaway PostgreSQL 15 (tests/postgres_server.h, fsync off) runs on this machine too.
#include <grpcpp/grpcpp.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <memory>
#include <mutex>
#include <numeric>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "absl/strings/str_cat.h"
#include "bench/bench_util.h"
#include "core/common/json_proto.h"
#include "core/common/seconds.h"
#include "core/optimize/job.h"
#include "fenestra/v1/service.grpc.pb.h"
#include "server/store/sqlite_database.h"
#include "server/store/store.h"
#include "tests/child_process.h"
#include "tests/postgres_server.h"

namespace fenestra {
namespace {

using Clock = std::chrono::steady_clock;

int64_t NowMs() {
  return std::chrono::duration_cast<std::chrono::milliseconds>(
             std::chrono::system_clock::now().time_since_epoch())
      .count();
}

// Stops the benchmark at a failure.
void Check(const absl::Status& status, const char* what) {
  if (status.ok()) return;
  std::fprintf(stderr, "error (%s): %s\n", what, std::string(status.message()).c_str());
  std::exit(1);
}

// The q-quantile of `values` (sorted here).
double Quantile(std::vector<double> values, double q) {
  if (values.empty()) return 0;
  std::sort(values.begin(), values.end());
  return values[static_cast<size_t>(q * (values.size() - 1) + 0.5)];
}

v1::Limits Unlimited() {
  v1::Limits limits;
  limits.set_max_queued_jobs(1'000'000);
  limits.set_max_queued_jobs_per_user(1'000'000);
  limits.set_max_sites(1000);
  limits.set_max_sites_per_user(1000);
  limits.set_max_upload_bytes_per_user(int64_t{1} << 40);
  return limits;
}

// Queues `count` no-op jobs of 4 users.
void Queue(Store& store, int count) {
  for (int k = 0; k < count; ++k) {
    Store::NewJob job;
    job.info.set_owner(absl::StrCat("user", k % 4));
    job.info.set_outdoor_key(absl::StrCat("key", k % 8));
    job.info.set_created_unix_ms(NowMs());
    job.weather_epw = "weather";
    ValueOrExit(store.InsertJob(job, Unlimited()));
  }
}

struct ClaimRun {
  int jobs = 0;
  double seconds = 0;
  std::vector<double> claim_ms;
};

// K replicas, one worker each, run every queued job as the daemon's runner does: claim,
// store the running state, one progress event with a checkpoint, the end. Stops after
// `limit` jobs (0: all).
ClaimRun RunClaims(const std::vector<std::unique_ptr<Store>>& replicas, int limit = 0) {
  ClaimRun run;
  std::mutex mutex;
  std::atomic<int> taken = 0;
  const std::string checkpoint(4000, 'c');  // a checkpoint of about 30 steps
  const auto start = Clock::now();
  std::vector<std::thread> workers;
  for (size_t r = 0; r < replicas.size(); ++r) {
    workers.emplace_back([&, r] {
      Store& store = *replicas[r];
      const std::string name = absl::StrCat("replica", r);
      std::vector<double> latencies;
      while (limit == 0 || taken < limit) {
        const auto t0 = Clock::now();
        std::optional<Claim> claim = ValueOrExit(store.ClaimWork(name, 60'000, {}, {}));
        latencies.push_back(1000 * SecondsSince(t0));
        if (!claim) break;
        ++taken;
        v1::JobInfo info = ValueOrExit(store.GetJob(claim->lease.id, /*position=*/false));
        info.set_state(v1::JOB_STATE_RUNNING);
        v1::JobEvent event;
        event.set_sequence(info.last_sequence() + 1);
        event.mutable_started()->set_backend("none");
        info.set_last_sequence(event.sequence());
        Check(store.UpdateJob(claim->lease, info, &event), "start");
        event.Clear();
        event.set_sequence(info.last_sequence() + 1);
        event.mutable_progress()->set_evaluations(1);
        info.set_last_sequence(event.sequence());
        Check(store.UpdateJob(claim->lease, info, &event, false, nullptr, &checkpoint), "progress");
        event.Clear();
        event.set_sequence(info.last_sequence() + 1);
        event.set_failed("no-op");
        info.set_state(v1::JOB_STATE_FAILED);
        info.set_last_sequence(event.sequence());
        Check(store.FinishJob(claim->lease, info, event), "finish");
      }
      std::lock_guard lock(mutex);
      run.claim_ms.insert(run.claim_ms.end(), latencies.begin(), latencies.end());
    });
  }
  for (std::thread& t : workers) t.join();
  run.seconds = SecondsSince(start);
  run.jobs = taken;
  return run;
}

void PrintClaims(const std::string& what, const ClaimRun& run) {
  std::printf("%-34s %6d jobs %7.2f s %8.1f jobs/s   claim p50 %6.2f ms  p99 %7.2f ms\n",
              what.c_str(), run.jobs, run.seconds, run.jobs / run.seconds,
              Quantile(run.claim_ms, 0.5), Quantile(run.claim_ms, 0.99));
}

void StoreBench(PostgresServer& postgres, const std::string& dir) {
  constexpr int kJobs = 2000;
  std::printf(
      "# the claim protocol alone: claim, running state, progress with a 4 kB checkpoint, "
      "end (4 transactions a job)\n");
  int database = 0;
  const auto replicas_on = [&](int k, const std::string& url) {
    std::vector<std::unique_ptr<Store>> replicas;
    for (int r = 0; r < k; ++r) replicas.push_back(ValueOrExit(OpenStoreUrl(url, 2)));
    return replicas;
  };
  for (const int k : {1, 2, 4, 8}) {
    const std::string url = postgres.NewDatabase(absl::StrCat("claims", database++));
    std::vector<std::unique_ptr<Store>> replicas = replicas_on(k, url);
    Queue(*replicas[0], kJobs);
    PrintClaims(absl::StrCat("PostgreSQL, ", k, " replica(s)"), RunClaims(replicas));
  }
  // A deep queue: the claims of the first 500 of 10^4
  for (const int k : {1, 8}) {
    const std::string url = postgres.NewDatabase(absl::StrCat("claims", database++));
    std::vector<std::unique_ptr<Store>> replicas = replicas_on(k, url);
    const auto start = Clock::now();
    Queue(*replicas[0], 10'000);
    std::printf("(10^4 jobs queued in %.1f s)\n", SecondsSince(start));
    PrintClaims(absl::StrCat("PostgreSQL, 10^4 queued, ", k, " replica(s)"),
                RunClaims(replicas, 500));
  }
  // The single daemon's SQLite file
  const std::string path = dir + "/claims.db";
  std::vector<std::unique_ptr<Store>> single;
  single.push_back(ValueOrExit(
      Store::Open(ValueOrExit(SqliteDatabase::Open(path, SqliteDatabase::Sharing::kExclusive)))));
  Queue(*single[0], kJobs);
  PrintClaims("SQLite, the single daemon", RunClaims(single));
}

// ---- fenestrad replicas

// A tiny job on the city office: one evaluation of few paths, no final check.
v1::Job TinyJob() {
  v1::Job job =
      ValueOrExit(ReadJobFile(FENESTRA_SOURCE_DIR "/examples/city_office/alpha_max_quick.json"));
  job.mutable_budget()->set_max_evaluations(1);
  job.mutable_sampling()->set_indoor_paths_per_sensor(200);
  job.mutable_sampling()->set_outdoor_paths(40000);
  job.mutable_sampling()->set_backend("cpu");
  job.mutable_sampling()->set_final_check(false);
  return job;
}

class Client {
 public:
  explicit Client(const std::string& address)
      : channel_(grpc::CreateChannel(address, grpc::InsecureChannelCredentials())),
        jobs_(v1::JobService::NewStub(channel_)),
        sites_(v1::SiteService::NewStub(channel_)) {}
  v1::JobService::Stub& jobs() { return *jobs_; }
  v1::SiteService::Stub& sites() { return *sites_; }
  v1::JobInfo Get(const std::string& id) {
    grpc::ClientContext context;
    v1::GetJobRequest request;
    request.set_id(id);
    v1::JobInfo info;
    const grpc::Status status = jobs_->Get(&context, request, &info);
    if (!status.ok()) Check(absl::InternalError(status.error_message()), "Get");
    return info;
  }
  v1::JobInfo Submit(const v1::SubmitJobRequest& request) {
    grpc::ClientContext context;
    v1::JobInfo info;
    const grpc::Status status = jobs_->Submit(&context, request, &info);
    if (!status.ok()) Check(absl::InternalError(status.error_message()), "Submit");
    return info;
  }

 private:
  std::shared_ptr<grpc::Channel> channel_;
  std::unique_ptr<v1::JobService::Stub> jobs_;
  std::unique_ptr<v1::SiteService::Stub> sites_;
};

bool Ended(const v1::JobInfo& j) { return j.state() >= v1::JOB_STATE_SUCCEEDED; }

// Registers the tiny job's site through `client` and waits for it; the request for jobs on
// it.
v1::SubmitJobRequest SiteAndRequest(Client& client) {
  const v1::Job job = TinyJob();
  v1::Scene scene;
  Check(ReadJsonProtoFile(FENESTRA_SOURCE_DIR "/examples/city_office/scene.json", "scene", &scene),
        "scene");
  scene.mutable_site()->clear_weather_file();
  std::ifstream in(FENESTRA_SOURCE_DIR "/examples/weather/URY_Montevideo.865800_IWEC.epw",
                   std::ios::binary);
  std::stringstream weather;
  weather << in.rdbuf();
  v1::RegisterSiteRequest site;
  *site.mutable_scene() = scene;
  *site.mutable_sampling() = job.sampling();
  site.set_weather_epw(weather.str());
  v1::SiteInfo info;
  {
    grpc::ClientContext context;
    const grpc::Status status = client.sites().Register(&context, site, &info);
    if (!status.ok()) Check(absl::InternalError(status.error_message()), "Register");
  }
  while (info.state() == v1::SITE_STATE_COMPUTING) {
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
    grpc::ClientContext context;
    v1::GetSiteRequest get;
    get.set_id(info.id());
    (void)client.sites().Get(&context, get, &info);
  }
  v1::SubmitJobRequest request;
  *request.mutable_job() = job;
  request.mutable_job()->clear_scene_file();
  *request.mutable_job()->mutable_scene() = scene;
  request.set_site_id(info.id());
  return request;
}

void DaemonBench(PostgresServer& postgres, const std::string& dir) {
  constexpr int kJobs = 48;
  std::printf(
      "\n# fenestrad replicas, CPU backend, 1 worker each; %d tiny jobs (1 evaluation, "
      "200 indoor paths per sensor, no final check) on one site\n",
      kJobs);
  for (const int k : {1, 2, 4, 8}) {
    const std::string url = postgres.NewDatabase(absl::StrCat("daemons", k));
    std::vector<std::unique_ptr<FenestradProcess>> replicas;
    for (int r = 0; r < k; ++r) {
      replicas.push_back(std::make_unique<FenestradProcess>(
          FENESTRAD, absl::StrCat(dir, "/replica", k, "_", r),
          std::vector<std::string>{"--store", url, "--backend", "cpu", "--workers", "1",
                                   "--max-queued-jobs", "1000", "--max-queued-jobs-per-user",
                                   "1000", "--log-level", "warn"}));
      if (replicas.back()->address().empty()) {
        std::fprintf(stderr, "fenestrad did not start:\n%s\n", replicas.back()->Log().c_str());
        std::exit(1);
      }
    }
    std::vector<std::unique_ptr<Client>> clients;
    for (const auto& r : replicas) clients.push_back(std::make_unique<Client>(r->address()));
    const v1::SubmitJobRequest request = SiteAndRequest(*clients[0]);

    // Submission to start on an idle cluster: one job at a time
    std::vector<double> start_ms;
    for (int i = 0; i < 10; ++i) {
      const v1::JobInfo queued = clients[i % k]->Submit(request);
      v1::JobInfo info = clients[i % k]->Get(queued.id());
      while (!Ended(info)) {
        std::this_thread::sleep_for(std::chrono::milliseconds(20));
        info = clients[i % k]->Get(queued.id());
      }
      start_ms.push_back(info.started_unix_ms() - info.created_unix_ms());
    }
    // Throughput: every job submitted at once, through every replica
    const auto start = Clock::now();
    std::vector<std::string> ids;
    for (int i = 0; i < kJobs; ++i) ids.push_back(clients[i % k]->Submit(request).id());
    double busy_seconds = 0;
    for (const std::string& id : ids) {
      v1::JobInfo info = clients[0]->Get(id);
      while (!Ended(info)) {
        std::this_thread::sleep_for(std::chrono::milliseconds(20));
        info = clients[0]->Get(id);
      }
      busy_seconds += (info.finished_unix_ms() - info.started_unix_ms()) / 1000.0;
    }
    const double seconds = SecondsSince(start);
    std::printf(
        "%d replica(s): %5.2f jobs/s (%d jobs in %.1f s; a job runs %.2f s on average); "
        "submission to start when idle: p50 %.0f ms, max %.0f ms\n",
        k, kJobs / seconds, kJobs, seconds, busy_seconds / kJobs, Quantile(start_ms, 0.5),
        Quantile(start_ms, 1.0));
  }
}

// The replica name (host:pid:tag) a fenestrad log says it runs as.
std::string ReplicaOf(const std::string& log) {
  const size_t at = log.rfind("replica ");
  if (at == std::string::npos) return "";
  const size_t end = log.find_first_of(" \n", at + 8);
  return log.substr(at + 8, end - at - 8);
}

// Jobs run by one replica, watched through another: how late each stored event arrives.
// Two jobs at a time, each watched through both replicas; the streams of the replica that
// does not run the job count.
void WatchBench(PostgresServer& postgres, const std::string& dir) {
  const std::string url = postgres.NewDatabase("watch");
  const std::vector<std::string> flags = {"--store",   url, "--backend",   "cpu",
                                          "--workers", "1", "--log-level", "info"};
  std::vector<std::unique_ptr<FenestradProcess>> replicas;
  std::vector<std::string> names;
  std::vector<std::unique_ptr<Client>> clients;
  for (const char* name : {"/watch_a", "/watch_b"}) {
    replicas.push_back(std::make_unique<FenestradProcess>(FENESTRAD, dir + name, flags));
    names.push_back(ReplicaOf(replicas.back()->Log()));
    clients.push_back(std::make_unique<Client>(replicas.back()->address()));
  }
  v1::SubmitJobRequest request = SiteAndRequest(*clients[0]);
  request.mutable_job()->mutable_budget()->set_max_evaluations(30);
  request.mutable_job()->mutable_budget()->set_failed_cycles_to_stop(-1);
  std::mutex mutex;
  std::vector<double> late_ms, local_ms;  // watched through another replica, the runner
  int jobs = 0;
  for (int round = 0; round < 3; ++round) {
    std::vector<std::thread> streams;
    for (int j = 0; j < 2; ++j) {
      const std::string id = clients[j]->Submit(request).id();
      for (int w = 0; w < 2; ++w) {
        streams.emplace_back([&, id, w] {
          grpc::ClientContext context;
          v1::WatchJobRequest watch;
          watch.set_id(id);
          std::unique_ptr<grpc::ClientReader<v1::JobEvent>> stream =
              clients[w]->jobs().Watch(&context, watch);
          v1::JobEvent event;
          bool remote = false;
          std::vector<double> late;
          while (stream->Read(&event)) {
            const int64_t now = NowMs();
            if (event.has_started()) remote = event.started().replica() != names[w];
            if (event.has_progress())
              late.push_back(static_cast<double>(now - event.time_unix_ms()));
          }
          (void)stream->Finish();
          std::lock_guard lock(mutex);
          std::vector<double>& into = remote ? late_ms : local_ms;
          into.insert(into.end(), late.begin(), late.end());
          jobs += remote;
        });
      }
    }
    for (std::thread& t : streams) t.join();
  }
  std::printf(
      "\n# Watch through one replica of jobs the other runs: %d jobs, %zu progress events; "
      "stored by the runner -> received by the watching client: p50 %.0f ms, p90 %.0f ms, "
      "max %.0f ms (millisecond clock, one machine); through the replica that runs it: p50 "
      "%.0f ms, p90 %.0f ms\n",
      jobs, late_ms.size(), Quantile(late_ms, 0.5), Quantile(late_ms, 0.9), Quantile(late_ms, 1.0),
      Quantile(local_ms, 0.5), Quantile(local_ms, 0.9));
}

}  // namespace
}  // namespace fenestra

int main(int argc, char** argv) {
  using namespace fenestra;
  const std::string what = argc > 1 ? argv[1] : "all";
  const std::string dir =
      absl::StrCat(std::filesystem::temp_directory_path().string(), "/replicas_bench.", getpid());
  std::filesystem::create_directories(dir);
  PostgresServer postgres(dir + "/postgresql");
  if (!postgres.ok()) {
    std::fprintf(stderr, "PostgreSQL did not start: %s\n", postgres.error().c_str());
    return 1;
  }
  if (what == "all" || what == "store") StoreBench(postgres, dir);
  if (what == "all" || what == "daemons") DaemonBench(postgres, dir);
  if (what == "all" || what == "daemons" || what == "watch") WatchBench(postgres, dir);
  std::filesystem::remove_all(dir + "/claims.db");
  return 0;
}
