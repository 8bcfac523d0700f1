#include "server/work_queue.h"

#include <algorithm>
#include <chrono>

#include "absl/strings/str_cat.h"

namespace fenestra {

WorkQueue::WorkQueue(int workers, int max_queued_jobs, int max_queued_jobs_per_user)
    : max_queued_jobs_(max_queued_jobs), max_queued_jobs_per_user_(max_queued_jobs_per_user) {
  for (int i = 0; i < std::max(1, workers); ++i) workers_.emplace_back([this] { Work(); });
}

WorkQueue::~WorkQueue() { Join(); }

absl::Status WorkQueue::Push(const std::string& id, const std::string& owner,
                             std::function<void()> task, bool is_job, bool force) {
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
      const int owned =
          static_cast<int>(std::count_if(tasks_.begin(), tasks_.end(), [&](const Task& t) {
            return t.is_job && t.owner == owner;
          }));
      if (owned >= max_queued_jobs_per_user_) {
        return absl::ResourceExhaustedError(absl::StrCat(
            "limits.max_queued_jobs_per_user (", max_queued_jobs_per_user_, ") reached: ", owned,
            " of your jobs wait; submit more when one has started, or cancel one"));
      }
    }
    tasks_.push_back(Task{id, owner, std::move(task), is_job});
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

std::vector<size_t> WorkQueue::TakingOrder() const {
  // Each user's waiting tasks, oldest first, and when the user was last served
  std::map<std::string, std::deque<size_t>> waiting;
  for (size_t i = 0; i < tasks_.size(); ++i) waiting[tasks_[i].owner].push_back(i);
  std::map<std::string, uint64_t> last_taken;
  for (const auto& [owner, indices] : waiting) {
    auto it = last_taken_.find(owner);
    last_taken[owner] = it == last_taken_.end() ? 0 : it->second;
  }
  // Take in turn: the user served least recently, ties to the oldest task
  std::vector<size_t> order;
  order.reserve(tasks_.size());
  uint64_t takes = takes_;
  while (!waiting.empty()) {
    auto next = waiting.begin();
    for (auto it = waiting.begin(); it != waiting.end(); ++it) {
      if (std::pair(last_taken[it->first], it->second.front()) <
          std::pair(last_taken[next->first], next->second.front())) {
        next = it;
      }
    }
    order.push_back(next->second.front());
    next->second.pop_front();
    last_taken[next->first] = ++takes;
    if (next->second.empty()) waiting.erase(next);
  }
  return order;
}

int WorkQueue::Position(const std::string& id) const {
  std::lock_guard lock(mutex_);
  int ahead = 0;
  for (const size_t i : TakingOrder()) {
    if (tasks_[i].id == id) return ahead;
    if (tasks_[i].is_job) ++ahead;
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
      const size_t next = TakingOrder().front();
      task = std::move(tasks_[next]);
      tasks_.erase(tasks_.begin() + static_cast<std::ptrdiff_t>(next));
      last_taken_[task.owner] = ++takes_;
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
