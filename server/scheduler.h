#pragma once

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "server/outdoor_cache.h"
#include "server/store/store.h"

namespace fenestra {

// A replica's workers: each claims the next job or site computation from the store
// (Store::ClaimWork: taken-over jobs first, then in turn across users, then jobs whose
// outdoor matrix this replica holds in memory, then the oldest), runs it, and claims
// again. An idle worker waits for a change in the store (a submission, a registration,
// a job that ended: Database::WaitForChange, which PostgreSQL's NOTIFY reaches from every
// replica) or polls after `poll`, which is also how work whose replica stopped is found
// once its lease expired. A renewer thread renews the leases of what this replica holds
// every third of the lease and tells the runners when one was lost or a cancel was
// asked for. Thread-safe.
class Scheduler {
 public:
  // What this replica holds: the claim, and what the renewer learned since.
  struct Held {
    Claim claim;
    std::atomic<bool> lost{false};              // another claim took it
    std::atomic<bool> cancel_requested{false};  // a job asked to cancel, from any replica
    std::atomic<bool> done{false};              // its end is stored: no lease to renew
  };
  using Runner = std::function<void(std::shared_ptr<Held>)>;

  // `lease_seconds`: how long a claim lasts unrenewed; `poll_seconds`: an idle worker's
  // longest wait.
  Scheduler(Store& store, OutdoorCache& cache, std::string replica, int workers,
            double lease_seconds, double poll_seconds);
  ~Scheduler();
  Scheduler(const Scheduler&) = delete;
  Scheduler& operator=(const Scheduler&) = delete;

  // Starts the workers and the renewer; `run_job` and `run_site` run a claim to its end.
  void Start(Runner run_job, Runner run_site);
  // Workers take no new work; running work goes on.
  void Stop();
  // Waits until no work runs, or `timeout_seconds` passed; true when none runs.
  bool WaitIdle(double timeout_seconds);
  // Stop, then waits for the running work and joins the threads.
  void Join();
  // Work running now [count].
  int Running() const;

  // Keeps a claim held (its lease renewed, its id not claimed by this replica) while the
  // returned pointer lives: the workers hold what they run, and a runner may hold on
  // after (a job end waiting to be stored).
  std::shared_ptr<Held> Hold(const Claim& claim);
  // What this replica holds of `id`, if anything.
  std::shared_ptr<Held> Find(const std::string& id) const;

  const std::string& replica() const { return replica_; }
  int64_t lease_ms() const { return lease_ms_; }

 private:
  void Work(int worker);
  void Renew();
  // The claims held now (mutex_ held), expired entries dropped.
  std::vector<std::shared_ptr<Held>> HeldNow() const;
  // Logs a failed claim once per run of failures.
  void NoteClaimFailure(const absl::Status& status, const std::string& candidate);

  Store& store_;
  OutdoorCache& cache_;
  const std::string replica_;
  const int workers_;
  const int64_t lease_ms_;
  const std::chrono::milliseconds poll_;
  Runner run_job_, run_site_;
  mutable std::mutex mutex_;
  std::condition_variable idle_;
  std::condition_variable stop_cv_;
  mutable std::map<std::string, std::weak_ptr<Held>> held_;
  int running_ = 0;
  bool stopped_ = false;
  bool joined_ = false;
  std::string failing_;  // what the last failed claim was for ("" = none failing)
  std::vector<std::thread> threads_;
};

}  // namespace fenestra
