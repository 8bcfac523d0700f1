#include "core/trace/thread_pool.h"

#include <algorithm>
#include <atomic>
#include <thread>
#include <vector>

namespace fenestra {

int ResolveThreadCount(int requested) {
  if (requested > 0) return requested;
  return std::max(1u, std::thread::hardware_concurrency());
}

void ParallelFor(uint64_t count, int threads, const std::function<void(uint64_t)>& task) {
  std::atomic<uint64_t> next{0};
  const auto work = [&] {
    for (uint64_t i = next.fetch_add(1); i < count; i = next.fetch_add(1)) task(i);
  };
  const int workers = static_cast<int>(std::min<uint64_t>(std::max(threads, 1), count));
  std::vector<std::thread> pool;
  for (int w = 1; w < workers; ++w) pool.emplace_back(work);
  work();
  for (std::thread& t : pool) t.join();
}

}  // namespace fenestra
