#include "server/site_manager.h"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <chrono>
#include <thread>

#include "absl/cleanup/cleanup.h"
#include "absl/strings/str_cat.h"
#include "core/geometry/scene.h"
#include "core/optimize/job.h"
#include "server/limits.h"
#include "server/log_safe.h"

namespace fenestra {

int64_t NowUnixMs() {
  return std::chrono::duration_cast<std::chrono::milliseconds>(
             std::chrono::system_clock::now().time_since_epoch())
      .count();
}

double MeanRelativeStandardError(const OutdoorMatrix& matrix) {
  return MeanRelativeError(matrix.coefficients, matrix.standard_error, 0.01, false);
}

namespace {

int64_t OutdoorTriangles(const Scene& scene) {
  return std::count(scene.fixed.side.begin(), scene.fixed.side.end(), Side::kOutdoor);
}

// The answer for an unknown site, and for another user's.
absl::Status NoSite(const std::string& id) {
  return absl::NotFoundError(absl::StrCat("no site '", id, "' (fenestra site list shows them)"));
}

}  // namespace

SiteManager::SiteManager(const v1::DaemonConfig& config, const DataDir& data_dir, JobStore& store,
                         OutdoorCache& cache, UploadStore& weather, WorkQueue& queue,
                         HeavyRequests& heavy, UploadQuota& uploads)
    : config_(config),
      data_dir_(data_dir),
      store_(store),
      cache_(cache),
      weather_(weather),
      queue_(queue),
      heavy_(heavy),
      uploads_(uploads) {}

absl::Status SiteManager::Recover() {
  absl::StatusOr<JobStore::StoredSites> stored = store_.LoadSites();
  if (!stored.ok()) return stored.status();
  for (const JobStore::Quarantined& q : stored->quarantined) {
    spdlog::error(
        "site {}: its stored record does not parse ({}); moved to the quarantine "
        "table, the daemon goes on without it",
        LogSafe(q.id), q.reason);
  }
  std::vector<std::string> to_compute;
  {
    std::lock_guard lock(mutex_);
    for (JobStore::StoredSite& s : stored->sites) {
      v1::SiteInfo& info = s.info;
      const std::string id = info.id();
      if (!s.weather_path.empty()) weather_.Ref(s.weather_path);
      if (info.owner().empty()) info.set_owner(kLocalUser);  // stored before owners
      (void)uploads_.Reserve(info.owner(), info.upload_bytes(), /*force=*/true);
      if (info.state() == v1::SITE_STATE_READY) {
        if (cache_.Contains(info.outdoor_key())) {
          info.set_loaded_from_disk(cache_.LoadedFromDisk(info.outdoor_key()));
        } else {
          spdlog::warn(
              "site {}: its outdoor matrix is not in the cache (missing or corrupt "
              "file); computing it again",
              id);
          info.set_state(v1::SITE_STATE_COMPUTING);
          info.set_ready_unix_ms(0);
          info.set_loaded_from_disk(false);
          to_compute.push_back(id);
        }
      } else if (info.state() == v1::SITE_STATE_COMPUTING) {
        spdlog::info("site {}: computing its outdoor matrix again (the daemon stopped first)", id);
        to_compute.push_back(id);
      }
      order_.push_back(id);
      sites_[id] = Site{std::move(info), std::move(s.weather_path)};
    }
  }
  for (const std::string& id : to_compute) {
    std::string owner;
    {
      // The store says ready until this is stored; every start decides the same again
      std::lock_guard lock(mutex_);
      if (absl::Status s = store_.UpdateSite(sites_[id].info); !s.ok()) {
        spdlog::warn("site {}: cannot store its state: {}", id, std::string(s.message()));
      }
      owner = sites_[id].info.owner();
    }
    if (absl::Status s = QueueCompute(id, owner); !s.ok()) return s;
  }
  return absl::OkStatus();
}

absl::Status SiteManager::CheckSiteCount(const std::string& owner) const {
  const v1::Limits& limits = config_.limits();
  int64_t registering = 0;
  for (const auto& [user, count] : registering_) registering += count;
  const int64_t total = static_cast<int64_t>(sites_.size()) + registering;
  if (total >= limits.max_sites()) {
    return absl::ResourceExhaustedError(
        absl::StrCat("this server holds ", total,
                     " sites, its limit max_sites; delete one first (fenestra site rm)"));
  }
  auto pending = registering_.find(owner);
  const int64_t owned =
      std::count_if(sites_.begin(), sites_.end(),
                    [&](const auto& site) { return site.second.info.owner() == owner; }) +
      (pending == registering_.end() ? 0 : pending->second);
  if (owned >= limits.max_sites_per_user()) {
    return absl::ResourceExhaustedError(
        absl::StrCat("limits.max_sites_per_user (", limits.max_sites_per_user(),
                     ") reached: you have ", owned, " sites; delete one first (fenestra site rm)"));
  }
  return absl::OkStatus();
}

absl::StatusOr<v1::SiteInfo> SiteManager::Register(const v1::RegisterSiteRequest& request,
                                                   const Caller& caller) {
  if (shutting_down_) {
    return absl::UnavailableError("fenestrad is shutting down; register the site when it is back");
  }
  absl::StatusOr<HeavyRequests::Pass> pass = heavy_.Enter(request.ByteSizeLong());
  if (!pass.ok()) return pass.status();
  {
    std::lock_guard lock(mutex_);
    if (absl::Status s = CheckSiteCount(caller.name); !s.ok()) return s;
  }
  absl::StatusOr<v1::SiteInfo> described = Describe(request, caller);
  if (!described.ok()) return described.status();
  v1::SiteInfo& info = *described;

  // A place among the sites, counted again (other registrations may have come in
  // meanwhile) and held while the site is stored
  {
    std::lock_guard lock(mutex_);
    if (absl::Status s = CheckSiteCount(caller.name); !s.ok()) return s;
    ++registering_[caller.name];
  }
  absl::Cleanup registered = [&] {
    std::lock_guard lock(mutex_);
    if (--registering_[caller.name] == 0) registering_.erase(caller.name);
  };

  // The owner's upload quota, room for the scene, then the weather file
  const int64_t upload_bytes = info.upload_bytes();
  if (absl::Status s = uploads_.Reserve(caller.name, upload_bytes); !s.ok()) return s;
  absl::Cleanup release_quota = [&] { uploads_.Release(caller.name, upload_bytes); };
  if (absl::Status s = data_dir_.MakeRoom(static_cast<int64_t>(request.scene().ByteSizeLong()));
      !s.ok()) {
    return s;
  }
  std::string weather_path;
  if (!request.weather_epw().empty()) {
    absl::StatusOr<std::string> saved = weather_.Add(request.weather_epw());
    if (!saved.ok()) return saved.status();
    weather_path = *saved;
  }
  info.set_has_weather(!weather_path.empty());
  const std::shared_ptr<const OutdoorMatrix> cached = cache_.Find(info.outdoor_key());
  if (cached) {
    info.set_state(v1::SITE_STATE_READY);
    info.set_ready_unix_ms(info.created_unix_ms());
    info.set_loaded_from_disk(cache_.LoadedFromDisk(info.outdoor_key()));
    info.set_mean_relative_standard_error(MeanRelativeStandardError(*cached));
    info.set_backend(cached->backend);
  } else {
    info.set_state(v1::SITE_STATE_COMPUTING);
  }
  // Stored outside the lock: a large scene takes a while, and List goes on meanwhile
  absl::StatusOr<std::string> id = store_.InsertSite(info, weather_path, request.scene());
  if (!id.ok()) {
    if (!weather_path.empty()) weather_.Unref(weather_path);
    return id.status();
  }
  std::move(release_quota).Cancel();  // held by the site until it is deleted
  {
    std::lock_guard lock(mutex_);
    order_.push_back(*id);
    sites_[*id] = Site{info, weather_path};
  }
  spdlog::info(
      "site {} registered by {} (\"{}\"): {} outdoor triangles, {} outdoor paths, key {}; {}",
      info.id(), caller.name, LogSafe(info.name()), info.outdoor_triangles(),
      info.sampling().outdoor_paths(), info.outdoor_key().substr(0, 16),
      cached ? "outdoor matrix already cached" : "outdoor matrix queued");
  if (!cached) {
    if (absl::Status s = QueueCompute(info.id(), caller.name); !s.ok()) return s;
  }
  return ForCaller(std::move(info), caller);
}

absl::StatusOr<v1::SiteInfo> SiteManager::Describe(const v1::RegisterSiteRequest& request,
                                                   const Caller& caller) const {
  // Everything checked before anything is stored
  absl::StatusOr<CheckedSite> checked = CheckSiteRequest(request, config_);
  if (!checked.ok()) return checked.status();
  const Scene& scene = checked->scene;
  v1::SiteInfo info;
  info.set_owner(caller.name);
  info.set_upload_bytes(static_cast<int64_t>(request.weather_epw().size()));
  info.set_name(request.name().empty() ? scene.name : request.name());
  info.set_outdoor_key(OutdoorMatrixKey(scene, checked->sampling));
  info.set_latitude_deg(scene.site.latitude_deg);
  info.set_longitude_deg(scene.site.longitude_deg);
  info.set_outdoor_triangles(OutdoorTriangles(scene));
  *info.mutable_sampling() = checked->sampling;
  info.set_weather_name(request.weather_name());
  info.set_created_unix_ms(NowUnixMs());
  return info;
}

absl::Status SiteManager::QueueCompute(const std::string& id, const std::string& owner) {
  return queue_.Push(
      id, owner, [this, id] { Compute(id); }, /*is_job=*/false);
}

absl::StatusOr<OutdoorCache::Lookup> SiteManager::ComputeMatrix(
    const std::string& id, const v1::SiteInfo& info, const std::function<bool()>& cancelled) {
  absl::StatusOr<Scene> scene = absl::InternalError("not built");
  {
    absl::StatusOr<v1::Scene> stored = store_.LoadSiteScene(id);
    if (!stored.ok()) return stored.status();
    scene = BuildScene(*stored, "scene");
  }
  if (!scene.ok()) return scene.status();
  spdlog::info("site {}: computing its outdoor matrix ({} paths)", id,
               info.sampling().outdoor_paths());
  return cache_.GetOrCompute(
      info.outdoor_key(),
      [&]() -> absl::StatusOr<OutdoorMatrix> {
        absl::StatusOr<OutdoorMatrix> m = ComputeOutdoorMatrix(*scene, info.sampling(), cancelled);
        if (m.ok()) m->key = info.outdoor_key();
        return m;
      },
      cancelled);
}

void SiteManager::Compute(const std::string& id) {
  v1::SiteInfo info;
  std::shared_ptr<std::atomic<bool>> deleted;
  {
    std::lock_guard lock(mutex_);
    auto it = sites_.find(id);
    if (it == sites_.end()) return;
    info = it->second.info;
    deleted = it->second.deleted;
  }
  const auto cancelled = [&] { return deleted->load() || interrupted_.load(); };
  absl::StatusOr<OutdoorCache::Lookup> lookup = absl::InternalError("not computed");
  try {
    lookup = ComputeMatrix(id, info, cancelled);
  } catch (const std::exception& e) {
    lookup = absl::InternalError(absl::StrCat("internal error: ", e.what()));
  }
  ReleaseFreeMemory();  // the scene, its BVH and the tracer's buffers
  if (deleted->load()) return;
  if (!lookup.ok() && interrupted_) {
    spdlog::info("site {}: outdoor matrix interrupted by the shutdown; computed at next start", id);
    return;
  }
  const bool stored = StoreUntilDone(id, *deleted, [&](v1::SiteInfo& site) {
    if (!lookup.ok()) {
      site.set_state(v1::SITE_STATE_FAILED);
      site.set_error(std::string(lookup.status().message()));
      return;
    }
    const OutdoorMatrix& m = *lookup->matrix;
    site.set_state(v1::SITE_STATE_READY);
    site.set_ready_unix_ms(NowUnixMs());
    if (lookup->computed) {
      site.set_compute_seconds(m.wall_seconds);
      site.set_computations(site.computations() + 1);
      site.set_loaded_from_disk(false);
    } else {
      site.set_loaded_from_disk(cache_.LoadedFromDisk(site.outdoor_key()));
    }
    site.set_mean_relative_standard_error(MeanRelativeStandardError(m));
    site.set_backend(m.backend);
    site.clear_error();
  });
  if (!stored) return;
  if (lookup.ok()) {
    const OutdoorMatrix& m = *lookup->matrix;
    spdlog::info(
        "site {} ready: outdoor matrix {} in {:.2f} s on {}, mean relative standard error {:.4f}",
        id, lookup->computed ? "computed" : "found in the cache", m.wall_seconds, m.backend,
        MeanRelativeStandardError(m));
  } else {
    spdlog::warn("site {} failed: {}", id, LogSafe(std::string(lookup.status().message())));
  }
}

bool SiteManager::StoreUntilDone(const std::string& id, const std::atomic<bool>& deleted,
                                 const std::function<void(v1::SiteInfo&)>& update) {
  for (int attempt = 0;; ++attempt) {
    {
      std::lock_guard lock(mutex_);
      auto it = sites_.find(id);
      if (it == sites_.end() || deleted) return false;
      v1::SiteInfo next = it->second.info;
      update(next);
      const absl::Status s = store_.UpdateSite(next);
      if (s.ok()) {
        it->second.info = std::move(next);
        return true;
      }
      if (attempt == 0) {
        spdlog::error("site {}: cannot store its state ({}); trying again every second", id,
                      std::string(s.message()));
      }
    }
    if (interrupted_) {
      spdlog::warn("site {}: its state is not stored; it is computed again at the next start", id);
      return false;
    }
    std::this_thread::sleep_for(std::chrono::seconds(1));
  }
}

absl::StatusOr<v1::SiteInfo> SiteManager::Get(const std::string& id, const Caller& caller,
                                              bool with_scene) const {
  v1::SiteInfo info;
  {
    std::lock_guard lock(mutex_);
    auto it = sites_.find(id);
    if (it == sites_.end() || !caller.Owns(it->second.info.owner())) return NoSite(id);
    info = ForCaller(it->second.info, caller);
  }
  if (with_scene) {
    // Read outside the lock, so a large scene does not hold up the other calls; large
    // scenes count as heavy requests
    absl::StatusOr<int64_t> bytes = store_.SiteSceneBytes(id);
    if (!bytes.ok()) return bytes.status();
    absl::StatusOr<HeavyRequests::Pass> pass = heavy_.Enter(static_cast<size_t>(*bytes));
    if (!pass.ok()) return pass.status();
    absl::StatusOr<v1::Scene> scene = store_.LoadSiteScene(id);
    if (!scene.ok()) return scene.status();
    *info.mutable_scene() = *std::move(scene);
  }
  return info;
}

std::vector<v1::SiteInfo> SiteManager::List(const Caller& caller) const {
  std::lock_guard lock(mutex_);
  std::vector<v1::SiteInfo> sites;
  for (const std::string& id : order_) {
    const v1::SiteInfo& info = sites_.at(id).info;
    if (caller.Owns(info.owner())) sites.push_back(ForCaller(info, caller));
  }
  return sites;
}

absl::Status SiteManager::Delete(const std::string& id, const Caller& caller) {
  std::string weather_path;
  {
    std::lock_guard lock(mutex_);
    auto it = sites_.find(id);
    if (it == sites_.end() || !caller.Owns(it->second.info.owner())) return NoSite(id);
    if (absl::Status s = store_.DeleteSite(id); !s.ok()) return s;
    it->second.deleted->store(true);
    queue_.Remove(id);
    uploads_.Release(it->second.info.owner(), it->second.info.upload_bytes());
    weather_path = it->second.weather_path;
    sites_.erase(it);
    order_.erase(std::find(order_.begin(), order_.end(), id));
  }
  if (!weather_path.empty()) weather_.Unref(weather_path);
  spdlog::info("site {} deleted by {}", id, caller.name);
  return absl::OkStatus();
}

absl::StatusOr<SiteManager::ForJob> SiteManager::Lookup(const std::string& id,
                                                        const Caller& caller) const {
  std::lock_guard lock(mutex_);
  auto it = sites_.find(id);
  if (it == sites_.end() || !caller.Owns(it->second.info.owner())) return NoSite(id);
  return ForJob{it->second.info, it->second.weather_path};
}

void SiteManager::NoteReuse(const std::string& id) {
  std::lock_guard lock(mutex_);
  auto it = sites_.find(id);
  if (it == sites_.end()) return;
  v1::SiteInfo next = it->second.info;
  next.set_jobs_reused(next.jobs_reused() + 1);
  if (absl::Status s = store_.UpdateSite(next); !s.ok()) {
    spdlog::warn("site {}: cannot store its reuse count: {}", id, std::string(s.message()));
    return;
  }
  it->second.info = std::move(next);
}

bool SiteManager::UsesKey(const std::string& key) const {
  std::lock_guard lock(mutex_);
  for (const auto& [id, site] : sites_) {
    if (site.info.outdoor_key() == key) return true;
  }
  return false;
}

}  // namespace fenestra
