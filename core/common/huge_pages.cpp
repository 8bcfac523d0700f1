#include "core/common/huge_pages.h"

#include <sys/mman.h>

#include <cstdint>

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

}  // namespace fenestra
