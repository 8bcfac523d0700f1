#include "core/common/huge_pages.h"

#include <sys/mman.h>

#include <algorithm>
#include <cstdint>
#include <cstring>
#include <vector>

#include "core/common/thread_pool.h"

namespace fenestra {

void AdviseHugePages(void* data, size_t bytes) {
  constexpr uintptr_t kHugePage = uintptr_t{2} << 20;
  const uintptr_t begin = reinterpret_cast<uintptr_t>(data);
  const uintptr_t first = (begin + kHugePage - 1) & ~(kHugePage - 1);
  const uintptr_t end = (begin + bytes) & ~(kHugePage - 1);
  if (data == nullptr || end <= first || begin + bytes < begin) return;
  // Advice only: a kernel without transparent huge pages refuses it, and the pages stay small
  (void)madvise(reinterpret_cast<void*>(first), end - first, MADV_HUGEPAGE);
}

void ReadyFreshBuffers(std::span<const FreshBuffer> buffers) {
  constexpr size_t kPiece = size_t{2} << 20;
  std::vector<FreshBuffer> pieces;
  for (const FreshBuffer& b : buffers) {
    AdviseHugePages(b.data, b.bytes);
    for (size_t at = 0; at < b.bytes; at += kPiece) {
      pieces.push_back({static_cast<char*>(b.data) + at, std::min(kPiece, b.bytes - at)});
    }
  }
  ParallelFor(pieces.size(), ResolveThreadCount(0),
              [&](uint64_t i) { std::memset(pieces[i].data, 0, pieces[i].bytes); });
}

}  // namespace fenestra
