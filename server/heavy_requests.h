#pragma once

#include <cstddef>
#include <mutex>

#include "absl/status/statusor.h"

namespace fenestra {

// Registrations, submissions and site scenes sent back of at least this size are heavy
// [bytes] (daemon.proto, limits.max_concurrent_heavy_requests).
inline constexpr size_t kHeavyRequestBytes = size_t{1} << 20;

// Hands the free memory of every malloc arena back to the system (glibc's malloc_trim):
// after a large request or a trace, so the daemon's resident memory falls back.
void ReleaseFreeMemory();

// Makes glibc's malloc map blocks of 8 MiB or more on their own, so they go back to the
// system when freed (M_MMAP_THRESHOLD), and trim an arena's free top beyond 16 MiB
// (M_TRIM_THRESHOLD). Set, they also stop both thresholds from growing after large
// frees, which left freed scenes resident in the threads' arenas, where malloc_trim does not
// reach. Not lower: a job's evaluations allocate and free buffers of a few MiB each (a
// design's indoor matrix, the annual products), and with blocks of 1 MiB mapped on their
// own every evaluation faulted its pages in again, which doubled a CPU job's evaluation
// time. Call once at start.
void ReleaseLargeBlocksWhenFreed();

// Bounds the heavy requests processed at once (limits.max_concurrent_heavy_requests); one
// beyond it is refused at once rather than held, since its message already sits in memory.
// Thread-safe.
class HeavyRequests {
 public:
  explicit HeavyRequests(int max_concurrent) : max_concurrent_(max_concurrent) {}

  // Held while one request is processed; a heavy one's end releases its slot and the
  // memory it freed (ReleaseFreeMemory).
  class Pass {
   public:
    Pass(Pass&& other) noexcept : gate_(other.gate_) { other.gate_ = nullptr; }
    Pass& operator=(Pass&&) = delete;
    ~Pass();

   private:
    friend class HeavyRequests;
    explicit Pass(HeavyRequests* gate) : gate_(gate) {}
    HeavyRequests* gate_;  // null for a light request
  };

  // A pass for a request of `bytes`: at once for a light one; for a heavy one while fewer
  // than max_concurrent are processed, else ResourceExhausted naming the limit.
  absl::StatusOr<Pass> Enter(size_t bytes);

 private:
  const int max_concurrent_;
  std::mutex mutex_;
  int active_ = 0;
};

}  // namespace fenestra
