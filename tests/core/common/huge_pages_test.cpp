#include "core/common/huge_pages.h"

#include <gtest/gtest.h>
#include <sys/mman.h>

#include <cstdint>
#include <cstring>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

namespace fenestra {
namespace {

constexpr size_t kHugePage = size_t{2} << 20;

// The VmFlags line of the mapping that holds `address` in /proc/self/smaps ("" if none).
std::string VmFlagsAt(const void* address) {
  std::ifstream smaps("/proc/self/smaps");
  const uintptr_t a = reinterpret_cast<uintptr_t>(address);
  bool inside = false;
  for (std::string line; std::getline(smaps, line);) {
    uintptr_t from = 0, to = 0;
    char dash = 0;
    std::istringstream range(line);
    if (range >> std::hex >> from >> dash >> to && dash == '-') {
      inside = from <= a && a < to;
    } else if (inside && line.rfind("VmFlags:", 0) == 0) {
      return line;
    }
  }
  return "";
}

// A private anonymous mapping of `bytes`, 2 MiB-aligned, unmapped when destroyed.
struct Mapping {
  explicit Mapping(size_t bytes) : size(bytes + kHugePage) {
    base = static_cast<char*>(
        mmap(nullptr, size, PROT_READ | PROT_WRITE, MAP_PRIVATE | MAP_ANONYMOUS, -1, 0));
    const uintptr_t b = reinterpret_cast<uintptr_t>(base);
    aligned = base + ((kHugePage - b % kHugePage) % kHugePage);
  }
  ~Mapping() { munmap(base, size); }
  size_t size;
  char* base;
  char* aligned;
};

bool KernelOffersHugePages() {
  std::ifstream enabled("/sys/kernel/mm/transparent_hugepage/enabled");
  std::string modes;
  std::getline(enabled, modes);
  return !modes.empty() && modes.find("[never]") == std::string::npos;
}

// Where the kernel offers huge pages the advice marks the mapping ("hg" in its VmFlags);
// where it does not, nothing is marked.
TEST(HugePagesTest, AdvisesTheWholeHugePagesInsideTheRangeOnly) {
  const bool offered = KernelOffersHugePages();
  Mapping m(6 * kHugePage);
  ASSERT_NE(m.base, MAP_FAILED);
  const auto advised = [](const void* a) { return VmFlagsAt(a).find(" hg") != std::string::npos; };
  // From 1 KiB into the first huge page to 1 KiB into the fourth: only the second and third
  // are whole, and the mapping splits around them
  AdviseHugePages(m.aligned + 1024, 3 * kHugePage);
  EXPECT_FALSE(advised(m.aligned)) << VmFlagsAt(m.aligned);
  EXPECT_EQ(advised(m.aligned + kHugePage), offered) << VmFlagsAt(m.aligned + kHugePage);
  EXPECT_EQ(advised(m.aligned + 3 * kHugePage - 1), offered);
  EXPECT_FALSE(advised(m.aligned + 3 * kHugePage));
}

TEST(HugePagesTest, KeepsWhatTheBufferHolds) {
  Mapping m(4 * kHugePage);
  ASSERT_NE(m.base, MAP_FAILED);
  double* values = reinterpret_cast<double*>(m.aligned);
  const size_t count = 4 * kHugePage / sizeof(double);
  for (size_t i = 0; i < count / 2; ++i) values[i] = static_cast<double>(i) + 0.5;
  AdviseHugePages(values, 4 * kHugePage);
  for (size_t i = count / 2; i < count; ++i) values[i] = static_cast<double>(i) + 0.5;
  size_t wrong = 0;
  for (size_t i = 0; i < count; ++i) wrong += values[i] != static_cast<double>(i) + 0.5;
  EXPECT_EQ(wrong, 0u);
}

TEST(HugePagesTest, RangesWithoutAWholeHugePageAreLeftAlone) {
  Mapping m(2 * kHugePage);
  ASSERT_NE(m.base, MAP_FAILED);
  AdviseHugePages(nullptr, 8 * kHugePage);
  AdviseHugePages(m.aligned + 1, kHugePage);  // no whole huge page inside
  AdviseHugePages(m.aligned, 0);
  AdviseHugePages(reinterpret_cast<void*>(UINTPTR_MAX - 100), 1000);  // would wrap around
  EXPECT_EQ(VmFlagsAt(m.aligned).find(" hg"), std::string::npos) << VmFlagsAt(m.aligned);
  EXPECT_EQ(VmFlagsAt(m.aligned + kHugePage).find(" hg"), std::string::npos);
}

// Every byte of each buffer becomes 0, whatever its size and alignment, and nothing around
// them changes; the pages are then resident (mincore).
TEST(HugePagesTest, ReadyFreshBuffersZeroesThemAndFaultsThemIn) {
  Mapping m(8 * kHugePage);
  ASSERT_NE(m.base, MAP_FAILED);
  char* const a = m.aligned + 100;
  const size_t a_bytes = 5 * kHugePage + 12345;  // pieces of 2 MiB and a last short one
  char* const b = a + a_bytes + 64;
  const size_t b_bytes = 777;
  std::memset(m.aligned, 0x5a, 7 * kHugePage);
  const FreshBuffer buffers[] = {{a, a_bytes}, {b, b_bytes}, {b, 0}};
  ReadyFreshBuffers(buffers);
  const auto count_if = [](const char* from, const char* to, auto pred) {
    size_t n = 0;
    for (const char* p = from; p < to; ++p) n += pred(*p);
    return n;
  };
  const auto zero = [](char c) { return c == 0; };
  const auto kept = [](char c) { return c == 0x5a; };
  EXPECT_EQ(count_if(a, a + a_bytes, zero), a_bytes);
  EXPECT_EQ(count_if(b, b + b_bytes, zero), b_bytes);
  EXPECT_EQ(count_if(m.aligned, a, kept), 100u);
  EXPECT_EQ(count_if(a + a_bytes, b, kept), 64u);
  EXPECT_EQ(count_if(b + b_bytes, m.aligned + 7 * kHugePage, kept),
            static_cast<size_t>(m.aligned + 7 * kHugePage - (b + b_bytes)));
}

TEST(HugePagesTest, ReadyFreshBuffersFaultsInFreshMemory) {
  Mapping m(4 * kHugePage);
  ASSERT_NE(m.base, MAP_FAILED);
  const size_t pages = 4 * kHugePage / 4096;
  std::vector<unsigned char> resident(pages);
  ASSERT_EQ(mincore(m.aligned, 4 * kHugePage, resident.data()), 0);
  size_t before = 0;
  for (unsigned char r : resident) before += r & 1;
  EXPECT_EQ(before, 0u);  // a fresh anonymous mapping has no pages yet
  const FreshBuffer buffer[] = {{m.aligned, 4 * kHugePage}};
  ReadyFreshBuffers(buffer);
  ASSERT_EQ(mincore(m.aligned, 4 * kHugePage, resident.data()), 0);
  size_t after = 0;
  for (unsigned char r : resident) after += r & 1;
  EXPECT_EQ(after, pages);
}

}  // namespace
}  // namespace fenestra
