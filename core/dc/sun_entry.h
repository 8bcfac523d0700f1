#pragma once

// One sensor's direct-sun illuminance in one column of a sky (core/dc/direct_sun.h), plain
// data for the CPU's products and the GPU's alike.
#include <cstdint>

namespace fenestra {

struct SunEntry {
  int32_t sensor = 0;
  int32_t column = 0;
  double lux = 0;
};

}  // namespace fenestra
