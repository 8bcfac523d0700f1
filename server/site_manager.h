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
#include "server/work_queue.h"

namespace fenestra {

// Stores an uploaded EPW file as <dir>/<sha256>.epw (once per content); returns its path.
absl::StatusOr<std::string> SaveUploadedWeather(const std::string& dir, const std::string& bytes);

// Milliseconds since the Unix epoch.
int64_t NowUnixMs();

// Mean of standard_error / coefficient over the entries at least 1% of the largest [-].
double MeanRelativeStandardError(const OutdoorMatrix& matrix);

// The registered sites: their outdoor matrices are computed by tasks on the work queue
// and kept in the outdoor cache; the sites themselves live in the job store.
class SiteManager {
 public:
  SiteManager(const v1::DaemonConfig& config, JobStore& store, OutdoorCache& cache,
              WorkQueue& queue);

  // Loads the stored sites. Those computing, or ready but missing from the cache (a file
  // found corrupt), are queued for computation again.
  absl::Status Recover();

  // Registers a site (see SiteService.Register).
  absl::StatusOr<v1::SiteInfo> Register(const v1::RegisterSiteRequest& request);
  // A site by id; NotFound when unknown. `with_scene` includes the registered scene.
  absl::StatusOr<v1::SiteInfo> Get(const std::string& id, bool with_scene = true) const;
  // Every site, oldest first, without scenes.
  std::vector<v1::SiteInfo> List() const;
  // Forgets a site; a running computation of it stops at its next checkpoint.
  absl::Status Delete(const std::string& id);

  // What a job on a site needs from it.
  struct ForJob {
    v1::SiteInfo info;         // without the scene
    std::string weather_path;  // empty when the site has no weather file
  };
  // NotFound when unknown.
  absl::StatusOr<ForJob> Lookup(const std::string& id) const;
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
  // Queues the computation of a site's matrix.
  absl::Status QueueCompute(const std::string& id);
  // A work queue task: computes (or finds) the matrix and marks the site ready or failed.
  void Compute(const std::string& id);

  const v1::DaemonConfig config_;
  JobStore& store_;
  OutdoorCache& cache_;
  WorkQueue& queue_;
  std::atomic<bool> shutting_down_{false};
  std::atomic<bool> interrupted_{false};
  mutable std::mutex mutex_;
  std::vector<std::string> order_;  // ids, oldest first
  std::map<std::string, Site> sites_;
};

}  // namespace fenestra
