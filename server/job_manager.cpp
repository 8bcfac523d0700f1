#include "server/job_manager.h"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <thread>

#include "absl/cleanup/cleanup.h"
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

JobManager::JobManager(const v1::DaemonConfig& config, const DataDir& data_dir, JobStore& store,
                       OutdoorCache& cache, UploadStore& weather, WorkQueue& queue,
                       SiteManager& sites, HeavyRequests& heavy, UploadQuota& uploads)
    : config_(config),
      data_dir_(data_dir),
      store_(store),
      cache_(cache),
      weather_(weather),
      queue_(queue),
      sites_(sites),
      heavy_(heavy),
      uploads_(uploads),
      committer_([this] { Commit(); }) {}

JobManager::~JobManager() {
  {
    std::lock_guard lock(waiting_mutex_);
    stop_committer_ = true;
  }
  waiting_changed_.notify_all();
  if (committer_.joinable()) committer_.join();
}

absl::Status JobManager::Recover() {
  absl::StatusOr<JobStore::StoredJobs> stored = store_.LoadJobs();
  if (!stored.ok()) return stored.status();
  for (const JobStore::Quarantined& q : stored->quarantined) {
    spdlog::error(
        "job {}: its stored record does not parse ({}); moved to the quarantine "
        "table, the daemon goes on without it",
        LogSafe(q.id), q.reason);
  }
  std::vector<std::shared_ptr<Record>> queued;
  for (v1::JobInfo& info : stored->jobs) {
    auto record = std::make_shared<Record>();
    const std::string id = info.id();
    record->info = std::move(info);
    if (record->info.owner().empty()) record->info.set_owner(kLocalUser);  // stored before owners
    record->owner = record->info.owner();
    record->wanted = record->info;
    const v1::JobState state = record->info.state();
    if (state == v1::JOB_STATE_QUEUED) {
      // A queued job runs from its stored form: check that it parses now
      absl::StatusOr<v1::Job> job = store_.LoadJob(id);
      if (!job.ok()) {
        if (job.status().code() != absl::StatusCode::kDataLoss) return job.status();
        const absl::Status moved =
            store_.Quarantine("jobs", id, std::string(job.status().message()));
        spdlog::error("job {}: {}; {}, the daemon goes on without it", id,
                      std::string(job.status().message()),
                      moved.ok() ? "moved to the quarantine table"
                                 : absl::StrCat("not moved (", moved.message(), ")"));
        continue;
      }
      record->weather_path = job->weather_file();
      if (!record->weather_path.empty()) weather_.Ref(record->weather_path);
      queued.push_back(record);
    } else if (state == v1::JOB_STATE_RUNNING) {
      // The latest progress is in the event log only
      absl::StatusOr<std::vector<v1::JobEvent>> events = store_.LoadEvents(id);
      if (events.ok()) {
        for (const v1::JobEvent& e : *events) {
          if (e.has_progress()) *record->wanted.mutable_progress() = e.progress();
        }
      }
    }
    // An unfinished job's upload counts against its owner until it ends (Ended)
    if (!IsTerminal(state)) {
      (void)uploads_.Reserve(record->owner, record->info.upload_bytes(), /*force=*/true);
    }
    {
      std::lock_guard lock(mutex_);
      if (state == v1::JOB_STATE_QUEUED) active_keys_.insert(record->info.outdoor_key());
      order_.push_back(id);
      jobs_[id] = record;
    }
    if (state == v1::JOB_STATE_RUNNING) {
      std::lock_guard lock(record->mutex);
      (void)Finish(*record, v1::JOB_STATE_FAILED, nullptr, "daemon stopped while running",
                   /*retry=*/true);
    }
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
  absl::StatusOr<HeavyRequests::Pass> pass = heavy_.Enter(request.ByteSizeLong());
  if (!pass.ok()) return pass.status();
  absl::StatusOr<Admission> admitted = Admit(request, caller);
  if (!admitted.ok()) return admitted.status();

  // Its upload counts against its owner until it ends; room for the job, then its weather
  // file: the upload, or the site's
  const int64_t upload_bytes = admitted->info.upload_bytes();
  if (absl::Status s = uploads_.Reserve(caller.name, upload_bytes); !s.ok()) return s;
  absl::Cleanup release_quota = [&] { uploads_.Release(caller.name, upload_bytes); };
  if (absl::Status s = data_dir_.MakeRoom(static_cast<int64_t>(request.job().ByteSizeLong()));
      !s.ok()) {
    return s;
  }
  absl::StatusOr<std::string> weather_path = TakeWeather(request, admitted->site, caller);
  if (!weather_path.ok()) return weather_path.status();
  // Until the job is queued, the reference is this call's
  absl::Cleanup release_weather = [&] { weather_.Unref(*weather_path); };
  v1::Job& job = admitted->job;
  job.set_weather_file(*weather_path);
  job.mutable_scene()->mutable_site()->clear_weather_file();
  absl::StatusOr<v1::JobInfo> queued = StoreAndQueue(job, admitted->info, *weather_path, caller);
  if (!queued.ok()) return queued.status();
  std::move(release_weather).Cancel();
  std::move(release_quota).Cancel();
  spdlog::info("job {} queued by {} (\"{}\"): {} evaluations at most, {} indoor paths per sensor{}",
               queued->id(), caller.name, LogSafe(queued->name()), admitted->max_evaluations,
               admitted->indoor_paths_per_sensor,
               admitted->site ? absl::StrCat(", site ", request.site_id()) : "");
  return queued;
}

absl::StatusOr<JobManager::Admission> JobManager::Admit(const v1::SubmitJobRequest& request,
                                                        const Caller& caller) const {
  // Everything checked before anything is stored
  absl::StatusOr<CheckedJob> checked = CheckJobRequest(request, config_);
  if (!checked.ok()) return checked.status();
  const PreparedJob& prepared = checked->prepared;
  Admission admitted;

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

absl::StatusOr<std::string> JobManager::TakeWeather(const v1::SubmitJobRequest& request,
                                                    const std::optional<SiteManager::ForJob>& site,
                                                    const Caller& caller) {
  if (!request.weather_epw().empty()) return weather_.Add(request.weather_epw());
  weather_.Ref(site->weather_path);
  if (!sites_.Lookup(request.site_id(), caller).ok()) {  // deleted meanwhile
    weather_.Unref(site->weather_path);
    return absl::NotFoundError(absl::StrCat("no site '", request.site_id(), "' any more"));
  }
  return site->weather_path;
}

absl::StatusOr<v1::JobInfo> JobManager::StoreAndQueue(const v1::Job& job, v1::JobInfo info,
                                                      const std::string& weather_path,
                                                      const Caller& caller) {
  info.set_state(v1::JOB_STATE_QUEUED);
  info.set_stage("queued");
  info.set_created_unix_ms(NowUnixMs());
  info.set_last_sequence(1);
  v1::JobEvent queued;
  queued.set_sequence(1);
  queued.set_time_unix_ms(info.created_unix_ms());
  queued.set_queued(queue_.QueuedJobs());
  absl::StatusOr<std::string> id = store_.InsertJob(info, job, &queued);
  if (!id.ok()) return id.status();
  auto record = std::make_shared<Record>();
  record->owner = info.owner();
  record->info = info;
  record->wanted = info;
  record->weather_path = weather_path;
  record->events.push_back(queued);
  {
    std::lock_guard lock(mutex_);
    order_.push_back(*id);
    jobs_[*id] = record;
    active_keys_.insert(info.outdoor_key());
  }
  std::lock_guard lock(record->mutex);
  if (absl::Status s = Queue(record, /*force=*/false); !s.ok()) {
    {
      std::lock_guard jobs_lock(mutex_);
      order_.pop_back();
      jobs_.erase(*id);
      active_keys_.erase(active_keys_.find(info.outdoor_key()));
    }
    if (absl::Status d = store_.DeleteJob(*id); !d.ok()) {
      spdlog::error("job {}: cannot remove it from the store: {}", *id, std::string(d.message()));
    }
    return s;
  }
  return InfoOf(*record, caller);
}

absl::Status JobManager::Store(Record& r, std::optional<v1::JobEvent> event, bool durable) {
  if (event) {
    event->set_sequence(r.info.last_sequence() + 1);
    event->set_time_unix_ms(NowUnixMs());
    r.wanted.set_last_sequence(event->sequence());
  }
  const absl::Status stored = store_.UpdateJob(r.wanted, event ? &*event : nullptr, durable);
  if (!stored.ok()) {
    r.wanted.set_last_sequence(r.info.last_sequence());
    return stored;
  }
  r.info = r.wanted;
  if (event) {
    r.events.push_back(*std::move(event));
    while (r.events.size() > kKeptEvents) r.events.pop_front();
  }
  r.changed.notify_all();
  return absl::OkStatus();
}

void JobManager::Report(Record& r, std::optional<v1::JobEvent> event, bool durable) {
  const absl::Status stored = Store(r, std::move(event), durable);
  if (!stored.ok() && !r.store_failing) {
    spdlog::error(
        "job {}: cannot store its progress ({}); it goes on, and what it reports "
        "waits until the store takes it",
        r.info.id(), std::string(stored.message()));
  } else if (stored.ok() && r.store_failing) {
    spdlog::info("job {}: its progress is stored again", r.info.id());
  }
  r.store_failing = !stored.ok();
}

void JobManager::Run(const std::shared_ptr<Record>& shared) {
  Record& r = *shared;
  if (Start(r)) {
    try {
      RunStarted(r);
    } catch (const std::exception& e) {
      std::lock_guard lock(r.mutex);
      (void)Finish(r, v1::JOB_STATE_FAILED, nullptr, absl::StrCat("internal error: ", e.what()),
                   /*retry=*/true);
    }
  }
  ReleaseFreeMemory();  // the scene, its BVH and the tracer's buffers
}

bool JobManager::Start(Record& r) {
  for (int attempt = 0;; ++attempt) {
    {
      std::lock_guard lock(r.mutex);
      if (r.info.state() != v1::JOB_STATE_QUEUED || r.end) return false;
      if (r.cancel_requested) {
        (void)Finish(r, v1::JOB_STATE_CANCELLED, nullptr, "", /*retry=*/true);
        return false;
      }
      r.wanted.set_state(v1::JOB_STATE_RUNNING);
      r.wanted.set_started_unix_ms(NowUnixMs());
      r.wanted.set_stage("outdoor");
      v1::JobEvent event;
      event.mutable_started()->set_backend(r.info.backend());
      const absl::Status stored = Store(r, event);
      if (stored.ok()) {
        spdlog::info("job {} running (\"{}\")", r.info.id(), LogSafe(r.info.name()));
        return true;
      }
      // Not started: a job runs only once its running state is stored
      r.wanted = r.info;
      if (attempt == 0) {
        spdlog::error(
            "job {}: cannot start, its running state cannot be stored ({}); trying "
            "again every second",
            r.info.id(), std::string(stored.message()));
      }
    }
    if (shutting_down_) return false;  // stays queued, and runs after the next start
    std::this_thread::sleep_for(std::chrono::seconds(1));
  }
}

void JobManager::RunStarted(Record& r) {
  const auto start = std::chrono::steady_clock::now();
  const auto cancelled = [&] { return r.cancel_requested.load() || interrupted_.load(); };
  const auto stopped_state = [&] {
    return r.cancel_requested.load() ? v1::JOB_STATE_CANCELLED : v1::JOB_STATE_INTERRUPTED;
  };
  const auto fail = [&](const std::string& error) {
    std::lock_guard lock(r.mutex);
    (void)Finish(r, cancelled() ? stopped_state() : v1::JOB_STATE_FAILED, nullptr,
                 cancelled() ? "" : error, /*retry=*/true);
  };

  // The job as submitted, read back from the store; its scene is needed only built
  absl::StatusOr<PreparedJob> prepared = absl::InternalError("not prepared");
  {
    absl::StatusOr<v1::Job> job = store_.LoadJob(r.info.id());
    if (!job.ok()) return fail(absl::StrCat("cannot read the job: ", job.status().message()));
    prepared = PrepareJob(*job, "");
  }
  if (!prepared.ok()) return fail(std::string(prepared.status().message()));
  prepared->job.clear_scene();
  const std::string key = OutdoorMatrixKey(prepared->scene, prepared->job.sampling());

  // The outdoor matrix: cached, being computed by another task, or traced here
  {
    std::lock_guard lock(r.mutex);
    v1::JobEvent event;
    event.mutable_stage()->set_name("outdoor");
    event.mutable_stage()->set_cached(cache_.Contains(key));
    Report(r, event);
  }
  const auto outdoor_start = std::chrono::steady_clock::now();
  absl::StatusOr<OutdoorCache::Lookup> lookup = cache_.GetOrCompute(
      key,
      [&]() -> absl::StatusOr<OutdoorMatrix> {
        return ComputeOutdoorMatrix(prepared->scene, prepared->job.sampling(), cancelled);
      },
      cancelled);
  const double outdoor_seconds = SecondsSince(outdoor_start);
  if (!lookup.ok()) return fail(absl::StrCat("outdoor stage: ", lookup.status().message()));
  {
    std::lock_guard lock(r.mutex);
    r.wanted.set_outdoor_reused(!lookup->computed);
    r.wanted.set_outdoor_seconds(outdoor_seconds);
    Report(r, std::nullopt);
    spdlog::info("job {}: outdoor matrix {} in {:.3f} s", r.info.id(),
                 lookup->computed ? "traced" : "reused from the cache", outdoor_seconds);
  }
  if (!lookup->computed && !r.info.site_id().empty()) sites_.NoteReuse(r.info.site_id());

  // The search
  JobCallbacks callbacks;
  callbacks.stage = [&](const std::string& stage) {
    if (stage == "outdoor") return;
    std::lock_guard lock(r.mutex);
    r.wanted.set_stage(stage);
    v1::JobEvent event;
    event.mutable_stage()->set_name(stage);
    Report(r, event);
  };
  callbacks.progress = [&](const JobProgress& progress) {
    std::lock_guard lock(r.mutex);
    v1::JobEvent event;
    *event.mutable_progress() = ToProto(progress);
    *r.wanted.mutable_progress() = event.progress();
    Report(r, event, /*durable=*/false);
  };
  callbacks.cancelled = cancelled;
  absl::StatusOr<v1::JobResult> result = RunJob(*prepared, lookup->matrix.get(), callbacks);
  if (!result.ok()) return fail(std::string(result.status().message()));

  v1::Timings& timings = *result->mutable_timings();
  timings.set_outdoor_seconds(lookup->computed ? lookup->matrix->wall_seconds : 0);
  timings.set_total_seconds(SecondsSince(start));
  std::lock_guard lock(r.mutex);
  (void)Finish(r, result->stop_reason() == "cancelled" ? stopped_state() : v1::JOB_STATE_SUCCEEDED,
               &*result, "", /*retry=*/true);
}

absl::Status JobManager::Finish(Record& r, v1::JobState state, const v1::JobResult* result,
                                const std::string& error, bool retry) {
  const v1::JobInfo before = r.wanted;
  r.wanted.set_state(state);
  r.wanted.set_stage("done");
  r.wanted.set_finished_unix_ms(NowUnixMs());
  r.wanted.set_queue_position(0);
  if (result) *r.wanted.mutable_result() = *result;
  r.wanted.set_error(error);
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
      event.set_failed(r.wanted.error());
  }
  event.set_sequence(r.info.last_sequence() + 1);
  event.set_time_unix_ms(r.wanted.finished_unix_ms());
  r.wanted.set_last_sequence(event.sequence());
  r.end = std::move(event);
  const absl::Status stored = StoreEnd(r);
  if (stored.ok()) return stored;
  if (!retry) {
    r.wanted = before;
    r.end.reset();
    return stored;
  }
  spdlog::error(
      "job {}: it ended ({}) but the store does not take its final state ({}); it "
      "shows as it was until stored, trying again every second",
      r.info.id(), v1::JobState_Name(state), std::string(stored.message()));
  {
    std::lock_guard lock(waiting_mutex_);
    std::lock_guard jobs_lock(mutex_);
    if (auto it = jobs_.find(r.info.id()); it != jobs_.end()) waiting_.push_back(it->second);
  }
  return stored;
}

absl::Status JobManager::StoreEnd(Record& r) {
  if (absl::Status s = store_.FinishJob(r.wanted, *r.end); !s.ok()) return s;
  Ended(r);
  return absl::OkStatus();
}

void JobManager::Ended(Record& r) {
  r.info = r.wanted;
  r.events.push_back(*std::move(r.end));
  r.end.reset();
  TrimEvents(r);
  r.changed.notify_all();
  if (!r.weather_path.empty()) weather_.Unref(r.weather_path);
  r.weather_path.clear();
  uploads_.Release(r.owner, r.info.upload_bytes());
  {
    std::lock_guard lock(mutex_);
    if (auto it = active_keys_.find(r.info.outdoor_key()); it != active_keys_.end()) {
      active_keys_.erase(it);
    }
  }
  const v1::JobResult* result = r.info.has_result() ? &r.info.result() : nullptr;
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
  switch (r.info.state()) {
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
      spdlog::warn("job {} failed: {}", id, LogSafe(r.info.error()));
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

void JobManager::TrimEvents(Record& r) {
  if (!IsTerminal(r.info.state()) || r.watchers > 0) return;
  while (r.events.size() > 1) r.events.pop_front();
}

void JobManager::Commit() {
  std::unique_lock lock(waiting_mutex_);
  while (!stop_committer_) {
    waiting_changed_.wait_for(lock, std::chrono::seconds(1));
    std::vector<std::shared_ptr<Record>> waiting = waiting_;
    lock.unlock();
    std::vector<std::shared_ptr<Record>> stored;
    for (const auto& r : waiting) {
      std::lock_guard record_lock(r->mutex);
      if (!r->end || StoreEnd(*r).ok()) stored.push_back(r);
    }
    lock.lock();
    std::erase_if(waiting_, [&](const auto& r) {
      return std::find(stored.begin(), stored.end(), r) != stored.end();
    });
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
  if (IsTerminal(r->wanted.state())) return InfoOf(*r, caller);  // ended, or its end stored
  if (r->info.state() == v1::JOB_STATE_QUEUED && queue_.Position(id) >= 0) {
    // A waiting job is cancelled at once, once that is stored
    if (absl::Status s = Finish(*r, v1::JOB_STATE_CANCELLED, nullptr, "", /*retry=*/false);
        !s.ok()) {
      return s;
    }
    queue_.Remove(id);
    spdlog::info("job {}: cancelled by {} while queued", id, caller.name);
    return InfoOf(*r, caller);
  }
  r->cancel_requested = true;
  spdlog::info("job {}: cancel requested by {}; it stops at its next checkpoint", id, caller.name);
  return InfoOf(*r, caller);
}

bool JobManager::UsesKey(const std::string& key) const {
  std::lock_guard lock(mutex_);
  return active_keys_.contains(key);
}

absl::Status JobManager::Watch(const std::string& id, const Caller& caller,
                               const std::function<bool(const v1::JobEvent&)>& write,
                               const std::function<bool()>& client_gone) {
  std::shared_ptr<Record> r = Find(id, caller);
  if (!r) return NoJob(id);
  {
    std::lock_guard lock(r->mutex);
    ++r->watchers;
  }
  absl::Cleanup unwatch = [&] {
    std::lock_guard lock(r->mutex);
    --r->watchers;
    TrimEvents(*r);
  };
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

  // The final states still waiting to be stored: one last try each
  {
    std::lock_guard lock(waiting_mutex_);
    stop_committer_ = true;
  }
  waiting_changed_.notify_all();
  if (committer_.joinable()) committer_.join();
  for (const auto& r : waiting_) {
    std::lock_guard lock(r->mutex);
    if (!r->end) continue;
    if (absl::Status s = StoreEnd(*r); !s.ok()) {
      spdlog::error("job {}: its final state ({}) could not be stored ({}); the store keeps it {}",
                    r->info.id(), v1::JobState_Name(r->wanted.state()), std::string(s.message()),
                    r->info.state() == v1::JOB_STATE_RUNNING
                        ? "running, so the next start marks it failed and it does not run again"
                        : "queued");
    }
  }
  waiting_.clear();
  closing_ = true;
  std::lock_guard lock(mutex_);
  for (auto& [id, r] : jobs_) r->changed.notify_all();
}

}  // namespace fenestra
