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
#include "server/outdoor_cache.h"
#include "server/scheduler.h"
#include "server/store/store.h"
#include "server/users.h"

namespace fenestra {

// Milliseconds since the Unix epoch.
int64_t NowUnixMs();

// Mean of standard_error / coefficient over the entries at least 1% of the largest [-].
double MeanRelativeStandardError(const OutdoorMatrix& matrix);

// The registered sites: their outdoor matrices are computed by a replica's workers (a
// site computation is claimed from the store as a job is) and kept in the outdoor cache;
// the sites live in the store, scenes included, and every replica answers for every site.
// Each site belongs to the user who registered it: to everyone else (administrators
// aside) it does not exist, and its id answers NotFound exactly as an unknown id. Matrices
// stay shared by content key, weather files by content.
class SiteManager {
 public:
  // `data_dir`: the SQLite store's folder, asked for room before a site is stored; null
  // with a PostgreSQL store.
  SiteManager(const v1::DaemonConfig& config, const DataDir* data_dir, Store& store,
              OutdoorCache& cache, HeavyRequests& heavy, Scheduler& scheduler);

  // Sites ready but whose matrix is missing from the cache (a file found corrupt) are
  // queued for computation again.
  absl::Status Recover();

  // Registers a site of `caller` (see SiteService.Register).
  absl::StatusOr<v1::SiteInfo> Register(const v1::RegisterSiteRequest& request,
                                        const Caller& caller);
  // A site by id; NotFound when unknown or not the caller's. `with_scene` includes the
  // registered scene, read from the store (a scene of 1 MiB or more counts as a heavy
  // request).
  absl::StatusOr<v1::SiteInfo> Get(const std::string& id, const Caller& caller,
                                   bool with_scene = true);
  // The caller's sites (an administrator's: all), oldest first, without scenes.
  absl::StatusOr<std::vector<v1::SiteInfo>> List(const Caller& caller);
  // Forgets a site and drops its weather file's reference (which gives its upload bytes
  // back to its owner); a running computation of it stops at its next checkpoint. Its
  // cached matrix stays until the data directory needs the room. NotFound when unknown or
  // not the caller's.
  absl::Status Delete(const std::string& id, const Caller& caller);

  // What a job on a site needs from it.
  struct ForJob {
    v1::SiteInfo info;    // without the scene
    std::string weather;  // its weather file, empty when it has none
  };
  // NotFound when unknown or not the caller's.
  absl::StatusOr<ForJob> Lookup(const std::string& id, const Caller& caller);
  // Counts a job that reused the site's matrix.
  void NoteReuse(const std::string& id);

  // Computes a claimed site's matrix (or finds it cached) and marks the site ready or
  // failed (a Scheduler worker's task).
  void Compute(std::shared_ptr<Scheduler::Held> held);

  // Registrations are refused from now on (Unavailable).
  void BeginShutdown() { shutting_down_ = true; }
  // Running computations stop at their next checkpoint; their sites stay computing and
  // are computed again at the next start (with a shared store, by another replica).
  void Interrupt() { interrupted_ = true; }

 private:
  // Register's checks of the request (CheckSiteRequest) and the new site's info of
  // `caller` from its scene (built, then dropped).
  absl::StatusOr<v1::SiteInfo> Describe(const v1::RegisterSiteRequest& request,
                                        const Caller& caller) const;
  // The stored site `id` if `caller` may see it; NotFound otherwise.
  absl::StatusOr<Store::StoredSite> Find(const std::string& id, const Caller& caller);
  // `info` as `caller` sees it: whether this process read its matrix from the cache.
  v1::SiteInfo Shown(v1::SiteInfo info, const Caller& caller) const;
  // Traces (or finds) the matrix of a site from its stored scene.
  absl::StatusOr<OutdoorCache::Lookup> ComputeMatrix(const std::string& id,
                                                     const v1::SiteInfo& info,
                                                     const std::function<bool()>& cancelled);
  // Stores what `update` makes of a computed site's info under its claim; while the store
  // fails, tries again every second until the site is deleted, the claim lost or the
  // daemon stops. True when stored.
  bool StoreUntilDone(const Scheduler::Held& held,
                      const std::function<void(v1::SiteInfo&)>& update);

  const v1::DaemonConfig config_;
  const DataDir* const data_dir_;
  Store& store_;
  OutdoorCache& cache_;
  HeavyRequests& heavy_;
  Scheduler& scheduler_;
  std::atomic<bool> shutting_down_{false};
  std::atomic<bool> interrupted_{false};
};

}  // namespace fenestra
