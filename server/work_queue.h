#pragma once

#include <condition_variable>
#include <deque>
#include <functional>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "absl/status/status.h"

namespace fenestra {

// A FIFO of named tasks run by a fixed set of worker threads. Jobs count against a bound
// on waiting tasks; other tasks (site computations) do not. Thread-safe.
class WorkQueue {
 public:
  // Starts `workers` threads; at most `max_queued_jobs` job tasks may wait.
  WorkQueue(int workers, int max_queued_jobs);
  // Stops taking tasks and joins the workers (see Stop).
  ~WorkQueue();
  WorkQueue(const WorkQueue&) = delete;
  WorkQueue& operator=(const WorkQueue&) = delete;

  // Appends a task. ResourceExhausted when `is_job` and max_queued_jobs job tasks already
  // wait, unless `force` (re-queueing after a restart); FailedPrecondition after Stop.
  absl::Status Push(const std::string& id, std::function<void()> task, bool is_job = true,
                    bool force = false);
  // Removes a waiting task; false when it is not waiting (running, done or unknown).
  bool Remove(const std::string& id);
  // Job tasks ahead of a waiting task [count], or -1 when it is not waiting.
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
    std::function<void()> run;
    bool is_job;
  };
  void Work();

  const int max_queued_jobs_;
  mutable std::mutex mutex_;
  std::condition_variable wake_;
  std::condition_variable idle_;
  std::deque<Task> tasks_;
  int running_ = 0;
  bool stopped_ = false;
  std::vector<std::thread> workers_;
};

}  // namespace fenestra
