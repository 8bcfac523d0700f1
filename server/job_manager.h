#pragma once

#include <atomic>
#include <condition_variable>
#include <deque>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "fenestra/v1/daemon.pb.h"
#include "fenestra/v1/service.pb.h"
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
// watchers. Each job belongs to the user who submitted it: to everyone else
// (administrators aside) it does not exist, and its id answers NotFound exactly as an
// unknown id.
class JobManager {
 public:
  JobManager(const v1::DaemonConfig& config, JobStore& store, OutdoorCache& cache, WorkQueue& queue,
             SiteManager& sites, UploadQuota& uploads);

  // Loads the stored jobs: those that were running are marked failed ("daemon stopped
  // while running"), queued ones are queued again in their order.
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

  // The shutdown sequence: refuse new jobs; let running jobs go on for up to
  // `grace_seconds`, then stop them at their next checkpoint (INTERRUPTED); join the
  // workers; end the watch streams. Queued jobs stay queued in the store.
  void Shutdown(double grace_seconds);

 private:
  struct Record {
    mutable std::mutex mutex;
    std::condition_variable changed;
    std::string owner;  // info.owner, set before the record is shared and never changed
    v1::JobInfo info;
    v1::Job job;                      // as submitted, weather file resolved on the server
    std::deque<v1::JobEvent> events;  // the latest events, for watchers
    std::atomic<bool> cancel_requested{false};
  };
  // The job `id` if `caller` may see it, else null.
  std::shared_ptr<Record> Find(const std::string& id, const Caller& caller) const;
  // Numbers and records an event (the record's mutex held), and wakes the watchers.
  void Emit(Record& record, v1::JobEvent event);
  // Stores the record's JobInfo (its mutex held).
  void Save(const Record& record);
  // A job's info with its queue position, as `caller` may see it (its mutex held).
  v1::JobInfo InfoOf(const Record& record, const Caller& caller) const;
  // The work queue task of a job.
  void Run(const std::shared_ptr<Record>& record);
  // Marks a job ended (its mutex held): state, time, final event, log line; its upload
  // no longer counts against its owner.
  void Finish(Record& record, v1::JobState state, const v1::JobResult* result,
              const std::string& error);
  absl::Status Queue(const std::shared_ptr<Record>& record, bool force);

  const v1::DaemonConfig config_;
  JobStore& store_;
  OutdoorCache& cache_;
  WorkQueue& queue_;
  SiteManager& sites_;
  UploadQuota& uploads_;
  std::atomic<bool> shutting_down_{false};
  std::atomic<bool> interrupted_{false};
  std::atomic<bool> closing_{false};
  mutable std::mutex mutex_;
  std::vector<std::string> order_;  // oldest first
  std::map<std::string, std::shared_ptr<Record>> jobs_;
};

}  // namespace fenestra
