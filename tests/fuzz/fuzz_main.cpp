// One libFuzzer target: FENESTRA_FUZZ_ENTRY names the function of fuzz_targets.h it feeds.
#include <cstddef>
#include <cstdint>
#include <string_view>

#include "tests/fuzz/fuzz_targets.h"

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  fenestra::fuzz::QuietLibraries();
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  FENESTRA_FUZZ_ENTRY(std::string_view(reinterpret_cast<const char*>(data), size)).IgnoreError();
  return 0;
}
