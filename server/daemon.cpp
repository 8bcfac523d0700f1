#include "server/daemon.h"

#include <grpcpp/ext/proto_server_reflection_plugin.h>
#include <grpcpp/grpcpp.h>
#include <grpcpp/health_check_service_interface.h>
#include <spdlog/spdlog.h>

#include <chrono>
#include <filesystem>

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
  absl::StatusOr<std::shared_ptr<grpc::ServerCredentials>> credentials = PortCredentials(config);
  if (!credentials.ok()) return credentials.status();
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
  const v1::Limits& limits = config.limits();
  d->queue_ = std::make_unique<WorkQueue>(config.worker_threads(), limits.max_queued_jobs(),
                                          limits.max_queued_jobs_per_user());
  d->uploads_ = std::make_unique<UploadQuota>(limits.max_upload_bytes_per_user());
  d->auth_ = std::make_unique<Authenticator>(config.auth(), *d->store_);
  d->sites_ =
      std::make_unique<SiteManager>(config, *d->store_, *d->cache_, *d->queue_, *d->uploads_);
  d->jobs_ = std::make_unique<JobManager>(config, *d->store_, *d->cache_, *d->queue_, *d->sites_,
                                          *d->uploads_);

  // The gRPC server; then what the last run left. The standard health service answers
  // without a token, so that load balancers' and orchestrators' probes can use it: it tells
  // only SERVING or NOT_SERVING. Reflection would answer without a token too, so it is
  // served only with auth none.
  grpc::EnableDefaultHealthCheckService(true);
  d->site_service_ = std::make_unique<SiteServiceImpl>(*d->sites_, *d->auth_);
  d->job_service_ = std::make_unique<JobServiceImpl>(*d->jobs_, *d->auth_);
  grpc::ServerBuilder builder;
  builder.SetOption(std::make_unique<ReflectionOption>(config.auth() == "none"));
  builder.AddListeningPort(config.listen_address(), *credentials, &d->port_);
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
  spdlog::info(
      "fenestrad listening on {} (port {}, {}, auth {}), data in {}, {} worker thread(s), backend "
      "{}",
      config.listen_address(), d->port_,
      config.tls_cert_file().empty()        ? "plaintext"
      : config.tls_client_ca_file().empty() ? "TLS"
                                            : "TLS with client certificates",
      config.auth(), data_dir.string(), config.worker_threads(), config.backend());
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
