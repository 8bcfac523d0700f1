#pragma once

#include <grpcpp/server.h>

#include <memory>

#include "absl/status/statusor.h"
#include "fenestra/v1/daemon.pb.h"
#include "server/data_dir.h"
#include "server/heavy_requests.h"
#include "server/job_manager.h"
#include "server/job_store.h"
#include "server/outdoor_cache.h"
#include "server/services.h"
#include "server/site_manager.h"
#include "server/upload_quota.h"
#include "server/users.h"
#include "server/work_queue.h"

namespace fenestra {

// fenestrad assembled: data directory, job store (with the users), outdoor cache, uploaded
// weather files, work queue, sites, jobs and the gRPC server (SiteService, JobService,
// health checking, and reflection with auth none), over TLS when configured.
class Daemon {
 public:
  // Opens the data directory (FailedPrecondition naming it when it is not writable),
  // recovers the stored sites and jobs, drops the uploaded files nothing refers to any
  // more, and starts serving on config.listen_address; `config` resolved (ResolveConfig).
  // On a full disk it starts too: it serves reads and refuses writes until space is freed.
  static absl::StatusOr<std::unique_ptr<Daemon>> Start(const v1::DaemonConfig& config);
  ~Daemon();

  // The port the server listens on (useful with port 0).
  int port() const { return port_; }

  // Reports NOT_SERVING to health checks, refuses new work, lets running jobs reach the
  // end or a checkpoint (see JobManager::Shutdown), then stops the gRPC server.
  void Shutdown();

 private:
  explicit Daemon(const v1::DaemonConfig& config);

  v1::DaemonConfig config_;
  std::unique_ptr<DataDir> data_dir_;
  std::unique_ptr<JobStore> store_;
  std::unique_ptr<OutdoorCache> cache_;
  std::unique_ptr<UploadStore> weather_;
  std::unique_ptr<HeavyRequests> heavy_;
  std::unique_ptr<WorkQueue> queue_;
  std::unique_ptr<UploadQuota> uploads_;
  std::unique_ptr<Authenticator> auth_;
  std::unique_ptr<SiteManager> sites_;
  std::unique_ptr<JobManager> jobs_;
  std::unique_ptr<SiteServiceImpl> site_service_;
  std::unique_ptr<JobServiceImpl> job_service_;
  std::unique_ptr<grpc::Server> server_;
  int port_ = 0;
  bool stopped_ = false;
};

}  // namespace fenestra
