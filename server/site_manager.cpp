#include "server/site_manager.h"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <chrono>
#include <filesystem>

#include "absl/strings/str_cat.h"
#include "core/common/atomic_file.h"
#include "core/geometry/scene.h"
#include "core/optimize/job.h"
#include "server/checksum.h"
#include "server/limits.h"

namespace fenestra {

absl::StatusOr<std::string> SaveUploadedWeather(const std::string& dir, const std::string& bytes) {
  std::error_code error;
  std::filesystem::create_directories(dir, error);
  const std::string path = (std::filesystem::path(dir) / (Sha256Hex(bytes) + ".epw")).string();
  if (std::filesystem::exists(path, error)) return path;
  absl::Status written = WriteFileAtomically(
      path,
      [&](std::ostream& out) {
        out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
        return absl::OkStatus();
      },
      /*binary=*/true);
  if (!written.ok()) return written;
  return path;
}

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

}  // namespace

SiteManager::SiteManager(const v1::DaemonConfig& config, JobStore& store, OutdoorCache& cache,
                         WorkQueue& queue)
    : config_(config), store_(store), cache_(cache), queue_(queue) {}

absl::Status SiteManager::Recover() {
  absl::StatusOr<std::vector<JobStore::StoredSite>> stored = store_.LoadSites();
  if (!stored.ok()) return stored.status();
  std::vector<std::string> to_compute;
  {
    std::lock_guard lock(mutex_);
    for (JobStore::StoredSite& s : *stored) {
      v1::SiteInfo& info = s.info;
      const std::string id = info.id();
      if (info.state() == v1::SITE_STATE_READY) {
        if (cache_.Find(info.outdoor_key())) {
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
    {
      std::lock_guard lock(mutex_);
      if (absl::Status s = store_.UpdateSite(sites_[id].info); !s.ok()) return s;
    }
    if (absl::Status s = QueueCompute(id); !s.ok()) return s;
  }
  return absl::OkStatus();
}

absl::StatusOr<v1::SiteInfo> SiteManager::Register(const v1::RegisterSiteRequest& request) {
  if (shutting_down_) {
    return absl::UnavailableError("fenestrad is shutting down; register the site when it is back");
  }
  const v1::Limits& limits = config_.limits();
  {
    std::lock_guard lock(mutex_);
    if (static_cast<int>(sites_.size()) >= limits.max_sites()) {
      return absl::ResourceExhaustedError(
          absl::StrCat("this server holds ", sites_.size(),
                       " sites, its limit max_sites; delete one first (fenestra site rm)"));
    }
  }
  if (!request.has_scene()) return absl::InvalidArgumentError("scene: is required");
  if (absl::Status s = CheckInlineScene(request.scene()); !s.ok()) return s;
  if (absl::Status s = CheckSceneLimits(request.scene(), limits); !s.ok()) return s;

  v1::Sampling sampling = request.sampling();
  if (sampling.backend().empty()) sampling.set_backend(config_.backend());
  absl::StatusOr<v1::Sampling> resolved = ResolveSampling(sampling);
  if (!resolved.ok()) return resolved.status();
  if (absl::Status s = CheckSamplingLimits(*resolved, limits, /*indoor=*/false); !s.ok()) {
    return s;
  }
  v1::Scene scene_proto = request.scene();
  scene_proto.mutable_site()->clear_weather_file();
  absl::StatusOr<Scene> scene = BuildScene(scene_proto, "scene");
  if (!scene.ok()) return scene.status();

  std::string weather_path;
  if (!request.weather_epw().empty()) {
    absl::StatusOr<std::string> saved = SaveUploadedWeather(
        (std::filesystem::path(config_.data_dir()) / "weather").string(), request.weather_epw());
    if (!saved.ok()) return saved.status();
    weather_path = *saved;
  }

  v1::SiteInfo info;
  info.set_name(request.name().empty() ? scene->name : request.name());
  info.set_outdoor_key(OutdoorMatrixKey(*scene, *resolved));
  *info.mutable_sampling() = *resolved;
  info.set_latitude_deg(scene->site.latitude_deg);
  info.set_longitude_deg(scene->site.longitude_deg);
  info.set_weather_name(request.weather_name());
  info.set_has_weather(!weather_path.empty());
  info.set_outdoor_triangles(OutdoorTriangles(*scene));
  info.set_created_unix_ms(NowUnixMs());
  *info.mutable_scene() = request.scene();
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
  {
    std::lock_guard lock(mutex_);
    absl::StatusOr<std::string> id = store_.InsertSite(info, weather_path);
    if (!id.ok()) return id.status();
    order_.push_back(*id);
    sites_[*id] = Site{info, weather_path};
  }
  spdlog::info("site {} registered ({}): {} outdoor triangles, {} outdoor paths, key {}; {}",
               info.id(), info.name(), info.outdoor_triangles(), resolved->outdoor_paths(),
               info.outdoor_key().substr(0, 16),
               cached ? "outdoor matrix already cached" : "outdoor matrix queued");
  if (!cached) {
    if (absl::Status s = QueueCompute(info.id()); !s.ok()) return s;
  }
  info.clear_scene();
  return info;
}

absl::Status SiteManager::QueueCompute(const std::string& id) {
  return queue_.Push(
      id, [this, id] { Compute(id); }, /*is_job=*/false);
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
    v1::Scene scene_proto = info.scene();
    scene_proto.mutable_site()->clear_weather_file();
    absl::StatusOr<Scene> scene = BuildScene(scene_proto, "scene");
    if (!scene.ok()) {
      lookup = scene.status();
    } else {
      spdlog::info("site {}: computing its outdoor matrix ({} paths)", id,
                   info.sampling().outdoor_paths());
      lookup = cache_.GetOrCompute(
          info.outdoor_key(),
          [&]() -> absl::StatusOr<OutdoorMatrix> {
            absl::StatusOr<OutdoorMatrix> m =
                ComputeOutdoorMatrix(*scene, info.sampling(), cancelled);
            if (m.ok()) m->key = info.outdoor_key();
            return m;
          },
          cancelled);
    }
  } catch (const std::exception& e) {
    lookup = absl::InternalError(absl::StrCat("internal error: ", e.what()));
  }

  std::lock_guard lock(mutex_);
  auto it = sites_.find(id);
  if (it == sites_.end() || deleted->load()) return;
  v1::SiteInfo& site = it->second.info;
  if (lookup.ok()) {
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
    spdlog::info(
        "site {} ready: outdoor matrix {} in {:.2f} s on {}, mean relative standard "
        "error {:.4f}",
        id, lookup->computed ? "computed" : "found in the cache", m.wall_seconds, m.backend,
        site.mean_relative_standard_error());
  } else if (interrupted_) {
    spdlog::info("site {}: outdoor matrix interrupted by the shutdown; computed at next start", id);
    return;
  } else {
    site.set_state(v1::SITE_STATE_FAILED);
    site.set_error(std::string(lookup.status().message()));
    spdlog::warn("site {} failed: {}", id, site.error());
  }
  if (absl::Status s = store_.UpdateSite(site); !s.ok()) {
    spdlog::error("site {}: cannot store its state: {}", id, s.ToString());
  }
}

absl::StatusOr<v1::SiteInfo> SiteManager::Get(const std::string& id, bool with_scene) const {
  std::lock_guard lock(mutex_);
  auto it = sites_.find(id);
  if (it == sites_.end()) {
    return absl::NotFoundError(absl::StrCat("no site '", id, "' (fenestra site list shows them)"));
  }
  v1::SiteInfo info = it->second.info;
  if (!with_scene) info.clear_scene();
  return info;
}

std::vector<v1::SiteInfo> SiteManager::List() const {
  std::lock_guard lock(mutex_);
  std::vector<v1::SiteInfo> sites;
  for (const std::string& id : order_) {
    sites.push_back(sites_.at(id).info);
    sites.back().clear_scene();
  }
  return sites;
}

absl::Status SiteManager::Delete(const std::string& id) {
  std::lock_guard lock(mutex_);
  auto it = sites_.find(id);
  if (it == sites_.end()) {
    return absl::NotFoundError(absl::StrCat("no site '", id, "' (fenestra site list shows them)"));
  }
  if (absl::Status s = store_.DeleteSite(id); !s.ok()) return s;
  it->second.deleted->store(true);
  queue_.Remove(id);
  sites_.erase(it);
  order_.erase(std::find(order_.begin(), order_.end(), id));
  spdlog::info("site {} deleted", id);
  return absl::OkStatus();
}

absl::StatusOr<SiteManager::ForJob> SiteManager::Lookup(const std::string& id) const {
  std::lock_guard lock(mutex_);
  auto it = sites_.find(id);
  if (it == sites_.end()) {
    return absl::NotFoundError(absl::StrCat("no site '", id, "' (fenestra site list shows them)"));
  }
  ForJob site{it->second.info, it->second.weather_path};
  site.info.clear_scene();
  return site;
}

void SiteManager::NoteReuse(const std::string& id) {
  std::lock_guard lock(mutex_);
  auto it = sites_.find(id);
  if (it == sites_.end()) return;
  it->second.info.set_jobs_reused(it->second.info.jobs_reused() + 1);
  if (absl::Status s = store_.UpdateSite(it->second.info); !s.ok()) {
    spdlog::error("site {}: cannot store its state: {}", id, s.ToString());
  }
}

}  // namespace fenestra
