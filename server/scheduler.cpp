#include "server/scheduler.h"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <cmath>

#include "core/dc/dc_backend.h"
#include "server/log_safe.h"

namespace fenestra {

Scheduler::Scheduler(Store& store, OutdoorCache& cache, std::string replica, int workers,
                     double lease_seconds, double poll_seconds)
    : store_(store),
      cache_(cache),
      replica_(std::move(replica)),
      workers_(std::max(1, workers)),
      lease_ms_(std::max<int64_t>(1, std::llround(lease_seconds * 1000))),
      poll_(std::max<int64_t>(1, std::llround(poll_seconds * 1000))) {}

Scheduler::~Scheduler() { Join(); }

void Scheduler::Start(Runner run_job, Runner run_site) {
  run_job_ = std::move(run_job);
  run_site_ = std::move(run_site);
  for (int i = 0; i < workers_; ++i) threads_.emplace_back([this, i] { Work(i); });
  threads_.emplace_back([this] { Renew(); });
}

void Scheduler::Stop() {
  {
    std::lock_guard lock(mutex_);
    stopped_ = true;
  }
  stop_cv_.notify_all();
}

bool Scheduler::WaitIdle(double timeout_seconds) {
  std::unique_lock lock(mutex_);
  return idle_.wait_for(lock, std::chrono::duration<double>(timeout_seconds),
                        [&] { return running_ == 0; });
}

void Scheduler::Join() {
  Stop();
  {
    std::lock_guard lock(mutex_);
    if (joined_) return;
    joined_ = true;
  }
  stop_cv_.notify_all();
  for (std::thread& t : threads_) {
    if (t.joinable()) t.join();
  }
  threads_.clear();
}

int Scheduler::Running() const {
  std::lock_guard lock(mutex_);
  return running_;
}

std::shared_ptr<Scheduler::Held> Scheduler::Hold(const Claim& claim) {
  auto held = std::make_shared<Held>();
  held->claim = claim;
  std::lock_guard lock(mutex_);
  held_[claim.lease.id] = held;
  return held;
}

std::shared_ptr<Scheduler::Held> Scheduler::Find(const std::string& id) const {
  std::lock_guard lock(mutex_);
  auto it = held_.find(id);
  return it == held_.end() ? nullptr : it->second.lock();
}

std::vector<std::shared_ptr<Scheduler::Held>> Scheduler::HeldNow() const {
  std::vector<std::shared_ptr<Held>> held;
  for (auto it = held_.begin(); it != held_.end();) {
    if (auto h = it->second.lock()) {
      held.push_back(std::move(h));
      ++it;
    } else {
      it = held_.erase(it);
    }
  }
  return held;
}

void Scheduler::NoteClaimFailure(const absl::Status& status, const std::string& candidate) {
  const std::string what = candidate.empty() ? "?" : candidate;
  {
    std::lock_guard lock(mutex_);
    if (failing_ == what) return;
    failing_ = what;
  }
  if (candidate.empty()) {
    spdlog::error("cannot take work from the store ({}); trying again",
                  std::string(status.message()));
  } else if (candidate.starts_with("job-")) {
    spdlog::error(
        "job {}: cannot start, its running state cannot be stored ({}); trying again every "
        "second",
        candidate, std::string(status.message()));
  } else {
    spdlog::error(
        "site {}: cannot start computing, its claim cannot be stored ({}); trying "
        "again every second",
        candidate, std::string(status.message()));
  }
}

void Scheduler::Work(int worker) {
  // The worker's jobs and site computations run on its GPUs, so that with a worker per GPU
  // (the default) concurrent jobs never share one
  const ThreadCudaDevices gpus(WorkerCudaDevices(worker, workers_));
  while (true) {
    const uint64_t seen = store_.database().ChangeCount();
    std::vector<std::string> excluded;
    {
      std::lock_guard lock(mutex_);
      if (stopped_) return;
      for (const auto& h : HeldNow()) excluded.push_back(h->claim.lease.id);
    }
    std::string candidate;
    absl::StatusOr<std::optional<Claim>> claim =
        store_.ClaimWork(replica_, lease_ms_, cache_.KeysInMemory(), excluded, &candidate);
    if (!claim.ok()) {
      NoteClaimFailure(claim.status(), candidate);
      std::unique_lock lock(mutex_);
      stop_cv_.wait_for(lock, std::chrono::seconds(1), [&] { return stopped_; });
      continue;
    }
    {
      std::lock_guard lock(mutex_);
      if (!failing_.empty()) spdlog::info("work is taken from the store again");
      failing_.clear();
    }
    if (!*claim) {
      // Nothing to do: wait for a change, or poll (expired leases tell no one)
      const auto deadline = std::chrono::steady_clock::now() + poll_;
      while (std::chrono::steady_clock::now() < deadline) {
        {
          std::lock_guard lock(mutex_);
          if (stopped_) return;
        }
        if (store_.database().WaitForChange(seen, std::chrono::milliseconds(100))) break;
      }
      continue;
    }
    std::shared_ptr<Held> held = Hold(**claim);
    {
      std::lock_guard lock(mutex_);
      ++running_;
    }
    if (held->claim.kind == Claim::Kind::kJob) {
      run_job_(held);
    } else {
      run_site_(held);
    }
    held.reset();
    {
      std::lock_guard lock(mutex_);
      --running_;
    }
    idle_.notify_all();
  }
}

void Scheduler::Renew() {
  const auto period = std::chrono::milliseconds(std::max<int64_t>(1, lease_ms_ / 3));
  bool failing = false;
  while (true) {
    std::vector<std::shared_ptr<Held>> held;
    {
      std::unique_lock lock(mutex_);
      // Runs until the workers are joined: held work goes on after Stop
      stop_cv_.wait_for(lock, period, [&] { return stopped_ && running_ == 0 && joined_; });
      if (stopped_ && running_ == 0 && joined_) return;
      held = HeldNow();
    }
    if (held.empty()) continue;
    std::vector<std::pair<Claim::Kind, Lease>> leases;
    std::erase_if(held, [](const auto& h) { return h->done.load(); });
    if (held.empty()) continue;
    for (const auto& h : held) leases.push_back({h->claim.kind, h->claim.lease});
    absl::StatusOr<std::vector<Store::Renewal>> renewed = store_.RenewLeases(lease_ms_, leases);
    if (!renewed.ok()) {
      if (!failing) {
        spdlog::error(
            "cannot renew this replica's leases ({}); its work goes on, and another "
            "replica may take it over if this lasts {:.1f} s",
            std::string(renewed.status().message()), lease_ms_ / 1000.0);
      }
      failing = true;
      continue;
    }
    if (failing) spdlog::info("this replica's leases are renewed again");
    failing = false;
    for (size_t i = 0; i < held.size(); ++i) {
      // Ended meanwhile: its lease ended with it
      if (held[i]->done) continue;
      if (!(*renewed)[i].held && !held[i]->lost.exchange(true)) {
        spdlog::warn(
            "{}: its lease was lost (taken over by another replica, or the record is "
            "gone); stopping it here",
            held[i]->claim.lease.id);
      }
      if ((*renewed)[i].cancel_requested) held[i]->cancel_requested = true;
    }
  }
}

}  // namespace fenestra
