#pragma once

#include <math.h>

#include "core/common/cpu_gpu.h"

namespace fenestra {

// The mean of `count` >= 2 independent batch estimates value(0), ..., value(count - 1) and
// the standard error of that mean from their spread: one entry of a matrix of batches, on the
// host or on the device.
template <class Value>
FENESTRA_CPU_GPU void BatchMeanAndError(int count, const Value& value, double* mean,
                                        double* standard_error) {
  double sum = 0;
  for (int b = 0; b < count; ++b) sum += value(b);
  const double m = sum / count;
  double variance = 0;
  for (int b = 0; b < count; ++b) variance += (value(b) - m) * (value(b) - m);
  *mean = m;
  *standard_error = sqrt(variance / (count * (count - 1.0)));
}

}  // namespace fenestra
