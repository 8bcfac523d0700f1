#include "server/heavy_requests.h"

#include <malloc.h>

#include "absl/strings/str_cat.h"

namespace fenestra {
namespace {

// Blocks of at least this size are mapped on their own by glibc's malloc [bytes]
// (ReleaseLargeBlocksWhenFreed).
constexpr int kOwnMappingBytes = 8 << 20;

}  // namespace

void ReleaseFreeMemory() { malloc_trim(0); }

void ReleaseLargeBlocksWhenFreed() {
  mallopt(M_MMAP_THRESHOLD, kOwnMappingBytes);
  mallopt(M_TRIM_THRESHOLD, 2 * kOwnMappingBytes);
}

HeavyRequests::Pass::~Pass() {
  if (!gate_) return;
  {
    std::lock_guard lock(gate_->mutex_);
    --gate_->active_;
  }
  ReleaseFreeMemory();
}

absl::StatusOr<HeavyRequests::Pass> HeavyRequests::Enter(size_t bytes) {
  if (bytes < kHeavyRequestBytes) return Pass(nullptr);
  std::lock_guard lock(mutex_);
  if (active_ >= max_concurrent_) {
    return absl::ResourceExhaustedError(absl::StrCat(
        "the server is processing ", active_, " large requests (of at least ", kHeavyRequestBytes,
        " bytes), its limit max_concurrent_heavy_requests; try again in a moment"));
  }
  ++active_;
  return Pass(this);
}

}  // namespace fenestra
