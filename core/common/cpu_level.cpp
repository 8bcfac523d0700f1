// The processor check of the executables built for x86-64-v3 (FENESTRA_X86_64_LEVEL in
// CMakeLists.txt). This file alone is built for the baseline x86-64, and its check runs before
// the program's other initializers, so that an older processor gets a clear error rather than
// an illegal instruction somewhere later.
#include <cstdio>
#include <cstdlib>

namespace {

__attribute__((constructor(101))) void CheckX8664V3() {
  __builtin_cpu_init();
  if (__builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma") &&
      __builtin_cpu_supports("bmi2")) {
    return;
  }
  std::fputs(
      "fenestra: this build needs an x86-64-v3 processor (AVX2, FMA, BMI2), which this one is "
      "not; build with -DFENESTRA_X86_64_LEVEL=x86-64 to run here\n",
      stderr);
  std::_Exit(EXIT_FAILURE);
}

}  // namespace
