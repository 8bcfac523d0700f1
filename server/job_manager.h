#pragma once

#include <atomic>
#include <condition_variable>
#include <deque>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <set>
#include <string>
#include <thread>
#include <vector>

#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "fenestra/v1/daemon.pb.h"
#include "fenestra/v1/service.pb.h"
#include "server/data_dir.h"
#include "server/heavy_requests.h"
#include "server/job_store.h"
#include "server/outdoor_cache.h"
#include "server/site_manager.h"
#include "server/upload_quota.h"
#include "server/users.h"
#include "server/work_queue.h"

namespace fenestra {

// True for SUCCEEDED, FAILED, CANCELLED and INTERRUPTED.
bool IsTerminal(v1::JobState state);

// The jobs: validated and stored at submission, run by work queue tasks (outdoor matrix
// from the cache or traced, then RunJob), their events kept in the store and fanned out to
// watchers. A state is shown (to Get, List and watchers) only once it is stored: a job
// starts only when its running state is stored, and a final state the store refuses (a
// full disk) is tried again every second until it is stored, so a job that ended never
// runs again. In memory a job keeps its JobInfo and latest events; its submitted form
// (scene included) stays in the store. Each job belongs to the user who submitted it: to
// everyone else (administrators aside) it does not exist, and its id answers NotFound
// exactly as an unknown id.
class JobManager {
 public:
  JobManager(const v1::DaemonConfig& config, const DataDir& data_dir, JobStore& store,
             OutdoorCache& cache, UploadStore& weather, WorkQueue& queue, SiteManager& sites,
             HeavyRequests& heavy, UploadQuota& uploads);
  ~JobManager();

  // Loads the stored jobs (those that do not parse are quarantined and logged): those that
  // were running are marked failed ("daemon stopped while running"), queued ones are queued
  // again in their order and count their weather files' references.
  absl::Status Recover();

  // Submits a job of `caller` (see JobService.Submit).
  absl::StatusOr<v1::JobInfo> Submit(const v1::SubmitJobRequest& request, const Caller& caller);
  // A job with its result; NotFound when unknown or not the caller's.
  absl::StatusOr<v1::JobInfo> Get(const std::string& id, const Caller& caller) const;
  // The caller's jobs (an administrator's: all), newest first, results left out; `state`
  // UNSPECIFIED = all; `limit` 0 = 100.
  std::vector<v1::JobInfo> List(v1::JobState state, int limit, const Caller& caller) const;
  // See JobService.Cancel; NotFound when unknown or not the caller's.
  absl::StatusOr<v1::JobInfo> Cancel(const std::string& id, const Caller& caller);
  // Sends a snapshot, then every later event until the job ends, `write` fails or
  // `client_gone` turns true. NotFound when unknown or not the caller's; Unavailable when
  // the daemon stops before the job ends.
  absl::Status Watch(const std::string& id, const Caller& caller,
                     const std::function<bool(const v1::JobEvent&)>& write,
                     const std::function<bool()>& client_gone);
  // Whether a queued or running job uses the outdoor matrix with `key`.
  bool UsesKey(const std::string& key) const;

  // The shutdown sequence: refuse new jobs; let running jobs go on for up to
  // `grace_seconds`, then stop them at their next checkpoint (INTERRUPTED); join the
  // workers; store the final states still waiting; end the watch streams. Queued jobs stay
  // queued in the store.
  void Shutdown(double grace_seconds);

 private:
  struct Record {
    mutable std::mutex mutex;
    std::condition_variable changed;
    std::string owner;   // info.owner, set before the record is shared and never changed
    v1::JobInfo info;    // as stored: what Get, List and Watch show
    v1::JobInfo wanted;  // `info` with the changes not stored yet
    std::optional<v1::JobEvent> end;  // the final event, while its storing waits
    std::string weather_path;         // referenced while the job is queued or running
    std::deque<v1::JobEvent> events;  // the latest stored events, for watchers
    std::atomic<bool> cancel_requested{false};
    bool store_failing = false;  // the last Report failed (logged once)
    int watchers = 0;            // Watch streams open
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
  // Submit's checks before anything is stored: the request (CheckJobRequest), the caller's
  // site, where the weather comes from, the job's match with its site. The scene built for
  // them is dropped on return.
  absl::StatusOr<Admission> Admit(const v1::SubmitJobRequest& request, const Caller& caller) const;
  // A reference to the job's weather file: its upload stored, or its site's.
  absl::StatusOr<std::string> TakeWeather(const v1::SubmitJobRequest& request,
                                          const std::optional<SiteManager::ForJob>& site,
                                          const Caller& caller);
  // Stores a new job with its queued event and queues it; its info with its id, as
  // `caller` may see it.
  absl::StatusOr<v1::JobInfo> StoreAndQueue(const v1::Job& job, v1::JobInfo info,
                                            const std::string& weather_path, const Caller& caller);
  // The job `id` if `caller` may see it, else null.
  std::shared_ptr<Record> Find(const std::string& id, const Caller& caller) const;
  // Stores `wanted` and `event` (numbered after the last stored event; none: the info
  // alone) in one transaction; once stored they are shown. `durable` = false for progress.
  // Nothing is shown on failure, and `wanted` keeps its changes for the next store.
  // (Record mutex held.)
  absl::Status Store(Record& record, std::optional<v1::JobEvent> event = std::nullopt,
                     bool durable = true);
  // Store for what a running job reports (stage, outdoor matrix, progress): a failure is
  // logged, the first of a run of them, and the job goes on.
  void Report(Record& record, std::optional<v1::JobEvent> event, bool durable = true);
  // Ends a job (record mutex held): final state, time and event, stored; once stored, shown
  // and logged, the weather file's reference dropped and its upload no longer counted
  // against its owner. A failed store is tried again every second by the committer thread
  // (`retry`), or returned with nothing changed.
  absl::Status Finish(Record& record, v1::JobState state, const v1::JobResult* result,
                      const std::string& error, bool retry);
  // Stores a waiting final state (record mutex held); on success shows it (Ended).
  absl::Status StoreEnd(Record& record);
  void Ended(Record& record);
  // An ended job no one watches keeps only its final event (record mutex held).
  void TrimEvents(Record& record);
  // The committer thread: stores the waiting final states every second until `stop`.
  void Commit();
  // A job's info with its queue position, as `caller` may see it (its mutex held).
  v1::JobInfo InfoOf(const Record& record, const Caller& caller) const;
  // The work queue task of a job.
  void Run(const std::shared_ptr<Record>& record);
  // Stores a queued job's running state; while the store fails, tries again every second
  // until the job is cancelled or the daemon stops. True when the job may run.
  bool Start(Record& record);
  // Runs a started job to its end.
  void RunStarted(Record& record);
  absl::Status Queue(const std::shared_ptr<Record>& record, bool force);

  const v1::DaemonConfig config_;
  const DataDir& data_dir_;
  JobStore& store_;
  OutdoorCache& cache_;
  UploadStore& weather_;
  WorkQueue& queue_;
  SiteManager& sites_;
  HeavyRequests& heavy_;
  UploadQuota& uploads_;
  std::atomic<bool> shutting_down_{false};
  std::atomic<bool> interrupted_{false};
  std::atomic<bool> closing_{false};
  mutable std::mutex mutex_;
  std::vector<std::string> order_;  // oldest first
  std::map<std::string, std::shared_ptr<Record>> jobs_;
  std::multiset<std::string> active_keys_;  // outdoor keys of queued and running jobs
  // Final states waiting to be stored, and the thread that stores them
  std::mutex waiting_mutex_;
  std::condition_variable waiting_changed_;
  std::vector<std::shared_ptr<Record>> waiting_;
  bool stop_committer_ = false;
  std::thread committer_;
};

}  // namespace fenestra
