#include "server/daemon.h"

#include <grpcpp/ext/proto_server_reflection_plugin.h>
#include <grpcpp/grpcpp.h>
#include <grpcpp/health_check_service_interface.h>
#include <spdlog/spdlog.h>
#include <sys/random.h>
#include <unistd.h>

#include <chrono>
#include <ctime>

#include "absl/strings/str_cat.h"
#include "core/dc/dc_backend.h"
#include "server/log_safe.h"
#include "server/store/postgres_database.h"
#include "server/store/sqlite_database.h"
#include "server/tls.h"

namespace fenestra {
namespace {

// Server reflection on one server, or not: gRPC's reflection library, once linked, adds
// its plugin to every server of the process.
class ReflectionOption final : public grpc::ServerBuilderOption {
 public:
  explicit ReflectionOption(bool served) : served_(served) {}
  void UpdateArguments(grpc::ChannelArguments*) override {}
  void UpdatePlugins(std::vector<std::unique_ptr<grpc::ServerBuilderPlugin>>* plugins) override {
    std::erase_if(*plugins, [](const std::unique_ptr<grpc::ServerBuilderPlugin>& plugin) {
      return dynamic_cast<grpc::reflection::ProtoServerReflectionPlugin*>(plugin.get()) != nullptr;
    });
    if (served_) {
      plugins->push_back(std::make_unique<grpc::reflection::ProtoServerReflectionPlugin>());
    }
  }

 private:
  const bool served_;
};

// The name this process's claims carry in the store: host, process id and a random tag
// (process ids repeat across restarts and containers).
std::string ReplicaName() {
  char host[256] = {};
  gethostname(host, sizeof host - 1);
  uint16_t tag = 0;
  if (getrandom(&tag, sizeof tag, 0) != sizeof tag) tag = static_cast<uint16_t>(time(nullptr));
  return absl::StrCat(host, ":", getpid(), ":", absl::Hex(tag, absl::kZeroPad4));
}

// Pooled store connections: one per worker and a few for the RPCs and the renewer.
constexpr int kExtraConnections = 4;
// The longest an idle worker waits before it looks for work again [s]: how late a job
// whose replica stopped is taken over after its lease expired.
constexpr double kMaxPollSeconds = 1.0;

}  // namespace

Daemon::Daemon(const v1::DaemonConfig& config) : config_(config) {}

Daemon::~Daemon() { Shutdown(); }

absl::Status Daemon::OpenStore() {
  const v1::Limits& limits = config_.limits();
  if (!config_.store().empty()) {
    absl::StatusOr<std::unique_ptr<PostgresDatabase>> db =
        PostgresDatabase::Open(config_.store(), config_.worker_threads() + kExtraConnections);
    if (!db.ok()) return db.status();
    absl::StatusOr<std::unique_ptr<Store>> store = Store::Open(*std::move(db));
    if (!store.ok()) return store.status();
    store_ = *std::move(store);
    cache_ = std::make_unique<OutdoorCache>(*store_, config_.outdoor_memory_bytes());
    return absl::OkStatus();
  }
  absl::StatusOr<std::unique_ptr<DataDir>> data_dir =
      DataDir::Open(config_.data_dir(), limits.max_data_dir_bytes());
  if (!data_dir.ok()) return data_dir.status();
  data_dir_ = *std::move(data_dir);
  const DataDir& dir = *data_dir_;
  if (dir.full_at_start()) {
    spdlog::warn(
        "the data directory {} is full: fenestrad serves reads and refuses new work "
        "until space is freed there; `fenestrad user` can change its users only after a "
        "start with room",
        dir.root().string());
  }
  if (dir.temporaries_removed() > 0) {
    spdlog::info("removed {} temporary file(s) of interrupted writes", dir.temporaries_removed());
  }
  weather_ = std::make_unique<UploadStore>(dir, dir.weather_dir(), "epw");
  // Shared, so that `fenestrad user` changes the users of the running daemon; on a full
  // disk, where no -shm file can be made, this process's alone until the next start
  absl::StatusOr<std::unique_ptr<SqliteDatabase>> db = SqliteDatabase::Open(
      dir.db_path().string(),
      dir.full_at_start() ? SqliteDatabase::Sharing::kExclusive : SqliteDatabase::Sharing::kShared);
  if (!db.ok()) return db.status();
  absl::StatusOr<std::unique_ptr<Store>> store = Store::Open(*std::move(db), weather_.get());
  if (!store.ok()) return store.status();
  store_ = *std::move(store);
  // This daemon alone uses the data directory: what ran when the last one stopped is
  // taken over now, from its last checkpoint
  if (absl::Status s = store_->ExpireLeases(); !s.ok()) {
    spdlog::warn("cannot take over what was running ({}); it is taken over when its lease ends",
                 std::string(s.message()));
  }
  cache_ = std::make_unique<OutdoorCache>(dir.outdoor_dir().string(), data_dir_.get(),
                                          config_.outdoor_memory_bytes());
  return absl::OkStatus();
}

absl::StatusOr<std::unique_ptr<Daemon>> Daemon::Start(const v1::DaemonConfig& config) {
  std::unique_ptr<Daemon> d(new Daemon(config));
  // The health port first, so that probes find the process alive while the store opens
  if (!config.health_listen().empty()) {
    absl::StatusOr<std::unique_ptr<HealthServer>> health =
        HealthServer::Start(config.health_listen());
    if (!health.ok()) return health.status();
    d->health_ = *std::move(health);
    spdlog::info("health checks on {} (port {}, plaintext, the health service only)",
                 config.health_listen(), d->health_->port());
  }
  absl::StatusOr<std::shared_ptr<grpc::ServerCredentials>> credentials = PortCredentials(config);
  if (!credentials.ok()) return credentials.status();

  // The store and the cache
  if (absl::Status s = d->OpenStore(); !s.ok()) return s;
  absl::StatusOr<OutdoorCache::LoadReport> loaded = d->cache_->Load();
  if (!loaded.ok()) return loaded.status();
  for (const std::string& discarded : loaded->discarded) {
    spdlog::warn("outdoor cache: discarded {}", discarded);
  }
  spdlog::info(
      "outdoor cache: {} matrices loaded from {}", loaded->loaded,
      d->data_dir_ ? d->data_dir_->outdoor_dir().string() : d->store_->database().Describe());

  // The GPUs jobs take in turn (ResolveConfig checked the list)
  absl::StatusOr<std::vector<int>> gpus = ParseGpuList(config.gpus(), CudaDevices());
  if (!gpus.ok()) return gpus.status();
  UseCudaDevices(*gpus);

  d->MakeManagers();
  if (absl::Status s = d->Recover(); !s.ok()) return s;
  if (absl::Status s = d->Serve(*credentials); !s.ok()) return s;
  if (!config.http_listen().empty()) {
    absl::StatusOr<std::unique_ptr<HttpGateway>> http =
        HttpGateway::Start(config, {*d->auth_, *d->jobs_, *d->sites_});
    if (!http.ok()) return http.status();
    d->http_ = *std::move(http);
  }
  d->server_->GetHealthCheckService()->SetServingStatus(kReadinessService, true);
  if (d->health_) d->health_->SetReady(true);
  return d;
}

void Daemon::MakeManagers() {
  const v1::Limits& limits = config_.limits();
  heavy_ = std::make_unique<HeavyRequests>(limits.max_concurrent_heavy_requests());
  auth_ = std::make_unique<Authenticator>(config_.auth(), *store_);
  scheduler_ = std::make_unique<Scheduler>(*store_, *cache_, ReplicaName(),
                                           config_.worker_threads(), config_.lease_seconds(),
                                           std::min(kMaxPollSeconds, config_.lease_seconds() / 4));
  sites_ = std::make_unique<SiteManager>(config_, data_dir_.get(), *store_, *cache_, *heavy_,
                                         *scheduler_);
  jobs_ = std::make_unique<JobManager>(config_, data_dir_.get(), *store_, *cache_, *sites_, *heavy_,
                                       *scheduler_);
  cache_->SetInUse([store = store_.get()](const std::string& key) {
    absl::StatusOr<bool> used = store->KeyInUse(key);
    return !used.ok() || *used;
  });
  if (data_dir_) data_dir_->SetEvictor([cache = cache_.get()] { return cache->EvictOne(); });
}

absl::Status Daemon::Recover() {
  absl::StatusOr<std::vector<Store::Quarantined>> quarantined = store_->QuarantineUnparsable();
  if (!quarantined.ok()) return quarantined.status();
  for (const Store::Quarantined& q : *quarantined) {
    spdlog::error(
        "{} {}: its stored record does not parse ({}); moved to the quarantine table, the "
        "daemon goes on without it",
        q.id.starts_with("job-") ? "job" : "site", LogSafe(q.id), q.reason);
  }
  if (absl::Status s = sites_->Recover(); !s.ok()) return s;
  absl::StatusOr<int> removed = store_->CountWeatherReferences();
  if (!removed.ok()) return removed.status();
  if (*removed > 0) {
    spdlog::info("removed {} weather file(s) no site or unfinished job uses", *removed);
  }
  scheduler_->Start(
      [jobs = jobs_.get()](std::shared_ptr<Scheduler::Held> held) { jobs->Run(std::move(held)); },
      [sites = sites_.get()](std::shared_ptr<Scheduler::Held> held) {
        sites->Compute(std::move(held));
      });
  return absl::OkStatus();
}

absl::Status Daemon::Serve(const std::shared_ptr<grpc::ServerCredentials>& credentials) {
  const v1::Limits& limits = config_.limits();
  // The standard health service answers without a token, so that load balancers' and
  // orchestrators' probes can use it: it tells only SERVING or NOT_SERVING. Reflection
  // would answer without a token too, so it is served only with auth none.
  grpc::EnableDefaultHealthCheckService(true);
  site_service_ = std::make_unique<SiteServiceImpl>(*sites_, *auth_);
  job_service_ = std::make_unique<JobServiceImpl>(*jobs_, *auth_);
  grpc::ServerBuilder builder;
  builder.SetOption(std::make_unique<ReflectionOption>(config_.auth() == "none"));
  builder.AddListeningPort(config_.listen_address(), credentials, &port_);
  builder.SetMaxReceiveMessageSize(limits.max_message_bytes());
  builder.SetMaxSendMessageSize(limits.max_message_bytes());
  // Accept the clients' keepalive pings (every 30 s), also while no call is open
  builder.AddChannelArgument(GRPC_ARG_HTTP2_MIN_RECV_PING_INTERVAL_WITHOUT_DATA_MS, 10'000);
  builder.AddChannelArgument(GRPC_ARG_KEEPALIVE_PERMIT_WITHOUT_CALLS, 1);
  builder.RegisterService(site_service_.get());
  builder.RegisterService(job_service_.get());
  server_ = builder.BuildAndStart();
  if (!server_ || port_ == 0) {
    server_.reset();
    return absl::UnavailableError(
        absl::StrCat("cannot listen on ", config_.listen_address(), " (address in use?)"));
  }
  spdlog::info(
      "fenestrad listening on {} (port {}, {}, auth {}), {}, {} worker thread(s), backend {} "
      "(gpus {}), replica {}",
      config_.listen_address(), port_,
      config_.tls_cert_file().empty()        ? "plaintext"
      : config_.tls_client_ca_file().empty() ? "TLS"
                                             : "TLS with client certificates",
      config_.auth(),
      data_dir_ ? absl::StrCat("data in ", data_dir_->root().string(), " (", data_dir_->UsedBytes(),
                               " of ", data_dir_->max_bytes(), " bytes used)")
                : absl::StrCat("store ", store_->database().Describe(), " (lease ",
                               config_.lease_seconds(), " s)"),
      config_.worker_threads(), config_.backend(), config_.gpus(), scheduler_->replica());
  return absl::OkStatus();
}

void Daemon::Shutdown() {
  if (stopped_) return;
  stopped_ = true;
  if (server_) server_->GetHealthCheckService()->SetServingStatus(false);
  if (health_) health_->SetReady(false);
  if (jobs_) {
    jobs_->Shutdown(config_.shutdown_grace_seconds());
  } else if (scheduler_) {
    scheduler_->Join();
  }
  http_.reset();
  if (server_) {
    server_->Shutdown(std::chrono::system_clock::now() + std::chrono::seconds(2));
    server_->Wait();
  }
  // Last, so that liveness holds while jobs wind down
  health_.reset();
  spdlog::info("fenestrad stopped");
}

}  // namespace fenestra
