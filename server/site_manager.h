#pragma once

#include <atomic>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <string_view>
#include <vector>

#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "fenestra/v1/daemon.pb.h"
#include "fenestra/v1/service.pb.h"
#include "server/data_dir.h"
#include "server/heavy_requests.h"
#include "server/job_store.h"
#include "server/outdoor_cache.h"
#include "server/upload_quota.h"
#include "server/users.h"
#include "server/work_queue.h"

namespace fenestra {

// Milliseconds since the Unix epoch.
int64_t NowUnixMs();

// Mean of standard_error / coefficient over the entries at least 1% of the largest [-].
double MeanRelativeStandardError(const OutdoorMatrix& matrix);

// The registered sites: their outdoor matrices are computed by tasks on the work queue
// and kept in the outdoor cache; the sites live in the job store, and in memory without
// their scenes (read from the store when a computation or a Get needs one). Each site
// belongs to the user who registered it: to everyone else (administrators aside) it does
// not exist, and its id answers NotFound exactly as an unknown id. Matrices stay shared by
// content key, weather files by content (UploadStore).
class SiteManager {
 public:
  SiteManager(const v1::DaemonConfig& config, const DataDir& data_dir, JobStore& store,
              OutdoorCache& cache, UploadStore& weather, WorkQueue& queue, HeavyRequests& heavy,
              UploadQuota& uploads);

  // Loads the stored sites (those that do not parse are quarantined and logged) and counts
  // their weather files' references. Those computing, or ready but missing from the cache
  // (a file found corrupt), are queued for computation again.
  absl::Status Recover();

  // Registers a site of `caller` (see SiteService.Register).
  absl::StatusOr<v1::SiteInfo> Register(const v1::RegisterSiteRequest& request,
                                        const Caller& caller);
  // A site by id; NotFound when unknown or not the caller's. `with_scene` includes the
  // registered scene, read from the store (a scene of 1 MiB or more counts as a heavy
  // request).
  absl::StatusOr<v1::SiteInfo> Get(const std::string& id, const Caller& caller,
                                   bool with_scene = true) const;
  // The caller's sites (an administrator's: all), oldest first, without scenes.
  std::vector<v1::SiteInfo> List(const Caller& caller) const;
  // Forgets a site, drops its weather file's reference and gives its upload bytes back to
  // its owner; a running computation of it stops at its next checkpoint. Its cached matrix
  // stays until the data directory needs the room. NotFound when unknown or not the
  // caller's.
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
  // Whether a site uses the outdoor matrix with `key`.
  bool UsesKey(const std::string& key) const;

  // Registrations are refused from now on (Unavailable).
  void BeginShutdown() { shutting_down_ = true; }
  // Running computations stop at their next checkpoint; their sites stay computing and
  // are computed again at the next start.
  void Interrupt() { interrupted_ = true; }

 private:
  struct Site {
    v1::SiteInfo info;  // without the scene
    std::string weather_path;
    std::shared_ptr<std::atomic<bool>> deleted = std::make_shared<std::atomic<bool>>(false);
  };
  // Checks the bounds on sites, in all and of `owner`, registrations under way included
  // (mutex_ held).
  absl::Status CheckSiteCount(const std::string& owner) const;
  // Register's checks of the request (CheckSiteRequest) and the new site's info of
  // `caller` from its scene (built, then dropped).
  absl::StatusOr<v1::SiteInfo> Describe(const v1::RegisterSiteRequest& request,
                                        const Caller& caller) const;
  // Queues the computation of a site's matrix.
  absl::Status QueueCompute(const std::string& id, const std::string& owner);
  // A work queue task: computes (or finds) the matrix and marks the site ready or failed.
  void Compute(const std::string& id);
  // Traces (or finds) the matrix of a site from its stored scene.
  absl::StatusOr<OutdoorCache::Lookup> ComputeMatrix(const std::string& id,
                                                     const v1::SiteInfo& info,
                                                     const std::function<bool()>& cancelled);
  // Stores what `update` makes of a site's info, then shows it; while the storage is full,
  // tries again every second until the site is deleted or the daemon stops. True when
  // stored.
  bool StoreUntilDone(const std::string& id, const std::atomic<bool>& deleted,
                      const std::function<void(v1::SiteInfo&)>& update);

  const v1::DaemonConfig config_;
  const DataDir& data_dir_;
  JobStore& store_;
  OutdoorCache& cache_;
  UploadStore& weather_;
  WorkQueue& queue_;
  HeavyRequests& heavy_;
  UploadQuota& uploads_;
  std::atomic<bool> shutting_down_{false};
  std::atomic<bool> interrupted_{false};
  mutable std::mutex mutex_;
  std::vector<std::string> order_;  // ids, oldest first
  std::map<std::string, Site> sites_;
  std::map<std::string, int> registering_;  // registrations being stored, by owner
};

}  // namespace fenestra
