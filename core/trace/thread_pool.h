#pragma once

#include <cstdint>
#include <functional>

namespace fenestra {

// `requested` threads, or every hardware thread when `requested` <= 0.
int ResolveThreadCount(int requested);

// Runs task(i) for every i in [0, count) on `threads` std::thread workers (the calling
// thread is one of them) that pull indices from a shared atomic counter. Returns when all
// are done. Each index runs exactly once; the order is unspecified.
void ParallelFor(uint64_t count, int threads, const std::function<void(uint64_t)>& task);

}  // namespace fenestra
