#pragma once

#include <condition_variable>
#include <cstdint>
#include <deque>
#include <functional>
#include <map>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "absl/status/status.h"

namespace fenestra {

// Named tasks of users, run by a fixed set of worker threads in turn across users: a free
// worker takes the oldest waiting task of the user served least recently (a user never
// served first), so one user's many tasks do not hold back another's. Job tasks count
// against bounds on waiting jobs, in all and per user; other tasks (site computations)
// do not. Thread-safe.
class WorkQueue {
 public:
  // Starts `workers` threads; at most `max_queued_jobs` job tasks may wait, and
  // `max_queued_jobs_per_user` of one user.
  WorkQueue(int workers, int max_queued_jobs, int max_queued_jobs_per_user);
  // Stops taking tasks and joins the workers (see Stop).
  ~WorkQueue();
  WorkQueue(const WorkQueue&) = delete;
  WorkQueue& operator=(const WorkQueue&) = delete;

  // Appends a task of user `owner`. ResourceExhausted when `is_job` and a bound on
  // waiting jobs is reached (the message names the limit), unless `force` (re-queueing
  // after a restart); FailedPrecondition after Stop.
  absl::Status Push(const std::string& id, const std::string& owner, std::function<void()> task,
                    bool is_job = true, bool force = false);
  // Removes a waiting task; false when it is not waiting (running, done or unknown).
  bool Remove(const std::string& id);
  // Job tasks that workers will take before a waiting task, as the queue stands [count],
  // or -1 when it is not waiting.
  int Position(const std::string& id) const;
  // Job tasks waiting [count].
  int QueuedJobs() const;
  // Tasks running now [count].
  int Running() const;

  // Workers take no new task; waiting tasks stay (and are dropped by the destructor).
  void Stop();
  // Waits until no task runs, or `timeout_seconds` passed; true when none runs.
  bool WaitIdle(double timeout_seconds);
  // Stop, then waits for the running tasks and joins the workers.
  void Join();

 private:
  struct Task {
    std::string id;
    std::string owner;
    std::function<void()> run;
    bool is_job;
  };
  // Indices into tasks_ in the order workers would take them if nothing else arrived
  // (mutex_ held).
  std::vector<size_t> TakingOrder() const;
  void Work();

  const int max_queued_jobs_;
  const int max_queued_jobs_per_user_;
  mutable std::mutex mutex_;
  std::condition_variable wake_;
  std::condition_variable idle_;
  std::deque<Task> tasks_;  // oldest first
  // When each user's task was last taken, in takes counted from 1 (0 = never)
  std::map<std::string, uint64_t> last_taken_;
  uint64_t takes_ = 0;
  int running_ = 0;
  bool stopped_ = false;
  std::vector<std::thread> workers_;
};

}  // namespace fenestra
