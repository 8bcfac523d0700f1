#pragma once

// The daylight glare probability's formula (glare.h), one definition for the CPU's glare
// figures and the GPU's glare counts.
#include <math.h>

#include "core/common/cpu_gpu.h"

namespace fenestra {

// evalglare's constants of the DGP (c1, c2, c3; the exponent of Ev)
inline constexpr double kDgpEvSlope = 5.87e-5, kDgpLogFactor = 0.092, kDgpOffset = 0.159;
inline constexpr double kDgpEvExponent = 1.87;

// The DGP from Ev and the sources' sum of L^2 omega / P^2, at most 1.
FENESTRA_CPU_GPU inline double DgpOfSum(double eye_lux, double sum) {
  double dgp = kDgpEvSlope * eye_lux + kDgpOffset;
  if (sum > 0) dgp += kDgpLogFactor * log10(1 + sum / pow(eye_lux, kDgpEvExponent));
  return dgp < 1.0 ? dgp : 1.0;
}

// The DGP with the sun as glare source from its geometric factor (glare.h, SunGlareFactor).
FENESTRA_CPU_GPU inline double DgpWithSunFactor(double eye_lux, double sun_eye_lux, double factor) {
  if (!(sun_eye_lux > 0) || !(factor > 0) || !(eye_lux > 0)) return DgpOfSum(eye_lux, 0);
  return DgpOfSum(eye_lux, sun_eye_lux * sun_eye_lux * factor);
}

}  // namespace fenestra
