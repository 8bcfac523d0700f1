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
  return OutdoorMeanRelativeError(matrix);
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

SiteManager::SiteManager(const v1::DaemonConfig& config, const DataDir* data_dir, Store& store,
                         OutdoorCache& cache, HeavyRequests& heavy, Scheduler& scheduler)
    : config_(config),
      data_dir_(data_dir),
      store_(store),
      cache_(cache),
      heavy_(heavy),
      scheduler_(scheduler) {}

absl::Status SiteManager::Recover() {
  absl::StatusOr<std::vector<v1::SiteInfo>> sites = store_.ListSites("");
  if (!sites.ok()) return sites.status();
  for (const v1::SiteInfo& site : *sites) {
    if (site.state() != v1::SITE_STATE_READY || cache_.Contains(site.outdoor_key())) continue;
    // Every start decides the same again until this is stored
    absl::StatusOr<v1::SiteInfo> queued =
        store_.UpdateSite(site.id(), nullptr, [](v1::SiteInfo& info) {
          if (info.state() != v1::SITE_STATE_READY) return;
          info.set_state(v1::SITE_STATE_COMPUTING);
          info.set_ready_unix_ms(0);
        });
    if (queued.ok()) {
      spdlog::warn(
          "site {}: its outdoor matrix is not in the cache (missing or corrupt file); "
          "computing it again",
          site.id());
    } else {
      spdlog::warn("site {}: cannot store its state: {}", site.id(),
                   std::string(queued.status().message()));
    }
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
  absl::StatusOr<v1::SiteInfo> described = Describe(request, caller);
  if (!described.ok()) return described.status();
  v1::SiteInfo& info = *described;
  if (data_dir_) {
    if (absl::Status s = data_dir_->MakeRoom(static_cast<int64_t>(request.scene().ByteSizeLong()));
        !s.ok()) {
      return s;
    }
  }
  const std::shared_ptr<const OutdoorMatrix> cached = cache_.Find(info.outdoor_key());
  if (cached) {
    info.set_state(v1::SITE_STATE_READY);
    info.set_ready_unix_ms(info.created_unix_ms());
    info.set_mean_relative_standard_error(MeanRelativeStandardError(*cached));
    info.set_backend(cached->backend);
  } else {
    info.set_state(v1::SITE_STATE_COMPUTING);
  }
  // Checked against the limits and stored in one transaction; a large scene takes a while
  absl::StatusOr<v1::SiteInfo> stored =
      store_.InsertSite(info, request.scene(), request.weather_epw(), config_.limits());
  if (!stored.ok()) return stored.status();
  spdlog::info(
      "site {} registered by {} (\"{}\"): {} outdoor triangles, {} outdoor paths, key {}; {}",
      stored->id(), caller.name, LogSafe(stored->name()), stored->outdoor_triangles(),
      stored->sampling().outdoor_paths(), stored->outdoor_key().substr(0, 16),
      cached ? "outdoor matrix already cached" : "outdoor matrix queued");
  return Shown(*std::move(stored), caller);
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

void SiteManager::Compute(std::shared_ptr<Scheduler::Held> held) {
  const std::string id = held->claim.lease.id;
  absl::StatusOr<Store::StoredSite> site = store_.GetSite(id);
  if (!site.ok()) return;  // deleted meanwhile
  if (site->info.state() != v1::SITE_STATE_COMPUTING) {
    // Computed by an earlier claim whose end raced this one: the claim ends
    (void)store_.UpdateSite(id, &held->claim.lease, [](v1::SiteInfo&) {});
    return;
  }
  const auto cancelled = [&] { return held->lost.load() || interrupted_.load(); };
  absl::StatusOr<OutdoorCache::Lookup> lookup = absl::InternalError("not computed");
  try {
    lookup = ComputeMatrix(id, site->info, cancelled);
  } catch (const std::exception& e) {
    lookup = absl::InternalError(absl::StrCat("internal error: ", e.what()));
  }
  ReleaseFreeMemory();  // the scene, its BVH and the tracer's buffers
  if (held->lost) return;
  if (!lookup.ok() && interrupted_) {
    spdlog::info("site {}: outdoor matrix interrupted by the shutdown; computed at next start{}",
                 id, store_.shared() ? " or by another replica" : "");
    if (store_.shared()) (void)store_.Release(Claim::Kind::kSite, held->claim.lease);
    return;
  }
  const bool stored = StoreUntilDone(*held, [&](v1::SiteInfo& info) {
    if (!lookup.ok()) {
      info.set_state(v1::SITE_STATE_FAILED);
      info.set_error(std::string(lookup.status().message()));
      return;
    }
    const OutdoorMatrix& m = *lookup->matrix;
    info.set_state(v1::SITE_STATE_READY);
    info.set_ready_unix_ms(NowUnixMs());
    if (lookup->computed) {
      info.set_compute_seconds(m.wall_seconds);
      info.set_computations(info.computations() + 1);
    }
    info.set_mean_relative_standard_error(MeanRelativeStandardError(m));
    info.set_backend(m.backend);
    info.clear_error();
  });
  held->done = true;
  ReleaseFreeMemory();  // and what was freed since (the registration request, read meanwhile)
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

bool SiteManager::StoreUntilDone(const Scheduler::Held& held,
                                 const std::function<void(v1::SiteInfo&)>& update) {
  const std::string& id = held.claim.lease.id;
  for (int attempt = 0;; ++attempt) {
    const absl::StatusOr<v1::SiteInfo> stored = store_.UpdateSite(id, &held.claim.lease, update);
    if (stored.ok()) return true;
    const absl::StatusCode code = stored.status().code();
    if (code == absl::StatusCode::kNotFound || code == absl::StatusCode::kAborted) return false;
    if (attempt == 0) {
      spdlog::error("site {}: cannot store its state ({}); trying again every second", id,
                    std::string(stored.status().message()));
    }
    if (interrupted_ || held.lost) {
      spdlog::warn("site {}: its state is not stored; it is computed again at the next start", id);
      return false;
    }
    std::this_thread::sleep_for(std::chrono::seconds(1));
  }
}

absl::StatusOr<Store::StoredSite> SiteManager::Find(const std::string& id, const Caller& caller) {
  absl::StatusOr<Store::StoredSite> site = store_.GetSite(id);
  if (!site.ok()) {
    return site.status().code() == absl::StatusCode::kNotFound ? NoSite(id) : site.status();
  }
  if (!caller.Owns(site->info.owner())) return NoSite(id);
  return site;
}

v1::SiteInfo SiteManager::Shown(v1::SiteInfo info, const Caller& caller) const {
  if (info.state() == v1::SITE_STATE_READY) {
    info.set_loaded_from_disk(cache_.LoadedFromDisk(info.outdoor_key()));
  }
  return ForCaller(std::move(info), caller);
}

absl::StatusOr<v1::SiteInfo> SiteManager::Get(const std::string& id, const Caller& caller,
                                              bool with_scene) {
  absl::StatusOr<Store::StoredSite> site = Find(id, caller);
  if (!site.ok()) return site.status();
  v1::SiteInfo info = Shown(std::move(site->info), caller);
  if (with_scene) {
    // Large scenes count as heavy requests
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

absl::StatusOr<std::vector<v1::SiteInfo>> SiteManager::List(const Caller& caller) {
  absl::StatusOr<std::vector<v1::SiteInfo>> sites =
      store_.ListSites(caller.admin ? "" : caller.name);
  if (!sites.ok()) return sites.status();
  for (v1::SiteInfo& info : *sites) info = Shown(std::move(info), caller);
  return sites;
}

absl::Status SiteManager::Delete(const std::string& id, const Caller& caller) {
  absl::StatusOr<Store::StoredSite> found = Find(id, caller);
  if (!found.ok()) return found.status();
  absl::StatusOr<Store::StoredSite> deleted = store_.DeleteSite(id);
  if (!deleted.ok()) return deleted.status();
  // Computed here: it stops at its next checkpoint (another replica's finds its lease gone)
  if (std::shared_ptr<Scheduler::Held> local = scheduler_.Find(id)) local->lost = true;
  store_.ReleaseWeather(deleted->weather);
  spdlog::info("site {} deleted by {}", id, caller.name);
  return absl::OkStatus();
}

absl::StatusOr<SiteManager::ForJob> SiteManager::Lookup(const std::string& id,
                                                        const Caller& caller) {
  absl::StatusOr<Store::StoredSite> site = Find(id, caller);
  if (!site.ok()) return site.status();
  return ForJob{std::move(site->info), std::move(site->weather)};
}

void SiteManager::NoteReuse(const std::string& id) {
  const absl::StatusOr<v1::SiteInfo> stored = store_.UpdateSite(
      id, nullptr, [](v1::SiteInfo& info) { info.set_jobs_reused(info.jobs_reused() + 1); });
  if (!stored.ok() && stored.status().code() != absl::StatusCode::kNotFound) {
    spdlog::warn("site {}: cannot store its reuse count: {}", id,
                 std::string(stored.status().message()));
  }
}

}  // namespace fenestra
