#include "server/daemon.h"

#include <grpcpp/ext/proto_server_reflection_plugin.h>
#include <grpcpp/grpcpp.h>
#include <grpcpp/health_check_service_interface.h>
#include <spdlog/spdlog.h>

#include <chrono>

#include "absl/strings/str_cat.h"

namespace fenestra {

Daemon::Daemon(const v1::DaemonConfig& config) : config_(config) {}

Daemon::~Daemon() { Shutdown(); }

absl::StatusOr<std::unique_ptr<Daemon>> Daemon::Start(const v1::DaemonConfig& config) {
  std::unique_ptr<Daemon> d(new Daemon(config));
  const v1::Limits& limits = config.limits();

  // The data directory: store, cache and uploads
  absl::StatusOr<std::unique_ptr<DataDir>> data_dir =
      DataDir::Open(config.data_dir(), limits.max_data_dir_bytes());
  if (!data_dir.ok()) return data_dir.status();
  d->data_dir_ = *std::move(data_dir);
  const DataDir& dir = *d->data_dir_;
  if (dir.full_at_start()) {
    spdlog::warn(
        "the data directory {} is full: fenestrad serves reads and refuses new work "
        "until space is freed there",
        dir.root().string());
  }
  if (dir.temporaries_removed() > 0) {
    spdlog::info("removed {} temporary file(s) of interrupted writes", dir.temporaries_removed());
  }
  absl::StatusOr<std::unique_ptr<JobStore>> store = JobStore::Open(dir.db_path().string());
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
  d->queue_ = std::make_unique<WorkQueue>(config.worker_threads(), limits.max_queued_jobs());
  d->sites_ = std::make_unique<SiteManager>(config, dir, *d->store_, *d->cache_, *d->weather_,
                                            *d->queue_, *d->heavy_);
  d->jobs_ = std::make_unique<JobManager>(config, dir, *d->store_, *d->cache_, *d->weather_,
                                          *d->queue_, *d->sites_, *d->heavy_);
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

  // The gRPC server
  grpc::EnableDefaultHealthCheckService(true);
  grpc::reflection::InitProtoReflectionServerBuilderPlugin();
  d->site_service_ = std::make_unique<SiteServiceImpl>(*d->sites_);
  d->job_service_ = std::make_unique<JobServiceImpl>(*d->jobs_);
  grpc::ServerBuilder builder;
  builder.AddListeningPort(config.listen_address(), grpc::InsecureServerCredentials(), &d->port_);
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
      "fenestrad listening on {} (port {}), data in {} ({} of {} bytes used), {} worker "
      "thread(s), backend {}",
      config.listen_address(), d->port_, dir.root().string(), dir.UsedBytes(), dir.max_bytes(),
      config.worker_threads(), config.backend());
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
