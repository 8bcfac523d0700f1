#pragma once

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <type_traits>
#include <vector>

#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "fenestra/v1/daemon.pb.h"
#include "fenestra/v1/service.pb.h"
#include "server/data_dir.h"
#include "server/heavy_requests.h"
#include "server/outdoor_cache.h"
#include "server/scheduler.h"
#include "server/site_manager.h"
#include "server/store/store.h"
#include "server/users.h"
#include "server/weather_cache.h"

namespace fenestra {

// True for SUCCEEDED, FAILED, CANCELLED and INTERRUPTED.
bool IsTerminal(v1::JobState state);

// The jobs: validated and stored at submission, claimed from the store by a replica's
// workers (the outdoor matrix from the cache or traced, then RunJob), their events kept
// in the store, from which any replica answers Get, List and Watch. A state is shown only
// once it is stored: a job starts only when its running state is stored, and a final
// state the store refuses (a full disk) is tried again every second until it is stored,
// so a job that ended never runs again. A job runs under its claim's lease: once another
// replica took it over (this one stopped renewing), this one's writes are refused and it
// stops. A job taken over goes on from its last checkpoint. Each job belongs to the user
// who submitted it: to everyone else (administrators aside) it does not exist, and its id
// answers NotFound exactly as an unknown id.
class JobManager {
 public:
  // `data_dir`: the SQLite store's folder, asked for room before a job is stored; null
  // with a PostgreSQL store.
  JobManager(const v1::DaemonConfig& config, const DataDir* data_dir, Store& store,
             OutdoorCache& cache, SiteManager& sites, HeavyRequests& heavy, Scheduler& scheduler);
  ~JobManager();

  // Submits a job of `caller` (see JobService.Submit).
  absl::StatusOr<v1::JobInfo> Submit(const v1::SubmitJobRequest& request, const Caller& caller);
  // A job with its result; NotFound when unknown or not the caller's.
  absl::StatusOr<v1::JobInfo> Get(const std::string& id, const Caller& caller);
  // The caller's jobs (an administrator's: all), newest first, results left out; `state`
  // UNSPECIFIED = all; `limit` 0 = 100.
  absl::StatusOr<std::vector<v1::JobInfo>> List(v1::JobState state, int limit,
                                                const Caller& caller);
  // See JobService.Cancel; NotFound when unknown or not the caller's.
  absl::StatusOr<v1::JobInfo> Cancel(const std::string& id, const Caller& caller);
  // Forgets an ended job (JobService.Delete): FailedPrecondition while it is queued or
  // running, NotFound when unknown or another user's.
  absl::Status Delete(const std::string& id, const Caller& caller);
  // Sends a snapshot, then every later event until the job ends, `write` fails or
  // `client_gone` turns true; a job run by another replica too (its events come from the
  // store as they are stored). NotFound when unknown or not the caller's; Unavailable when
  // the daemon stops before the job ends. The stream rides out a store that cannot be
  // reached for a while.
  absl::Status Watch(const std::string& id, const Caller& caller,
                     const std::function<bool(const v1::JobEvent&)>& write,
                     const std::function<bool()>& client_gone);

  // Runs a claimed job to its end (a Scheduler worker's task).
  void Run(std::shared_ptr<Scheduler::Held> held);

  // The shutdown sequence, once the scheduler takes no new work: refuse new jobs; let
  // running jobs go on for up to `grace_seconds`, then stop them at their next checkpoint
  // (INTERRUPTED; with a shared store, handed back instead, so another replica takes them
  // over from their checkpoint); join the workers; store the final states still waiting;
  // end the watch streams. Queued jobs stay queued in the store.
  void Shutdown(double grace_seconds);

 private:
  // A job this replica runs.
  struct Record {
    std::mutex mutex;
    std::shared_ptr<Scheduler::Held> held;  // its claim, renewed while held
    const Lease& lease() const { return held->claim.lease; }
    v1::JobInfo info;                 // as stored
    v1::JobInfo wanted;               // `info` with the changes not stored yet
    std::optional<v1::JobEvent> end;  // the final event, while its storing waits
    std::string weather;              // the job's weather file, released at its end
    bool store_failing = false;       // the last Report failed (logged once)
    // The checkpoint to store with the next progress; the step's checkpoint until its
    // progress comes; when a step was last stored
    std::optional<std::string> checkpoint;
    const v1::SearchCheckpoint* step_checkpoint = nullptr;
    std::chrono::steady_clock::time_point step_stored{};
    // A job taken over: the checkpoint it goes on from
    std::optional<v1::SearchCheckpoint> resume;
  };
  // What Admit found: the job as it is stored (the default backend filled in, its weather
  // file not yet), the new job's info (owner, name, site, outdoor key, backend, upload
  // size), its site if any, and, for the log, its budget and indoor sampling.
  struct Admission {
    v1::Job job;
    v1::JobInfo info;
    std::optional<SiteManager::ForJob> site;
    int max_evaluations = 0;
    int64_t indoor_paths_per_sensor = 0;
  };
  // Turns `info` into a job's end in `state` and returns its final event; FAILED: `error`
  // is why (its message and code; OK otherwise).
  static v1::JobEvent EndOf(v1::JobInfo& info, v1::JobState state, const v1::JobResult* result,
                            const absl::Status& error);
  // Submit's checks before anything is stored: the request (CheckJobRequest), a GPU for a
  // "cuda" job (FailedPrecondition naming the field that asked for it), the caller's site,
  // where the weather comes from, the job's match with its site. The scene built for
  // them is dropped on return.
  absl::StatusOr<Admission> Admit(const v1::SubmitJobRequest& request, const Caller& caller);
  // The stored job `id` if `caller` may see it; NotFound otherwise.
  absl::StatusOr<v1::JobInfo> Find(const std::string& id, const Caller& caller);
  // Stores `wanted` and `event` (numbered after the last stored event; none: the info
  // alone) in one transaction; once stored they are shown. `durable` = false for progress.
  // Nothing is shown on failure, and `wanted` keeps its changes for the next store. A
  // refused fence marks the claim lost. (Record mutex held.)
  absl::Status Save(Record& record, std::optional<v1::JobEvent> event = std::nullopt,
                    bool durable = true);
  // Save for what a running job reports (stage, outdoor matrix, progress): a failure is
  // logged, the first of a run of them, and the job goes on.
  void Report(Record& record, std::optional<v1::JobEvent> event, bool durable = true);
  // Ends a job (record mutex held): final state, time and event (FAILED: `error`, its code
  // kept in JobInfo.error_code), stored; once stored, logged and the weather file's
  // reference dropped. A failed store is tried again every second by the committer thread,
  // unless the claim was lost.
  void Finish(Record& record, v1::JobState state, const v1::JobResult* result,
              const absl::Status& error);
  // Stores a waiting final state (record mutex held); on success logs it (Ended).
  absl::Status StoreEnd(Record& record);
  void Ended(Record& record);
  // The committer thread: stores the waiting final states every second until `stop`.
  void Commit();
  // A job taken over: its last checkpoint, if it has one that parses.
  std::optional<v1::SearchCheckpoint> LastCheckpoint(const std::string& id);
  // Stores a claimed job's running state; while the store fails, tries again every second
  // until the claim is lost or the daemon stops. True when the job may run.
  bool Start(Record& record);
  // Runs a started job to its end.
  void RunStarted(Record& record);
  // step() (Prepare or Outdoor), and while it fails because a shared store cannot be
  // reached (PostgreSQL restarting, say), again once the store answers, up to
  // kStoreAttempts times; `stopped` ends the wait.
  template <typename Step>
  std::invoke_result_t<Step> WhileStoreAway(const std::string& id,
                                            const std::function<bool()>& stopped, Step step);
  // A job whose stored record does not parse (`unreadable`): moved to the quarantine table,
  // and the run ends without it.
  void Quarantine(Record& record, const absl::Status& unreadable);
  // The job as submitted, read back from the store, with its weather file parsed, its sky
  // matrix (both from weather_ when held there) and its scene built (left out of the
  // message). When its record does not parse, the store's DataLoss with the payload
  // kUnparsableRecordUrl (IsUnparsableRecord).
  absl::StatusOr<PreparedJob> Prepare(Record& record);
  // What RunJob reports, stored as the record's events (and checkpoints).
  JobCallbacks Callbacks(Record& record);
  // The job's outdoor matrix: cached, being computed by another task, or traced here;
  // reported as the "outdoor" stage.
  absl::StatusOr<OutdoorCache::Lookup> Outdoor(Record& record, const PreparedJob& prepared,
                                               const std::function<bool()>& cancelled);

  const v1::DaemonConfig config_;
  const DataDir* const data_dir_;
  Store& store_;
  OutdoorCache& cache_;
  WeatherCache weather_;
  SiteManager& sites_;
  HeavyRequests& heavy_;
  Scheduler& scheduler_;
  std::atomic<bool> shutting_down_{false};
  std::atomic<bool> interrupted_{false};
  std::atomic<bool> closing_{false};
  // Final states waiting to be stored, and the thread that stores them
  std::mutex waiting_mutex_;
  std::condition_variable waiting_changed_;
  std::vector<std::shared_ptr<Record>> waiting_;
  bool stop_committer_ = false;
  std::thread committer_;
};

}  // namespace fenestra
