#pragma once

#include <atomic>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "fenestra/v1/daemon.pb.h"
#include "fenestra/v1/service.pb.h"
#include "server/job_store.h"
#include "server/outdoor_cache.h"
#include "server/upload_quota.h"
#include "server/users.h"
#include "server/work_queue.h"

namespace fenestra {

// Stores an uploaded EPW file as <dir>/<sha256>.epw (once per content); returns its path.
absl::StatusOr<std::string> SaveUploadedWeather(const std::string& dir, const std::string& bytes);

// Milliseconds since the Unix epoch.
int64_t NowUnixMs();

// Mean of standard_error / coefficient over the entries at least 1% of the largest [-].
double MeanRelativeStandardError(const OutdoorMatrix& matrix);

// The registered sites: their outdoor matrices are computed by tasks on the work queue
// and kept in the outdoor cache; the sites themselves live in the job store. Each site
// belongs to the user who registered it: to everyone else (administrators aside) it does
// not exist, and its id answers NotFound exactly as an unknown id. Matrices stay shared by
// content key.
class SiteManager {
 public:
  SiteManager(const v1::DaemonConfig& config, JobStore& store, OutdoorCache& cache,
              WorkQueue& queue, UploadQuota& uploads);

  // Loads the stored sites. Those computing, or ready but missing from the cache (a file
  // found corrupt), are queued for computation again.
  absl::Status Recover();

  // Registers a site of `caller` (see SiteService.Register).
  absl::StatusOr<v1::SiteInfo> Register(const v1::RegisterSiteRequest& request,
                                        const Caller& caller);
  // A site by id; NotFound when unknown or not the caller's. `with_scene` includes the
  // registered scene.
  absl::StatusOr<v1::SiteInfo> Get(const std::string& id, const Caller& caller,
                                   bool with_scene = true) const;
  // The caller's sites (an administrator's: all), oldest first, without scenes.
  std::vector<v1::SiteInfo> List(const Caller& caller) const;
  // Forgets a site; a running computation of it stops at its next checkpoint. NotFound
  // when unknown or not the caller's.
  absl::Status Delete(const std::string& id, const Caller& caller);

  // What a job on a site needs from it.
  struct ForJob {
    v1::SiteInfo info;         // without the scene
    std::string weather_path;  // empty when the site has no weather file
  };
  // NotFound when unknown or not the caller's.
  absl::StatusOr<ForJob> Lookup(const std::string& id, const Caller& caller) const;
  // Counts a job that reused the site's matrix.
  void NoteReuse(const std::string& id);

  // Registrations are refused from now on (Unavailable).
  void BeginShutdown() { shutting_down_ = true; }
  // Running computations stop at their next checkpoint; their sites stay computing and
  // are computed again at the next start.
  void Interrupt() { interrupted_ = true; }

 private:
  struct Site {
    v1::SiteInfo info;  // scene included
    std::string weather_path;
    std::shared_ptr<std::atomic<bool>> deleted = std::make_shared<std::atomic<bool>>(false);
  };
  // Checks the bounds on sites, in all and of `owner` (mutex_ held).
  absl::Status CheckSiteCount(const std::string& owner) const;
  // Queues the computation of a site's matrix.
  absl::Status QueueCompute(const std::string& id, const std::string& owner);
  // A work queue task: computes (or finds) the matrix and marks the site ready or failed.
  void Compute(const std::string& id);

  const v1::DaemonConfig config_;
  JobStore& store_;
  OutdoorCache& cache_;
  WorkQueue& queue_;
  UploadQuota& uploads_;
  std::atomic<bool> shutting_down_{false};
  std::atomic<bool> interrupted_{false};
  mutable std::mutex mutex_;
  std::vector<std::string> order_;  // ids, oldest first
  std::map<std::string, Site> sites_;
};

}  // namespace fenestra
