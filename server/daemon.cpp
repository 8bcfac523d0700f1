#include "server/daemon.h"

#include <grpcpp/ext/proto_server_reflection_plugin.h>
#include <grpcpp/grpcpp.h>
#include <grpcpp/health_check_service_interface.h>
#include <spdlog/spdlog.h>

#include <chrono>

#include "absl/strings/str_cat.h"
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

}  // namespace

Daemon::Daemon(const v1::DaemonConfig& config) : config_(config) {}

Daemon::~Daemon() { Shutdown(); }

absl::StatusOr<std::unique_ptr<Daemon>> Daemon::Start(const v1::DaemonConfig& config) {
  std::unique_ptr<Daemon> d(new Daemon(config));
  const v1::Limits& limits = config.limits();
  absl::StatusOr<std::shared_ptr<grpc::ServerCredentials>> credentials = PortCredentials(config);
  if (!credentials.ok()) return credentials.status();

  // The data directory: store, cache and uploads
  absl::StatusOr<std::unique_ptr<DataDir>> data_dir =
      DataDir::Open(config.data_dir(), limits.max_data_dir_bytes());
  if (!data_dir.ok()) return data_dir.status();
  d->data_dir_ = *std::move(data_dir);
  const DataDir& dir = *d->data_dir_;
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
  // Shared, so that `fenestrad user` changes the users of the running daemon; on a full
  // disk, where no -shm file can be made, this process's alone until the next start
  absl::StatusOr<std::unique_ptr<JobStore>> store =
      JobStore::Open(dir.db_path().string(), dir.full_at_start() ? JobStore::Sharing::kExclusive
                                                                 : JobStore::Sharing::kShared);
  if (!store.ok()) return store.status();
  d->store_ = *std::move(store);
  d->cache_ = std::make_unique<OutdoorCache>(dir.outdoor_dir().string(), d->data_dir_.get());
  absl::StatusOr<OutdoorCache::LoadReport> loaded = d->cache_->Load();
  if (!loaded.ok()) return loaded.status();
  for (const std::string& discarded : loaded->discarded) {
    spdlog::warn("outdoor cache: discarded {}", discarded);
  }
  spdlog::info("outdoor cache: {} matrices loaded from {}", loaded->loaded,
               dir.outdoor_dir().string());
  d->weather_ = std::make_unique<UploadStore>(dir, dir.weather_dir(), "epw");

  // Sites and jobs, and what they keep from being dropped
  d->heavy_ = std::make_unique<HeavyRequests>(limits.max_concurrent_heavy_requests());
  d->queue_ = std::make_unique<WorkQueue>(config.worker_threads(), limits.max_queued_jobs(),
                                          limits.max_queued_jobs_per_user());
  d->uploads_ = std::make_unique<UploadQuota>(limits.max_upload_bytes_per_user());
  d->auth_ = std::make_unique<Authenticator>(config.auth(), *d->store_);
  d->sites_ = std::make_unique<SiteManager>(config, dir, *d->store_, *d->cache_, *d->weather_,
                                            *d->queue_, *d->heavy_, *d->uploads_);
  d->jobs_ = std::make_unique<JobManager>(config, dir, *d->store_, *d->cache_, *d->weather_,
                                          *d->queue_, *d->sites_, *d->heavy_, *d->uploads_);
  Daemon* daemon = d.get();
  d->cache_->SetInUse([daemon](const std::string& key) {
    return daemon->sites_->UsesKey(key) || daemon->jobs_->UsesKey(key);
  });
  d->data_dir_->SetEvictor([daemon] { return daemon->cache_->EvictOne(); });

  // What the last run left
  if (absl::Status s = d->sites_->Recover(); !s.ok()) return s;
  if (absl::Status s = d->jobs_->Recover(); !s.ok()) return s;
  if (const int removed = d->weather_->RemoveUnreferenced(); removed > 0) {
    spdlog::info("removed {} weather file(s) no site or unfinished job uses", removed);
  }

  // The gRPC server. The standard health service answers without a token, so that load
  // balancers' and orchestrators' probes can use it: it tells only SERVING or NOT_SERVING.
  // Reflection would answer without a token too, so it is served only with auth none.
  grpc::EnableDefaultHealthCheckService(true);
  d->site_service_ = std::make_unique<SiteServiceImpl>(*d->sites_, *d->auth_);
  d->job_service_ = std::make_unique<JobServiceImpl>(*d->jobs_, *d->auth_);
  grpc::ServerBuilder builder;
  builder.SetOption(std::make_unique<ReflectionOption>(config.auth() == "none"));
  builder.AddListeningPort(config.listen_address(), *credentials, &d->port_);
  builder.SetMaxReceiveMessageSize(limits.max_message_bytes());
  builder.SetMaxSendMessageSize(limits.max_message_bytes());
  // Accept the clients' keepalive pings (every 30 s), also while no call is open
  builder.AddChannelArgument(GRPC_ARG_HTTP2_MIN_RECV_PING_INTERVAL_WITHOUT_DATA_MS, 10'000);
  builder.AddChannelArgument(GRPC_ARG_KEEPALIVE_PERMIT_WITHOUT_CALLS, 1);
  builder.RegisterService(d->site_service_.get());
  builder.RegisterService(d->job_service_.get());
  d->server_ = builder.BuildAndStart();
  if (!d->server_ || d->port_ == 0) {
    d->server_.reset();
    return absl::UnavailableError(
        absl::StrCat("cannot listen on ", config.listen_address(), " (address in use?)"));
  }
  spdlog::info(
      "fenestrad listening on {} (port {}, {}, auth {}), data in {} ({} of {} bytes used), {} "
      "worker thread(s), backend {}",
      config.listen_address(), d->port_,
      config.tls_cert_file().empty()        ? "plaintext"
      : config.tls_client_ca_file().empty() ? "TLS"
                                            : "TLS with client certificates",
      config.auth(), dir.root().string(), dir.UsedBytes(), dir.max_bytes(), config.worker_threads(),
      config.backend());
  return d;
}

void Daemon::Shutdown() {
  if (stopped_) return;
  stopped_ = true;
  if (server_) server_->GetHealthCheckService()->SetServingStatus(false);
  if (jobs_) jobs_->Shutdown(config_.shutdown_grace_seconds());
  if (server_) {
    server_->Shutdown(std::chrono::system_clock::now() + std::chrono::seconds(2));
    server_->Wait();
  }
  spdlog::info("fenestrad stopped");
}

}  // namespace fenestra
