#include "server/job_manager.h"

#include <spdlog/spdlog.h>

#include <chrono>
#include <cmath>
#include <filesystem>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_join.h"
#include "core/optimize/job.h"
#include "server/limits.h"
#include "server/log_safe.h"

namespace fenestra {
namespace {

// Events kept in memory per job for watchers that fall behind; older ones are in the store.
constexpr size_t kKeptEvents = 4096;

v1::JobProgress ToProto(const JobProgress& p) {
  v1::JobProgress out;
  out.set_evaluations(p.evaluations);
  out.set_max_evaluations(p.max_evaluations);
  *out.mutable_current() = p.current;
  *out.mutable_best() = p.best;
  out.set_elapsed_seconds(p.elapsed_seconds);
  out.set_remaining_seconds(p.remaining_seconds);
  if (p.final_check) *out.mutable_final_check() = *p.final_check;
  return out;
}

std::string DesignText(const google::protobuf::Map<std::string, double>& design) {
  std::map<std::string, double> sorted(design.begin(), design.end());
  return absl::StrJoin(sorted, " ", [](std::string* out, const auto& kv) {
    absl::StrAppend(out, kv.first, "=", absl::SixDigits(kv.second));
  });
}

double SecondsSince(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

// The answer for an unknown job, and for another user's.
absl::Status NoJob(const std::string& id) {
  return absl::NotFoundError(absl::StrCat("no job '", id, "' (fenestra job list shows them)"));
}

}  // namespace

bool IsTerminal(v1::JobState state) {
  return state == v1::JOB_STATE_SUCCEEDED || state == v1::JOB_STATE_FAILED ||
         state == v1::JOB_STATE_CANCELLED || state == v1::JOB_STATE_INTERRUPTED;
}

JobManager::JobManager(const v1::DaemonConfig& config, JobStore& store, OutdoorCache& cache,
                       WorkQueue& queue, SiteManager& sites, UploadQuota& uploads)
    : config_(config),
      store_(store),
      cache_(cache),
      queue_(queue),
      sites_(sites),
      uploads_(uploads) {}

absl::Status JobManager::Recover() {
  absl::StatusOr<std::vector<JobStore::StoredJob>> stored = store_.LoadJobs();
  if (!stored.ok()) return stored.status();
  std::vector<std::shared_ptr<Record>> queued;
  for (JobStore::StoredJob& s : *stored) {
    auto record = std::make_shared<Record>();
    record->info = std::move(s.info);
    record->job = std::move(s.job);
    const std::string id = record->info.id();
    if (record->info.owner().empty()) record->info.set_owner(kLocalUser);  // stored before owners
    record->owner = record->info.owner();
    if (!IsTerminal(record->info.state())) {
      (void)uploads_.Reserve(record->info.owner(), record->info.upload_bytes(), /*force=*/true);
    }
    if (record->info.state() == v1::JOB_STATE_RUNNING) {
      // The latest progress is in the event log only
      absl::StatusOr<std::vector<v1::JobEvent>> events = store_.LoadEvents(id);
      if (events.ok()) {
        for (const v1::JobEvent& e : *events) {
          if (e.has_progress()) *record->info.mutable_progress() = e.progress();
        }
      }
      std::lock_guard lock(record->mutex);
      Finish(*record, v1::JOB_STATE_FAILED, nullptr, "daemon stopped while running");
    } else if (record->info.state() == v1::JOB_STATE_QUEUED) {
      queued.push_back(record);
    }
    std::lock_guard lock(mutex_);
    order_.push_back(id);
    jobs_[id] = record;
  }
  for (const auto& record : queued) {
    if (absl::Status s = Queue(record, /*force=*/true); !s.ok()) return s;
    spdlog::info("job {} queued again after a restart", record->info.id());
  }
  return absl::OkStatus();
}

absl::Status JobManager::Queue(const std::shared_ptr<Record>& record, bool force) {
  std::weak_ptr<Record> weak = record;
  return queue_.Push(
      record->info.id(), record->owner,
      [this, weak] {
        if (auto r = weak.lock()) Run(r);
      },
      /*is_job=*/true, force);
}

absl::StatusOr<v1::JobInfo> JobManager::Submit(const v1::SubmitJobRequest& request,
                                               const Caller& caller) {
  if (shutting_down_) {
    return absl::UnavailableError("fenestrad is shutting down; submit the job when it is back");
  }
  // Everything checked before anything is stored
  absl::StatusOr<CheckedJob> checked = CheckJobRequest(request, config_);
  if (!checked.ok()) return checked.status();
  v1::Job& job = checked->job;
  const PreparedJob* prepared = &checked->prepared;

  // The site, and the weather file
  std::optional<SiteManager::ForJob> site;
  if (!request.site_id().empty()) {
    absl::StatusOr<SiteManager::ForJob> found = sites_.Lookup(request.site_id(), caller);
    if (!found.ok()) return found.status();
    if (found->info.state() == v1::SITE_STATE_FAILED) {
      return absl::FailedPreconditionError(absl::StrCat(
          "site ", request.site_id(), " failed (", found->info.error(), "); register it again"));
    }
    site = *std::move(found);
  }
  if (request.weather_epw().empty() && !(site && !site->weather_path.empty())) {
    if (!job.weather_file().empty() || !job.scene().site().weather_file().empty()) {
      return absl::InvalidArgumentError(absl::StrCat(
          "weather file '",
          job.weather_file().empty() ? job.scene().site().weather_file() : job.weather_file(),
          "' is a path on the client; send its content in weather_epw (fenestra job submit "
          "does this)"));
    }
    return absl::InvalidArgumentError(
        "the job has no weather file: send one in weather_epw, or give a site registered with "
        "one");
  }
  const std::string key = OutdoorMatrixKey(prepared->scene, prepared->job.sampling());
  if (site && key != site->info.outdoor_key()) {
    return absl::InvalidArgumentError(absl::StrCat(
        "the job does not match site ", request.site_id(),
        ": its outdoor surfaces, materials, window or outdoor sampling (outdoor_paths, "
        "outdoor_bounces, seed, basis_cells, window parts) differ from the site's, so the site's "
        "outdoor "
        "matrix cannot be reused (job key ",
        key.substr(0, 16), ", site key ", site->info.outdoor_key().substr(0, 16), ")"));
  }

  // Its upload counts against its owner until it ends
  const int64_t upload_bytes = static_cast<int64_t>(request.weather_epw().size());
  if (absl::Status s = uploads_.Reserve(caller.name, upload_bytes); !s.ok()) return s;
  std::string weather_path;
  if (!request.weather_epw().empty()) {
    absl::StatusOr<std::string> saved = SaveUploadedWeather(
        (std::filesystem::path(config_.data_dir()) / "weather").string(), request.weather_epw());
    if (!saved.ok()) {
      uploads_.Release(caller.name, upload_bytes);
      return saved.status();
    }
    weather_path = *saved;
  } else {
    weather_path = site->weather_path;
  }
  job.set_weather_file(weather_path);
  job.mutable_scene()->mutable_site()->clear_weather_file();

  // Store and queue it
  auto record = std::make_shared<Record>();
  record->job = job;
  record->owner = caller.name;
  v1::JobInfo& info = record->info;
  info.set_owner(caller.name);
  info.set_upload_bytes(upload_bytes);
  info.set_name(job.name().empty() ? prepared->scene.name : job.name());
  info.set_state(v1::JOB_STATE_QUEUED);
  info.set_site_id(request.site_id());
  info.set_stage("queued");
  info.set_created_unix_ms(NowUnixMs());
  info.set_outdoor_key(key);
  info.set_backend(prepared->job.sampling().backend());
  absl::StatusOr<std::string> id = store_.InsertJob(info, job);
  if (!id.ok()) {
    uploads_.Release(caller.name, upload_bytes);
    return id.status();
  }
  {
    std::lock_guard lock(mutex_);
    order_.push_back(*id);
    jobs_[*id] = record;
  }
  std::lock_guard lock(record->mutex);
  if (absl::Status s = Queue(record, /*force=*/false); !s.ok()) {
    {
      std::lock_guard jobs_lock(mutex_);
      order_.pop_back();
      jobs_.erase(*id);
    }
    if (absl::Status d = store_.DeleteJob(*id); !d.ok()) {
      spdlog::error("job {}: cannot remove it from the store: {}", *id, d.ToString());
    }
    uploads_.Release(caller.name, upload_bytes);
    return s;
  }
  v1::JobEvent event;
  event.set_queued(std::max(0, queue_.Position(*id)));
  Emit(*record, event);
  spdlog::info("job {} queued by {} (\"{}\"): {} evaluations at most, {} indoor paths per sensor{}",
               *id, caller.name, LogSafe(info.name()), prepared->job.budget().max_evaluations(),
               prepared->job.sampling().indoor_paths_per_sensor(),
               site ? absl::StrCat(", site ", request.site_id()) : "");
  return InfoOf(*record, caller);
}

void JobManager::Run(const std::shared_ptr<Record>& shared) {
  Record& r = *shared;
  const auto start = std::chrono::steady_clock::now();
  const auto cancelled = [&] { return r.cancel_requested.load() || interrupted_.load(); };
  const auto stopped_state = [&] {
    return r.cancel_requested.load() ? v1::JOB_STATE_CANCELLED : v1::JOB_STATE_INTERRUPTED;
  };
  v1::Job job;
  {
    std::lock_guard lock(r.mutex);
    if (r.info.state() != v1::JOB_STATE_QUEUED) return;
    if (r.cancel_requested) {
      Finish(r, v1::JOB_STATE_CANCELLED, nullptr, "");
      return;
    }
    r.info.set_state(v1::JOB_STATE_RUNNING);
    r.info.set_started_unix_ms(NowUnixMs());
    r.info.set_stage("outdoor");
    v1::JobEvent event;
    event.mutable_started()->set_backend(r.info.backend());
    Emit(r, event);
    Save(r);
    job = r.job;
    spdlog::info("job {} running (\"{}\")", r.info.id(), LogSafe(r.info.name()));
  }
  try {
    absl::StatusOr<PreparedJob> prepared = PrepareJob(job, "");
    if (!prepared.ok()) {
      std::lock_guard lock(r.mutex);
      Finish(r, v1::JOB_STATE_FAILED, nullptr, std::string(prepared.status().message()));
      return;
    }
    const std::string key = OutdoorMatrixKey(prepared->scene, prepared->job.sampling());

    // The outdoor matrix: cached, being computed by another task, or traced here
    {
      std::lock_guard lock(r.mutex);
      v1::JobEvent event;
      event.mutable_stage()->set_name("outdoor");
      event.mutable_stage()->set_cached(cache_.Find(key) != nullptr);
      Emit(r, event);
    }
    const auto outdoor_start = std::chrono::steady_clock::now();
    absl::StatusOr<OutdoorCache::Lookup> lookup = cache_.GetOrCompute(
        key,
        [&]() -> absl::StatusOr<OutdoorMatrix> {
          return ComputeOutdoorMatrix(prepared->scene, prepared->job.sampling(), cancelled);
        },
        cancelled);
    const double outdoor_seconds = SecondsSince(outdoor_start);
    if (!lookup.ok()) {
      std::lock_guard lock(r.mutex);
      if (cancelled()) {
        Finish(r, stopped_state(), nullptr, "");
      } else {
        Finish(r, v1::JOB_STATE_FAILED, nullptr,
               absl::StrCat("outdoor stage: ", lookup.status().message()));
      }
      return;
    }
    {
      std::lock_guard lock(r.mutex);
      r.info.set_outdoor_reused(!lookup->computed);
      r.info.set_outdoor_seconds(outdoor_seconds);
      Save(r);
      spdlog::info("job {}: outdoor matrix {} in {:.3f} s", r.info.id(),
                   lookup->computed ? "traced" : "reused from the cache", outdoor_seconds);
    }
    if (!lookup->computed && !r.info.site_id().empty()) sites_.NoteReuse(r.info.site_id());

    // The search
    JobCallbacks callbacks;
    callbacks.stage = [&](const std::string& stage) {
      if (stage == "outdoor") return;
      std::lock_guard lock(r.mutex);
      r.info.set_stage(stage);
      v1::JobEvent event;
      event.mutable_stage()->set_name(stage);
      Emit(r, event);
    };
    callbacks.progress = [&](const JobProgress& progress) {
      std::lock_guard lock(r.mutex);
      v1::JobEvent event;
      *event.mutable_progress() = ToProto(progress);
      *r.info.mutable_progress() = event.progress();
      Emit(r, event);
    };
    callbacks.cancelled = cancelled;
    absl::StatusOr<v1::JobResult> result = RunJob(*prepared, lookup->matrix.get(), callbacks);

    std::lock_guard lock(r.mutex);
    if (!result.ok()) {
      if (cancelled()) {
        Finish(r, stopped_state(), nullptr, "");
      } else {
        Finish(r, v1::JOB_STATE_FAILED, nullptr, std::string(result.status().message()));
      }
      return;
    }
    v1::Timings& timings = *result->mutable_timings();
    timings.set_outdoor_seconds(lookup->computed ? lookup->matrix->wall_seconds : 0);
    timings.set_total_seconds(SecondsSince(start));
    if (result->stop_reason() == "cancelled") {
      Finish(r, stopped_state(), &*result, "");
    } else {
      Finish(r, v1::JOB_STATE_SUCCEEDED, &*result, "");
    }
  } catch (const std::exception& e) {
    std::lock_guard lock(r.mutex);
    Finish(r, v1::JOB_STATE_FAILED, nullptr, absl::StrCat("internal error: ", e.what()));
  }
}

void JobManager::Finish(Record& r, v1::JobState state, const v1::JobResult* result,
                        const std::string& error) {
  r.info.set_state(state);
  r.info.set_stage("done");
  r.info.set_finished_unix_ms(NowUnixMs());
  r.info.set_queue_position(0);
  if (result) *r.info.mutable_result() = *result;
  r.info.set_error(error);
  v1::JobEvent event;
  switch (state) {
    case v1::JOB_STATE_SUCCEEDED:
      *event.mutable_finished() = *result;
      break;
    case v1::JOB_STATE_CANCELLED:
      if (result)
        *event.mutable_cancelled()->mutable_result() = *result;
      else
        event.mutable_cancelled();
      break;
    case v1::JOB_STATE_INTERRUPTED:
      if (result)
        *event.mutable_interrupted()->mutable_result() = *result;
      else
        event.mutable_interrupted();
      break;
    default:
      event.set_failed(error);
  }
  Emit(r, event);
  Save(r);
  uploads_.Release(r.info.owner(), r.info.upload_bytes());
  const std::string& id = r.info.id();
  const std::string best =
      result && result->evaluations() > 0
          ? absl::StrCat(": best ", DesignText(result->best_design()), ", value ",
                         absl::SixDigits(result->best_value().value()), " ± ",
                         absl::SixDigits(result->best_value().standard_error()), " after ",
                         result->evaluations(), " evaluations (", result->stop_reason(), ")")
          : "";
  const std::string check =
      result && result->has_final_check()
          ? absl::StrCat("; final check (one-stage) ",
                         absl::SixDigits(result->final_check().one_stage().value()), " ± ",
                         absl::SixDigits(result->final_check().one_stage().standard_error()))
          : "";
  switch (state) {
    case v1::JOB_STATE_SUCCEEDED:
      spdlog::info("job {} succeeded{}{}", id, best, check);
      break;
    case v1::JOB_STATE_CANCELLED:
      spdlog::info("job {} cancelled{}", id, best);
      break;
    case v1::JOB_STATE_INTERRUPTED:
      spdlog::info("job {} interrupted by the shutdown{}", id, best);
      break;
    default:
      spdlog::warn("job {} failed: {}", id, LogSafe(error));
  }
  if (result && result->final_check().disagrees()) {
    const v1::Estimate& d = result->final_check().difference();
    spdlog::warn(
        "job {}: the final check disagrees: one-stage minus two-stage {:.4g} ± {:.4g} ({:.1f} "
        "standard errors); the two-stage value is off by more than its Monte Carlo error",
        id, d.value(), d.standard_error(),
        d.standard_error() > 0 ? std::abs(d.value()) / d.standard_error() : 0.0);
  }
}

void JobManager::Emit(Record& r, v1::JobEvent event) {
  event.set_sequence(r.info.last_sequence() + 1);
  event.set_time_unix_ms(NowUnixMs());
  r.info.set_last_sequence(event.sequence());
  if (absl::Status s = store_.AppendEvent(r.info.id(), event); !s.ok()) {
    spdlog::error("job {}: cannot store an event: {}", r.info.id(), s.ToString());
  }
  r.events.push_back(std::move(event));
  while (r.events.size() > kKeptEvents) r.events.pop_front();
  r.changed.notify_all();
}

void JobManager::Save(const Record& r) {
  if (absl::Status s = store_.UpdateJob(r.info); !s.ok()) {
    spdlog::error("job {}: cannot store its state: {}", r.info.id(), s.ToString());
  }
}

v1::JobInfo JobManager::InfoOf(const Record& r, const Caller& caller) const {
  v1::JobInfo info = ForCaller(r.info, caller);
  if (info.state() == v1::JOB_STATE_QUEUED) {
    info.set_queue_position(std::max(0, queue_.Position(info.id())));
  }
  info.set_cancel_requested(r.cancel_requested.load());
  return info;
}

std::shared_ptr<JobManager::Record> JobManager::Find(const std::string& id,
                                                     const Caller& caller) const {
  std::lock_guard lock(mutex_);
  auto it = jobs_.find(id);
  if (it == jobs_.end() || !caller.Owns(it->second->owner)) return nullptr;
  return it->second;
}

absl::StatusOr<v1::JobInfo> JobManager::Get(const std::string& id, const Caller& caller) const {
  std::shared_ptr<Record> r = Find(id, caller);
  if (!r) return NoJob(id);
  std::lock_guard lock(r->mutex);
  return InfoOf(*r, caller);
}

std::vector<v1::JobInfo> JobManager::List(v1::JobState state, int limit,
                                          const Caller& caller) const {
  if (limit <= 0) limit = 100;
  std::vector<std::shared_ptr<Record>> records;
  {
    std::lock_guard lock(mutex_);
    for (auto it = order_.rbegin(); it != order_.rend(); ++it) {
      const std::shared_ptr<Record>& r = jobs_.at(*it);
      if (caller.Owns(r->owner)) records.push_back(r);
    }
  }
  std::vector<v1::JobInfo> jobs;
  for (const auto& r : records) {
    if (static_cast<int>(jobs.size()) >= limit) break;
    std::lock_guard lock(r->mutex);
    if (state != v1::JOB_STATE_UNSPECIFIED && r->info.state() != state) continue;
    jobs.push_back(InfoOf(*r, caller));
    jobs.back().clear_result();
  }
  return jobs;
}

absl::StatusOr<v1::JobInfo> JobManager::Cancel(const std::string& id, const Caller& caller) {
  std::shared_ptr<Record> r = Find(id, caller);
  if (!r) return NoJob(id);
  std::lock_guard lock(r->mutex);
  if (IsTerminal(r->info.state())) return InfoOf(*r, caller);
  r->cancel_requested = true;
  if (r->info.state() == v1::JOB_STATE_QUEUED && queue_.Remove(id)) {
    Finish(*r, v1::JOB_STATE_CANCELLED, nullptr, "");
  } else {
    spdlog::info("job {}: cancel requested by {}; it stops at its next checkpoint", id,
                 caller.name);
  }
  return InfoOf(*r, caller);
}

absl::Status JobManager::Watch(const std::string& id, const Caller& caller,
                               const std::function<bool(const v1::JobEvent&)>& write,
                               const std::function<bool()>& client_gone) {
  std::shared_ptr<Record> r = Find(id, caller);
  if (!r) return NoJob(id);
  bool resend_snapshot = true;
  int64_t sent = 0;
  while (true) {
    std::vector<v1::JobEvent> pending;
    {
      std::unique_lock lock(r->mutex);
      if (!resend_snapshot) {
        r->changed.wait_for(lock, std::chrono::milliseconds(250),
                            [&] { return r->info.last_sequence() > sent || closing_.load(); });
        // Fell behind the kept events: start over from a snapshot
        if (!r->events.empty() && r->events.front().sequence() > sent + 1 &&
            r->info.last_sequence() > sent) {
          resend_snapshot = true;
        }
      }
      if (resend_snapshot) {
        v1::JobEvent snapshot;
        *snapshot.mutable_snapshot() = InfoOf(*r, caller);
        snapshot.set_sequence(r->info.last_sequence());
        snapshot.set_time_unix_ms(NowUnixMs());
        pending.push_back(std::move(snapshot));
        resend_snapshot = false;
      } else {
        for (const v1::JobEvent& e : r->events) {
          if (e.sequence() > sent) pending.push_back(e);
        }
      }
    }
    for (const v1::JobEvent& e : pending) {
      if (!write(e)) return absl::OkStatus();
      sent = e.sequence();
      const bool ended = e.has_snapshot() ? IsTerminal(e.snapshot().state())
                                          : e.has_finished() || e.has_failed() ||
                                                e.has_cancelled() || e.has_interrupted();
      if (ended) return absl::OkStatus();
    }
    if (pending.empty() && client_gone()) return absl::OkStatus();
    if (pending.empty() && closing_) {
      return absl::UnavailableError("fenestrad is shutting down; the job stays queued");
    }
  }
}

void JobManager::Shutdown(double grace_seconds) {
  shutting_down_ = true;
  sites_.BeginShutdown();
  queue_.Stop();
  if (queue_.Running() > 0) {
    spdlog::info("waiting up to {:.0f} s for {} running task(s) to finish", grace_seconds,
                 queue_.Running());
  }
  if (!queue_.WaitIdle(grace_seconds)) {
    spdlog::info("stopping the running tasks at their next checkpoint");
    interrupted_ = true;
    sites_.Interrupt();
  }
  queue_.Join();
  closing_ = true;
  std::lock_guard lock(mutex_);
  for (auto& [id, r] : jobs_) r->changed.notify_all();
}

}  // namespace fenestra
