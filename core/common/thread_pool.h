#pragma once

#include <condition_variable>
#include <cstdint>
#include <functional>
#include <mutex>
#include <thread>
#include <vector>

namespace fenestra {

// `requested` threads, or every hardware thread when `requested` <= 0.
int ResolveThreadCount(int requested);

// Runs task(i) for every i in [0, count) on `threads` std::thread workers (the calling
// thread is one of them) that pull indices from a shared atomic counter. Returns when all
// are done. Each index runs exactly once; the order is unspecified.
void ParallelFor(uint64_t count, int threads, const std::function<void(uint64_t)>& task);

// Threads that stand for the object's life, for work that each thread should keep doing on
// its own: Run calls task(w) on worker w for every w in [0, count) (worker 0 is the calling
// thread) and returns when all are done. A worker keeps its thread-local state (its Embree
// device, its CUDA default stream) from one Run to the next. One Run at a time.
class StandingThreads {
 public:
  explicit StandingThreads(int count);  // count - 1 threads stand; count >= 1
  ~StandingThreads();
  StandingThreads(const StandingThreads&) = delete;
  StandingThreads& operator=(const StandingThreads&) = delete;

  int count() const { return static_cast<int>(threads_.size()) + 1; }
  void Run(const std::function<void(int)>& task);

 private:
  void Stand(int worker);

  std::mutex mutex_;
  std::condition_variable start_, done_;
  const std::function<void(int)>* task_ = nullptr;
  uint64_t round_ = 0;  // Run's calls so far
  int running_ = 0;     // workers of this round not yet done
  bool stopping_ = false;
  std::vector<std::thread> threads_;
};

}  // namespace fenestra
