// JobManager: running a claimed job (its store writes, outdoor matrix, search and
// checkpoints), its end, and the shutdown.
#include <spdlog/spdlog.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <thread>
#include <utility>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_join.h"
#include "core/common/seconds.h"
#include "core/optimize/job.h"
#include "server/job_manager.h"
#include "server/log_safe.h"

namespace fenestra {
namespace {

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

// How often a job that met the store out of reach asks whether it answers again, and how
// many times in a row one step of it may meet the store out of reach
constexpr auto kStoreRetry = std::chrono::milliseconds(250);
constexpr int kStoreAttempts = 5;

// The least time between two stored steps of a search (progress and checkpoint): steps that
// come sooner are not stored, and the next step due carries theirs. Storing each step of a
// fast search (500 steps in 0.6 s on a GPU) took as long again as the steps: the checkpoint
// holds the whole history, and was serialized and written every step.
constexpr auto kStepStoreInterval = std::chrono::milliseconds(100);

}  // namespace

// ---- Running a claimed job

absl::Status JobManager::Save(Record& r, std::optional<v1::JobEvent> event, bool durable) {
  if (event) {
    event->set_sequence(r.info.last_sequence() + 1);
    event->set_time_unix_ms(NowUnixMs());
    r.wanted.set_last_sequence(event->sequence());
  }
  bool cancel_requested = false;
  const absl::Status stored =
      store_.UpdateJob(r.lease(), r.wanted, event ? &*event : nullptr, durable, &cancel_requested,
                       r.checkpoint ? &*r.checkpoint : nullptr);
  if (!stored.ok()) {
    r.wanted.set_last_sequence(r.info.last_sequence());
    if (stored.code() == absl::StatusCode::kAborted) r.held->lost = true;
    return stored;
  }
  if (cancel_requested) r.held->cancel_requested = true;
  r.info = r.wanted;
  r.checkpoint.reset();
  return absl::OkStatus();
}

void JobManager::Report(Record& r, std::optional<v1::JobEvent> event, bool durable) {
  const absl::Status stored = Save(r, std::move(event), durable);
  if (stored.code() == absl::StatusCode::kAborted) return;  // lost: the runner stops
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

void JobManager::Run(std::shared_ptr<Scheduler::Held> held) {
  auto record = std::make_shared<Record>();
  Record& r = *record;
  r.held = std::move(held);
  const Claim& claim = r.held->claim;
  const std::string& id = claim.lease.id;
  absl::StatusOr<v1::JobInfo> info = store_.GetJob(id, /*position=*/false);
  if (!info.ok()) {
    spdlog::error("job {}: cannot be read to start ({})", id, std::string(info.status().message()));
    return;
  }
  // What the store adds for callers is not stored
  info->set_queue_position(0);
  info->clear_replica();
  info->set_cancel_requested(false);
  r.info = r.wanted = *std::move(info);
  if (claim.taken_over) {
    r.resume = LastCheckpoint(id);
    spdlog::warn("job {}: taken over from replica {}, whose lease expired (it stopped); {}", id,
                 LogSafe(claim.previous_replica),
                 r.resume ? absl::StrCat("it goes on after its last checkpoint (",
                                         r.resume->history_size(), " steps)")
                          : std::string("it starts again (no checkpoint)"));
  }
  if (Start(r)) {
    try {
      RunStarted(r);
    } catch (const std::exception& e) {
      std::lock_guard lock(r.mutex);
      Finish(r, v1::JOB_STATE_FAILED, nullptr,
             absl::InternalError(absl::StrCat("internal error: ", e.what())));
    }
    // An end waiting in the committer keeps the claim held until it is stored
    std::lock_guard lock(r.mutex);
    if (r.end) {
      std::lock_guard waiting(waiting_mutex_);
      waiting_.push_back(record);
    }
  }
  ReleaseFreeMemory();  // the scene, its BVH and the tracer's buffers
}

std::optional<v1::SearchCheckpoint> JobManager::LastCheckpoint(const std::string& id) {
  absl::StatusOr<std::optional<std::string>> bytes = store_.LoadCheckpoint(id);
  if (!bytes.ok()) {
    spdlog::warn("job {}: its checkpoint cannot be read ({}); it starts again", id,
                 std::string(bytes.status().message()));
    return std::nullopt;
  }
  if (!*bytes) return std::nullopt;
  absl::StatusOr<v1::SearchCheckpoint> checkpoint = ParseSearchCheckpoint(**bytes);
  if (!checkpoint.ok()) {
    spdlog::warn("job {}: its checkpoint is not usable ({}); it starts again", id,
                 std::string(checkpoint.status().message()));
    return std::nullopt;
  }
  return *std::move(checkpoint);
}

bool JobManager::Start(Record& r) {
  int resumed_evaluations = 0;
  if (r.resume) {
    for (const v1::Evaluation& step : r.resume->history()) resumed_evaluations += !step.cached();
  }
  for (int attempt = 0;; ++attempt) {
    {
      std::lock_guard lock(r.mutex);
      if (r.held->lost) return false;
      r.wanted.set_state(v1::JOB_STATE_RUNNING);
      if (r.wanted.started_unix_ms() == 0) r.wanted.set_started_unix_ms(NowUnixMs());
      r.wanted.set_stage("outdoor");
      v1::JobEvent event;
      event.mutable_started()->set_backend(r.info.backend());
      event.mutable_started()->set_replica(scheduler_.replica());
      event.mutable_started()->set_resumed_evaluations(resumed_evaluations);
      const absl::Status stored = Save(r, event);
      if (stored.ok()) {
        spdlog::info("job {} running (\"{}\")", r.info.id(), LogSafe(r.info.name()));
        return true;
      }
      // Not started: a job runs only once its running state is stored
      r.wanted = r.info;
      if (stored.code() == absl::StatusCode::kAborted) return false;
      if (attempt == 0) {
        spdlog::error(
            "job {}: cannot start, its running state cannot be stored ({}); trying "
            "again every second",
            r.info.id(), std::string(stored.message()));
      }
    }
    if (shutting_down_) {
      // Stays claimed until its lease ends: then it runs here after the next start, or on
      // another replica
      return false;
    }
    std::this_thread::sleep_for(std::chrono::seconds(1));
  }
}

absl::StatusOr<PreparedJob> JobManager::Prepare(Record& r) {
  absl::StatusOr<v1::Job> job = store_.LoadJob(r.info.id());
  if (!job.ok()) {
    if (job.status().code() == absl::StatusCode::kDataLoss) return job.status();
    return absl::Status(job.status().code(),
                        absl::StrCat("cannot read the job: ", job.status().message()));
  }
  r.weather = job->weather_file();
  absl::StatusOr<PreparedJob> prepared = ValidateJob(*job, "");
  if (!prepared.ok()) return prepared.status();
  absl::StatusOr<WeatherCache::Entry> weather = weather_.Get(
      r.weather, JobSkyOptions(*prepared), [&] { return store_.ReadWeather(r.weather); });
  if (!weather.ok()) return weather.status();
  prepared->weather = *weather->weather;
  prepared->sky = weather->sky;
  prepared->job.clear_scene();  // needed only built
  return prepared;
}

JobCallbacks JobManager::Callbacks(Record& r) {
  JobCallbacks callbacks;
  callbacks.stage = [this, &r](const std::string& stage) {
    if (stage == "outdoor") return;
    std::lock_guard lock(r.mutex);
    r.wanted.set_stage(stage);
    v1::JobEvent event;
    event.mutable_stage()->set_name(stage);
    Report(r, event);
  };
  // A step's checkpoint is stored with the step's progress, which follows it, once
  // kStepStoreInterval has passed since the last step stored, and for the budget's last
  // step; the final check's progress always is. So the stored progress never runs ahead of
  // the stored checkpoint.
  callbacks.checkpoint = [&r](const v1::SearchCheckpoint& checkpoint) {
    std::lock_guard lock(r.mutex);
    r.step_checkpoint = &checkpoint;
  };
  callbacks.progress = [this, &r](const JobProgress& progress) {
    std::lock_guard lock(r.mutex);
    const v1::SearchCheckpoint* checkpoint = std::exchange(r.step_checkpoint, nullptr);
    const auto now = std::chrono::steady_clock::now();
    if (!progress.final_check && now - r.step_stored < kStepStoreInterval &&
        progress.evaluations < progress.max_evaluations) {
      return;  // stored with a later step
    }
    if (checkpoint) r.checkpoint = checkpoint->SerializeAsString();
    r.step_stored = now;
    v1::JobEvent event;
    *event.mutable_progress() = ToProto(progress);
    *r.wanted.mutable_progress() = event.progress();
    Report(r, event, /*durable=*/false);
  };
  return callbacks;
}

absl::StatusOr<OutdoorCache::Lookup> JobManager::Outdoor(Record& r, const PreparedJob& prepared,
                                                         const std::function<bool()>& cancelled) {
  const std::string key = OutdoorMatrixKey(prepared.scene, prepared.job.sampling());
  {
    std::lock_guard lock(r.mutex);
    v1::JobEvent event;
    event.mutable_stage()->set_name("outdoor");
    event.mutable_stage()->set_cached(cache_.Contains(key));
    Report(r, event);
  }
  const auto start = std::chrono::steady_clock::now();
  absl::StatusOr<OutdoorCache::Lookup> lookup = cache_.GetOrCompute(
      key,
      [&]() -> absl::StatusOr<OutdoorMatrix> {
        return ComputeOutdoorMatrix(prepared.scene, prepared.job.sampling(), cancelled);
      },
      cancelled);
  if (!lookup.ok()) return lookup;
  const double seconds = SecondsSince(start);
  {
    std::lock_guard lock(r.mutex);
    r.wanted.set_outdoor_reused(!lookup->computed);
    r.wanted.set_outdoor_seconds(seconds);
    Report(r, std::nullopt);
    spdlog::info("job {}: outdoor matrix {} in {:.3f} s", r.info.id(),
                 lookup->computed ? "traced" : "reused from the cache", seconds);
  }
  if (!lookup->computed && !r.info.site_id().empty()) sites_.NoteReuse(r.info.site_id());
  return lookup;
}

template <typename Step>
std::invoke_result_t<Step> JobManager::WhileStoreAway(const std::string& id,
                                                      const std::function<bool()>& stopped,
                                                      Step step) {
  std::invoke_result_t<Step> result = step();
  for (int attempt = 1; attempt <= kStoreAttempts && store_.shared() && !result.ok() &&
                        result.status().code() == absl::StatusCode::kUnavailable;
       ++attempt) {
    spdlog::warn("job {}: the store cannot be reached; it goes on once the store answers", id);
    if (!store_.AwaitAnswer(kStoreRetry, stopped)) break;
    result = step();
  }
  return result;
}

void JobManager::Quarantine(Record& r, const absl::Status& unreadable) {
  const std::string why(unreadable.message());
  const absl::Status moved = store_.Quarantine("jobs", r.info.id(), why);
  spdlog::error("job {}: {}; {}, the daemon goes on without it", r.info.id(), why,
                moved.ok() ? "moved to the quarantine table"
                           : absl::StrCat("not moved (", moved.message(), ")"));
  r.held->done = true;
}

void JobManager::RunStarted(Record& r) {
  const auto start = std::chrono::steady_clock::now();
  Scheduler::Held& held = *r.held;
  const auto cancelled = [&] {
    return held.cancel_requested.load() || interrupted_.load() || held.lost.load();
  };
  const auto stopped_state = [&] {
    return held.cancel_requested.load() ? v1::JOB_STATE_CANCELLED : v1::JOB_STATE_INTERRUPTED;
  };
  // A run that stopped for the shutdown: a shared store hands the job to another replica
  const auto hand_back = [&] {
    if (held.lost) return true;
    if (!(interrupted_ && store_.shared() && !held.cancel_requested)) return false;
    const absl::Status released = store_.Release(Claim::Kind::kJob, r.lease());
    spdlog::info(
        "job {}: handed back for another replica to take over{}", r.info.id(),
        released.ok() ? "" : absl::StrCat(" once its lease expires (", released.message(), ")"));
    return true;
  };
  const auto fail = [&](const absl::Status& error) {
    if (cancelled() && hand_back()) return;
    std::lock_guard lock(r.mutex);
    Finish(r, cancelled() ? stopped_state() : v1::JOB_STATE_FAILED, nullptr,
           cancelled() ? absl::OkStatus() : error);
  };

  // The job as submitted, read back from the store, with its weather file
  absl::StatusOr<PreparedJob> prepared =
      WhileStoreAway(r.info.id(), cancelled, [&] { return Prepare(r); });
  if (IsUnparsableRecord(prepared.status())) {
    Quarantine(r, prepared.status());
    return;
  }
  if (!prepared.ok()) return fail(prepared.status());
  absl::StatusOr<OutdoorCache::Lookup> lookup =
      WhileStoreAway(r.info.id(), cancelled, [&] { return Outdoor(r, *prepared, cancelled); });
  if (!lookup.ok()) {
    return fail(absl::Status(lookup.status().code(),
                             absl::StrCat("outdoor stage: ", lookup.status().message())));
  }

  // The search
  JobCallbacks callbacks = Callbacks(r);
  callbacks.cancelled = cancelled;
  absl::StatusOr<v1::JobResult> result =
      RunJob(*prepared, lookup->matrix.get(), callbacks, r.resume ? &*r.resume : nullptr);
  if (r.resume && result.status().code() == absl::StatusCode::kInvalidArgument) {
    // A checkpoint this job's search does not make (another build's): from the start
    spdlog::warn("job {}: its checkpoint cannot be resumed ({}); it starts again", r.info.id(),
                 std::string(result.status().message()));
    r.resume.reset();
    result = RunJob(*prepared, lookup->matrix.get(), callbacks);
  }
  if (!result.ok()) return fail(result.status());
  if (result->stop_reason() == "cancelled" && hand_back()) return;

  v1::Timings& timings = *result->mutable_timings();
  timings.set_outdoor_seconds(lookup->computed ? lookup->matrix->wall_seconds : 0);
  timings.set_total_seconds(SecondsSince(start));
  std::lock_guard lock(r.mutex);
  Finish(r, result->stop_reason() == "cancelled" ? stopped_state() : v1::JOB_STATE_SUCCEEDED,
         &*result, absl::OkStatus());
}

void JobManager::Finish(Record& r, v1::JobState state, const v1::JobResult* result,
                        const absl::Status& error) {
  r.end = EndOf(r.wanted, state, result, error);
  const absl::Status stored = StoreEnd(r);
  if (stored.ok()) return;
  if (stored.code() == absl::StatusCode::kAborted) {
    spdlog::warn(
        "job {}: it ended ({}) here, but another replica took it over meanwhile: its "
        "end there counts",
        r.info.id(), v1::JobState_Name(state));
    r.end.reset();
    return;
  }
  spdlog::error(
      "job {}: it ended ({}) but the store does not take its final state ({}); it "
      "shows as it was until stored, trying again every second",
      r.info.id(), v1::JobState_Name(state), std::string(stored.message()));
}

absl::Status JobManager::StoreEnd(Record& r) {
  if (absl::Status s = store_.FinishJob(r.lease(), r.wanted, *r.end); !s.ok()) {
    if (s.code() == absl::StatusCode::kAborted) r.held->lost = true;
    return s;
  }
  r.held->done = true;
  Ended(r);
  return absl::OkStatus();
}

void JobManager::Ended(Record& r) {
  r.info = r.wanted;
  r.end.reset();
  store_.ReleaseWeather(r.weather);
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

void JobManager::Commit() {
  std::unique_lock lock(waiting_mutex_);
  while (!stop_committer_) {
    waiting_changed_.wait_for(lock, std::chrono::seconds(1));
    std::vector<std::shared_ptr<Record>> waiting = waiting_;
    lock.unlock();
    std::vector<std::shared_ptr<Record>> settled;
    for (const auto& r : waiting) {
      std::lock_guard record_lock(r->mutex);
      if (!r->end || r->held->lost) {
        settled.push_back(r);
        continue;
      }
      const absl::Status s = StoreEnd(*r);
      if (s.ok() || s.code() == absl::StatusCode::kAborted) settled.push_back(r);
    }
    lock.lock();
    std::erase_if(waiting_, [&](const auto& r) {
      return std::find(settled.begin(), settled.end(), r) != settled.end();
    });
  }
}

void JobManager::Shutdown(double grace_seconds) {
  shutting_down_ = true;
  sites_.BeginShutdown();
  scheduler_.Stop();
  if (scheduler_.Running() > 0) {
    spdlog::info("waiting up to {:.0f} s for {} running task(s) to finish", grace_seconds,
                 scheduler_.Running());
  }
  if (!scheduler_.WaitIdle(grace_seconds)) {
    spdlog::info("stopping the running tasks at their next checkpoint");
    interrupted_ = true;
    sites_.Interrupt();
  }
  scheduler_.Join();

  // The final states still waiting to be stored: one last try each
  {
    std::lock_guard lock(waiting_mutex_);
    stop_committer_ = true;
  }
  waiting_changed_.notify_all();
  if (committer_.joinable()) committer_.join();
  for (const auto& r : waiting_) {
    std::lock_guard lock(r->mutex);
    if (!r->end || r->held->lost) continue;
    if (absl::Status s = StoreEnd(*r); !s.ok()) {
      spdlog::error(
          "job {}: its final state ({}) could not be stored ({}); the store keeps it running, "
          "so it is taken over at the next start (or by another replica) from its last "
          "checkpoint",
          r->info.id(), v1::JobState_Name(r->wanted.state()), std::string(s.message()));
    }
  }
  waiting_.clear();
  closing_ = true;
  store_.database().WakeWaiters();
}

}  // namespace fenestra
