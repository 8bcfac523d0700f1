#pragma once

// How one hour's illuminance at one sensor counts in the annual metrics (HourTally in
// annual_metrics.h): one definition for the CPU's tallies and the GPU's, so both classify
// every hour alike.
#include "core/common/cpu_gpu.h"

namespace fenestra {

struct HourClass {
  bool below;     // under the UDI range
  bool above;     // over it
  bool da;        // at or above the DA threshold
  double credit;  // continuous DA's credit, min(E / da, 1)
};

// `value` in lux against the limits in lux. The credit takes the ratio where it is not above
// 1, as std::min(ratio, 1.0) does (a NaN stays NaN).
FENESTRA_CPU_GPU inline HourClass ClassifyHour(double value, double lower, double upper,
                                               double da) {
  const double ratio = value / da;
  return {value<lower, value> upper, value >= da, 1.0 < ratio ? 1.0 : ratio};
}

}  // namespace fenestra
