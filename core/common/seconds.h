#pragma once

// Wall time since a point of the steady clock, in seconds.
#include <chrono>

namespace fenestra {

inline double SecondsSince(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

}  // namespace fenestra
