#include "server/work_queue.h"

#include <algorithm>
#include <chrono>

#include "absl/strings/str_cat.h"

namespace fenestra {

WorkQueue::WorkQueue(int workers, int max_queued_jobs) : max_queued_jobs_(max_queued_jobs) {
  for (int i = 0; i < std::max(1, workers); ++i) workers_.emplace_back([this] { Work(); });
}

WorkQueue::~WorkQueue() { Join(); }

absl::Status WorkQueue::Push(const std::string& id, std::function<void()> task, bool is_job,
                             bool force) {
  {
    std::lock_guard lock(mutex_);
    if (stopped_) return absl::FailedPreconditionError("the work queue is stopped");
    if (is_job && !force) {
      const int queued = static_cast<int>(
          std::count_if(tasks_.begin(), tasks_.end(), [](const Task& t) { return t.is_job; }));
      if (queued >= max_queued_jobs_) {
        return absl::ResourceExhaustedError(absl::StrCat(
            "the job queue is full: ", queued, " jobs wait (this server's limit max_queued_jobs = ",
            max_queued_jobs_, "); try again later"));
      }
    }
    tasks_.push_back(Task{id, std::move(task), is_job});
  }
  wake_.notify_one();
  return absl::OkStatus();
}

bool WorkQueue::Remove(const std::string& id) {
  std::lock_guard lock(mutex_);
  auto it = std::find_if(tasks_.begin(), tasks_.end(), [&](const Task& t) { return t.id == id; });
  if (it == tasks_.end()) return false;
  tasks_.erase(it);
  return true;
}

int WorkQueue::Position(const std::string& id) const {
  std::lock_guard lock(mutex_);
  int ahead = 0;
  for (const Task& t : tasks_) {
    if (t.id == id) return ahead;
    if (t.is_job) ++ahead;
  }
  return -1;
}

int WorkQueue::QueuedJobs() const {
  std::lock_guard lock(mutex_);
  return static_cast<int>(
      std::count_if(tasks_.begin(), tasks_.end(), [](const Task& t) { return t.is_job; }));
}

int WorkQueue::Running() const {
  std::lock_guard lock(mutex_);
  return running_;
}

void WorkQueue::Stop() {
  {
    std::lock_guard lock(mutex_);
    stopped_ = true;
  }
  wake_.notify_all();
}

bool WorkQueue::WaitIdle(double timeout_seconds) {
  std::unique_lock lock(mutex_);
  return idle_.wait_for(lock, std::chrono::duration<double>(timeout_seconds),
                        [&] { return running_ == 0; });
}

void WorkQueue::Join() {
  Stop();
  for (std::thread& worker : workers_) {
    if (worker.joinable()) worker.join();
  }
  workers_.clear();
}

void WorkQueue::Work() {
  while (true) {
    Task task;
    {
      std::unique_lock lock(mutex_);
      wake_.wait(lock, [&] { return stopped_ || !tasks_.empty(); });
      if (stopped_) return;
      task = std::move(tasks_.front());
      tasks_.pop_front();
      ++running_;
    }
    task.run();
    {
      std::lock_guard lock(mutex_);
      --running_;
    }
    idle_.notify_all();
  }
}

}  // namespace fenestra
