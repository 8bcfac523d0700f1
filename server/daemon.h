#pragma once

#include <grpcpp/security/server_credentials.h>
#include <grpcpp/server.h>

#include <memory>

#include "absl/status/statusor.h"
#include "fenestra/v1/daemon.pb.h"
#include "server/data_dir.h"
#include "server/health.h"
#include "server/heavy_requests.h"
#include "server/http_gateway.h"
#include "server/job_manager.h"
#include "server/outdoor_cache.h"
#include "server/scheduler.h"
#include "server/services.h"
#include "server/site_manager.h"
#include "server/store/store.h"
#include "server/users.h"

namespace fenestra {

// fenestrad assembled: the store (SQLite in the data directory, with its outdoor matrix
// files and uploaded weather files; or a PostgreSQL database shared with other replicas),
// outdoor cache, scheduler (workers claiming jobs and site computations), sites, jobs and
// the gRPC server (SiteService, JobService, health checking, and reflection with auth
// none), over TLS when configured; with config.health_listen, the health port too
// (HealthServer).
class Daemon {
 public:
  // Opens the store (SQLite: the data directory, FailedPrecondition naming it when it is
  // not writable; what was running when the last daemon stopped is taken over at once;
  // PostgreSQL: Unavailable when it cannot be reached), brings its schema up to date,
  // quarantines the records that no longer parse, drops the uploaded files nothing
  // refers to any more, starts the workers and serves on config.listen_address; `config`
  // resolved (ResolveConfig). On a full disk it starts too: it serves reads and refuses
  // writes until space is freed.
  static absl::StatusOr<std::unique_ptr<Daemon>> Start(const v1::DaemonConfig& config);
  ~Daemon();

  // The port the server listens on (useful with port 0).
  int port() const { return port_; }
  // The health port (config.health_listen), or 0 when there is none.
  int health_port() const { return health_ ? health_->port() : 0; }
  // The dashboard's port; 0 without one.
  int http_port() const { return http_ ? http_->port() : 0; }

  // Reports NOT_SERVING to health checks, refuses new work, lets running jobs reach the
  // end or a checkpoint (see JobManager::Shutdown), then stops the gRPC server.
  void Shutdown();

 private:
  explicit Daemon(const v1::DaemonConfig& config);

  // Opens the store and the cache: SQLite in the data directory, or PostgreSQL.
  absl::Status OpenStore();
  // The managers of sites and jobs, the scheduler and what they share.
  void MakeManagers();
  // What the last run left: records that no longer parse quarantined, sites recovered,
  // unused weather files removed; then the workers start.
  absl::Status Recover();
  // The gRPC server on config_.listen_address.
  absl::Status Serve(const std::shared_ptr<grpc::ServerCredentials>& credentials);

  v1::DaemonConfig config_;
  std::unique_ptr<HealthServer> health_;
  std::unique_ptr<HttpGateway> http_;
  std::unique_ptr<DataDir> data_dir_;     // SQLite only
  std::unique_ptr<UploadStore> weather_;  // SQLite only
  std::unique_ptr<Store> store_;
  std::unique_ptr<OutdoorCache> cache_;
  std::unique_ptr<HeavyRequests> heavy_;
  std::unique_ptr<Authenticator> auth_;
  std::unique_ptr<Scheduler> scheduler_;
  std::unique_ptr<SiteManager> sites_;
  std::unique_ptr<JobManager> jobs_;
  std::unique_ptr<SiteServiceImpl> site_service_;
  std::unique_ptr<JobServiceImpl> job_service_;
  std::unique_ptr<grpc::Server> server_;
  int port_ = 0;
  bool stopped_ = false;
};

}  // namespace fenestra
