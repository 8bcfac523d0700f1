// Transparent huge pages for large host buffers written once.
#pragma once

#include <cstddef>
#include <span>

namespace fenestra {

// Asks the kernel to back the 2 MiB-aligned pages inside [data, data + bytes) with
// transparent huge pages (madvise MADV_HUGEPAGE) before the buffer is first written: a
// buffer of many MiB filled at once (a GPU download, say) then takes one page fault per
// 2 MiB instead of one per 4 KiB. Where the kernel offers no huge pages, or the range holds
// no whole one, nothing changes. The buffer's content is never touched.
void AdviseHugePages(void* data, size_t bytes);

// A fresh buffer whose content is not yet set.
struct FreshBuffer {
  void* data;
  size_t bytes;
};

// Readies `buffers` to be overwritten whole: advises huge pages for them (AdviseHugePages),
// then writes zeros over them from every core, 2 MiB per task, so that their page faults
// (and the zeroing of their pages by the kernel) run on all cores at once instead of on the
// one thread that fills them later (a GPU download, say).
void ReadyFreshBuffers(std::span<const FreshBuffer> buffers);

}  // namespace fenestra
