// JobManager: submission and its checks, the queries (Get, List, Watch) and Cancel. Running
// a claimed job, its end and the shutdown: job_run.cpp.
#include "server/job_manager.h"

#include <spdlog/spdlog.h>

#include <chrono>
#include <utility>

#include "absl/strings/str_cat.h"
#include "core/common/status_macros.h"
#include "core/dc/dc_backend.h"
#include "server/checksum.h"
#include "server/limits.h"
#include "server/log_safe.h"

namespace fenestra {
namespace {

// The answer for an unknown job, and for another user's.
absl::Status NoJob(const std::string& id) {
  return absl::NotFoundError(absl::StrCat("no job '", id, "' (fenestra job list shows them)"));
}

// Whether an event ends its job's stream.
bool EndsStream(const v1::JobEvent& e) {
  return e.has_snapshot()
             ? IsTerminal(e.snapshot().state())
             : e.has_finished() || e.has_failed() || e.has_cancelled() || e.has_interrupted();
}

// How long a Watch waits for news before it looks at the store again; and how often it
// asks whether the store answers after it could not be reached.
constexpr auto kWatchPoll = std::chrono::seconds(1);
constexpr auto kWatchRetry = std::chrono::milliseconds(500);

}  // namespace

bool IsTerminal(v1::JobState state) {
  return state == v1::JOB_STATE_SUCCEEDED || state == v1::JOB_STATE_FAILED ||
         state == v1::JOB_STATE_CANCELLED || state == v1::JOB_STATE_INTERRUPTED;
}

JobManager::JobManager(const v1::DaemonConfig& config, const DataDir* data_dir, Store& store,
                       OutdoorCache& cache, SiteManager& sites, HeavyRequests& heavy,
                       Scheduler& scheduler)
    : config_(config),
      data_dir_(data_dir),
      store_(store),
      cache_(cache),
      sites_(sites),
      heavy_(heavy),
      scheduler_(scheduler),
      committer_([this] { Commit(); }) {}

JobManager::~JobManager() {
  {
    std::lock_guard lock(waiting_mutex_);
    stop_committer_ = true;
  }
  waiting_changed_.notify_all();
  if (committer_.joinable()) committer_.join();
}

absl::StatusOr<v1::JobInfo> JobManager::Submit(const v1::SubmitJobRequest& request,
                                               const Caller& caller) {
  if (shutting_down_) {
    return absl::UnavailableError("fenestrad is shutting down; submit the job when it is back");
  }
  absl::StatusOr<HeavyRequests::Pass> pass = heavy_.Enter(request.ByteSizeLong());
  if (!pass.ok()) return pass.status();
  absl::StatusOr<Admission> admitted = Admit(request, caller);
  if (!admitted.ok()) return admitted.status();
  if (data_dir_) {
    if (absl::Status s = data_dir_->MakeRoom(static_cast<int64_t>(request.job().ByteSizeLong()));
        !s.ok()) {
      return s;
    }
  }

  Store::NewJob job;
  job.info = std::move(admitted->info);
  job.info.set_stage("queued");
  job.info.set_created_unix_ms(NowUnixMs());
  job.job = std::move(admitted->job);
  job.job.clear_weather_file();
  job.job.mutable_scene()->mutable_site()->clear_weather_file();
  job.weather_epw = request.weather_epw();
  absl::StatusOr<v1::JobInfo> queued = store_.InsertJob(std::move(job), config_.limits());
  if (!queued.ok()) return queued.status();
  spdlog::info("job {} queued by {} (\"{}\"): {} evaluations at most, {} indoor paths per sensor{}",
               queued->id(), caller.name, LogSafe(queued->name()), admitted->max_evaluations,
               admitted->indoor_paths_per_sensor,
               admitted->site ? absl::StrCat(", site ", request.site_id()) : "");
  // Its place in the queue, as it stands now
  absl::StatusOr<v1::JobInfo> now = store_.GetJob(queued->id());
  return ForCaller(now.ok() ? *now : *queued, caller);
}

absl::StatusOr<JobManager::Admission> JobManager::Admit(const v1::SubmitJobRequest& request,
                                                        const Caller& caller) {
  // Everything checked before anything is stored
  absl::StatusOr<CheckedJob> checked = CheckJobRequest(
      request, config_, [this](const std::string& epw) { return weather_.Holds(Sha256Hex(epw)); });
  if (!checked.ok()) return checked.status();
  const PreparedJob& prepared = checked->prepared;
  Admission admitted;

  // A job for the GPU on a daemon without one would fail when it starts
  if (checked->job.sampling().backend() == "cuda" && CudaDevicesInUse() == 0) {
    const std::string field = !request.job().sampling().backend().empty() ? "job.sampling.backend"
                              : !request.default_backend().empty()
                                  ? "default_backend"
                                  : "backend (in fenestrad's configuration)";
    return absl::FailedPreconditionError(
        absl::StrCat(field,
                     ": \"cuda\" needs a GPU, and this fenestrad has none; give \"cpu\" "
                     "or \"auto\""));
  }

  // The site, and a weather file from somewhere
  if (!request.site_id().empty()) {
    absl::StatusOr<SiteManager::ForJob> found = sites_.Lookup(request.site_id(), caller);
    if (!found.ok()) return found.status();
    if (found->info.state() == v1::SITE_STATE_FAILED) {
      return absl::FailedPreconditionError(absl::StrCat(
          "site ", request.site_id(), " failed (", found->info.error(), "); register it again"));
    }
    admitted.site = *std::move(found);
  }
  const std::optional<SiteManager::ForJob>& site = admitted.site;
  const v1::Job& job = checked->job;
  if (request.weather_epw().empty() && !(site && !site->weather.empty())) {
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

  v1::JobInfo& info = admitted.info;
  info.set_owner(caller.name);
  info.set_upload_bytes(static_cast<int64_t>(request.weather_epw().size()));
  info.set_outdoor_key(OutdoorMatrixKey(prepared.scene, prepared.job.sampling()));
  info.set_name(job.name().empty() ? prepared.scene.name : job.name());
  info.set_backend(prepared.job.sampling().backend());
  info.set_site_id(request.site_id());
  admitted.max_evaluations = prepared.job.budget().max_evaluations();
  admitted.indoor_paths_per_sensor = prepared.job.sampling().indoor_paths_per_sensor();
  if (site && info.outdoor_key() != site->info.outdoor_key()) {
    return absl::InvalidArgumentError(absl::StrCat(
        "the job does not match site ", request.site_id(),
        ": its outdoor surfaces, materials, window or outdoor sampling (outdoor_paths, "
        "outdoor_bounces, seed, basis_cells, window parts) differ from the site's, so the site's "
        "outdoor matrix cannot be reused (job key ",
        info.outdoor_key().substr(0, 16), ", site key ", site->info.outdoor_key().substr(0, 16),
        ")"));
  }
  admitted.job = std::move(checked->job);
  return admitted;
}

absl::StatusOr<v1::JobInfo> JobManager::Find(const std::string& id, const Caller& caller) {
  absl::StatusOr<v1::JobInfo> info = store_.GetJob(id);
  if (!info.ok()) {
    return info.status().code() == absl::StatusCode::kNotFound ? NoJob(id) : info.status();
  }
  if (!caller.Owns(info->owner())) return NoJob(id);
  return info;
}

absl::StatusOr<v1::JobInfo> JobManager::Get(const std::string& id, const Caller& caller) {
  absl::StatusOr<v1::JobInfo> info = Find(id, caller);
  if (!info.ok()) return info.status();
  return ForCaller(*std::move(info), caller);
}

absl::StatusOr<std::vector<v1::JobInfo>> JobManager::List(v1::JobState state, int limit,
                                                          const Caller& caller) {
  absl::StatusOr<std::vector<v1::JobInfo>> jobs =
      store_.ListJobs(caller.admin ? "" : caller.name, state, limit <= 0 ? 100 : limit);
  if (!jobs.ok()) return jobs.status();
  for (v1::JobInfo& info : *jobs) info = ForCaller(std::move(info), caller);
  return jobs;
}

absl::StatusOr<v1::JobInfo> JobManager::Cancel(const std::string& id, const Caller& caller) {
  absl::StatusOr<v1::JobInfo> found = Find(id, caller);
  if (!found.ok()) return found.status();
  if (IsTerminal(found->state())) return ForCaller(*std::move(found), caller);
  // Run here: the runner hears it at once; the store tells the other replicas
  std::shared_ptr<Scheduler::Held> local = scheduler_.Find(id);
  if (local) local->cancel_requested = true;
  absl::StatusOr<Store::Cancelled> cancelled = store_.CancelJob(id, [](v1::JobInfo& info) {
    return EndOf(info, v1::JOB_STATE_CANCELLED, nullptr, absl::OkStatus());
  });
  if (!cancelled.ok()) {
    if (!local) return cancelled.status();
    // The runner stops all the same; its end is stored when the store takes it
    found->set_cancel_requested(true);
    spdlog::info("job {}: cancel requested by {}; it stops at its next checkpoint", id,
                 caller.name);
    return ForCaller(*std::move(found), caller);
  }
  if (cancelled->ended) {
    store_.ReleaseWeather(cancelled->weather);
    spdlog::info("job {}: cancelled by {} while queued", id, caller.name);
  } else if (cancelled->info.state() != v1::JOB_STATE_QUEUED ||
             cancelled->info.cancel_requested()) {
    spdlog::info("job {}: cancel requested by {}; it stops at its next checkpoint", id,
                 caller.name);
  }
  return ForCaller(std::move(cancelled->info), caller);
}

absl::Status JobManager::Delete(const std::string& id, const Caller& caller) {
  absl::StatusOr<v1::JobInfo> found = Find(id, caller);
  if (!found.ok()) return found.status();
  if (!IsTerminal(found->state())) {
    return absl::FailedPreconditionError(
        absl::StrCat("job ", id, " has not ended: cancel it first, then delete it"));
  }
  FENESTRA_RETURN_IF_ERROR(store_.DeleteJob(id));
  spdlog::info("job {}: deleted by {}", id, LogSafe(caller.name));
  return absl::OkStatus();
}

absl::Status JobManager::Watch(const std::string& id, const Caller& caller,
                               const std::function<bool(const v1::JobEvent&)>& write,
                               const std::function<bool()>& client_gone) {
  absl::StatusOr<v1::JobInfo> first = Find(id, caller);
  if (!first.ok()) return first.status();
  const auto snapshot_of = [&](v1::JobInfo info) {
    v1::JobEvent snapshot;
    snapshot.set_sequence(info.last_sequence());
    snapshot.set_time_unix_ms(NowUnixMs());
    *snapshot.mutable_snapshot() = ForCaller(std::move(info), caller);
    return snapshot;
  };
  std::optional<v1::JobEvent> snapshot = snapshot_of(*std::move(first));
  int64_t sent = 0;
  Database& db = store_.database();
  while (true) {
    const uint64_t seen = db.ChangeCount();
    std::vector<v1::JobEvent> pending;
    if (snapshot) {
      pending.push_back(*std::move(snapshot));
      snapshot.reset();
    } else {
      absl::StatusOr<std::vector<v1::JobEvent>> events = store_.LoadEvents(id, sent);
      if (!events.ok()) {
        // The store is away: the stream waits for it
        store_.AwaitAnswer(kWatchRetry, [&] { return client_gone() || closing_; });
        if (client_gone()) return absl::OkStatus();
        if (closing_) return absl::UnavailableError("fenestrad is shutting down");
        continue;
      }
      pending = *std::move(events);
      // Fell behind events that were dropped (the job ended): start over from a snapshot
      if (!pending.empty() && pending.front().sequence() > sent + 1) {
        absl::StatusOr<v1::JobInfo> now = Find(id, caller);
        if (!now.ok()) return now.status();
        pending = {snapshot_of(*std::move(now))};
      }
    }
    for (v1::JobEvent& e : pending) {
      if (!caller.admin && e.has_started()) e.mutable_started()->clear_replica();
      if (!write(e)) return absl::OkStatus();
      sent = e.sequence();
      if (EndsStream(e)) return absl::OkStatus();
    }
    if (!pending.empty()) continue;
    if (client_gone()) return absl::OkStatus();
    if (closing_) {
      return absl::UnavailableError(
          "fenestrad is shutting down; the job goes on (watch it again through another "
          "replica, or once this one is back)");
    }
    db.WaitForChange(seen, kWatchPoll);
  }
}

v1::JobEvent JobManager::EndOf(v1::JobInfo& info, v1::JobState state, const v1::JobResult* result,
                               const absl::Status& error) {
  info.set_state(state);
  info.set_stage("done");
  info.set_finished_unix_ms(NowUnixMs());
  info.set_queue_position(0);
  info.clear_replica();
  if (result) *info.mutable_result() = *result;
  info.set_error(std::string(error.message()));
  info.set_error_code(static_cast<int32_t>(error.code()));
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
      event.set_failed(std::string(error.message()));
  }
  event.set_sequence(info.last_sequence() + 1);
  event.set_time_unix_ms(info.finished_unix_ms());
  info.set_last_sequence(event.sequence());
  return event;
}

}  // namespace fenestra
