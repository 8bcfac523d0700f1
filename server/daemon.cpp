#include "server/daemon.h"

#include <grpcpp/ext/proto_server_reflection_plugin.h>
#include <grpcpp/grpcpp.h>
#include <grpcpp/health_check_service_interface.h>
#include <spdlog/spdlog.h>

#include <chrono>
#include <filesystem>

#include "absl/strings/str_cat.h"

namespace fenestra {

Daemon::Daemon(const v1::DaemonConfig& config) : config_(config) {}

Daemon::~Daemon() { Shutdown(); }

absl::StatusOr<std::unique_ptr<Daemon>> Daemon::Start(const v1::DaemonConfig& config) {
  std::unique_ptr<Daemon> d(new Daemon(config));
  const std::filesystem::path data_dir = config.data_dir();
  std::error_code error;
  std::filesystem::create_directories(data_dir, error);
  if (error) {
    return absl::InternalError(absl::StrCat("cannot create the data directory ", data_dir.string(),
                                            ": ", error.message()));
  }

  // Store, cache and queue
  absl::StatusOr<std::unique_ptr<JobStore>> store =
      JobStore::Open((data_dir / "fenestra.db").string());
  if (!store.ok()) return store.status();
  d->store_ = *std::move(store);
  d->cache_ = std::make_unique<OutdoorCache>((data_dir / "outdoor").string());
  absl::StatusOr<OutdoorCache::LoadReport> loaded = d->cache_->Load();
  if (!loaded.ok()) return loaded.status();
  for (const std::string& discarded : loaded->discarded) {
    spdlog::warn("outdoor cache: discarded {}", discarded);
  }
  spdlog::info("outdoor cache: {} matrices loaded from {}", loaded->loaded,
               (data_dir / "outdoor").string());
  d->queue_ =
      std::make_unique<WorkQueue>(config.worker_threads(), config.limits().max_queued_jobs());
  d->sites_ = std::make_unique<SiteManager>(config, *d->store_, *d->cache_, *d->queue_);
  d->jobs_ = std::make_unique<JobManager>(config, *d->store_, *d->cache_, *d->queue_, *d->sites_);
  // The gRPC server; then what the last run left
  grpc::EnableDefaultHealthCheckService(true);
  grpc::reflection::InitProtoReflectionServerBuilderPlugin();
  d->site_service_ = std::make_unique<SiteServiceImpl>(*d->sites_);
  d->job_service_ = std::make_unique<JobServiceImpl>(*d->jobs_);
  grpc::ServerBuilder builder;
  builder.AddListeningPort(config.listen_address(), grpc::InsecureServerCredentials(), &d->port_);
  builder.SetMaxReceiveMessageSize(config.limits().max_message_bytes());
  builder.SetMaxSendMessageSize(config.limits().max_message_bytes());
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
  if (absl::Status s = d->sites_->Recover(); !s.ok()) return s;
  if (absl::Status s = d->jobs_->Recover(); !s.ok()) return s;
  spdlog::info("fenestrad listening on {} (port {}), data in {}, {} worker thread(s), backend {}",
               config.listen_address(), d->port_, data_dir.string(), config.worker_threads(),
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
