// Radiance's `glass` (glass.c), grey: a thin pane of refractive index n whose transmissivity t_n
// (the internal transmittance of one pass at normal incidence, Radiance's argument) gives, at
// an angle of incidence with cosine c, the Fresnel reflection of each polarization at both
// faces and the light's passes through the pane summed:
//
//   c_t = sqrt(1 - (1 - c^2) / n^2),  t = t_n^(1 / c_t),
//   r_s = ((c - n c_t) / (c + n c_t))^2,  r_p = ((1/c - n/c_t) / (1/c + n/c_t))^2,
//   T = 1/2 sum_{r = r_s, r_p} (1 - r)^2 t / (1 - r^2 t^2),
//   R = 1/2 sum_{r = r_s, r_p} r (1 + (1 - 2 r) t^2) / (1 - r^2 t^2).
//
// So a pane of normal transmittance 0.88 has t_n = 0.96 (Radiance's documented 1.0895 factor).
#pragma once

#include <math.h>

#include "core/common/cpu_gpu.h"

namespace fenestra {

struct GlassPane {
  float transmissivity = 0;  // t_n, in [0, 1]
  float index = 1.52f;       // n, Radiance's default

  // Transmittance and reflectance at an angle of incidence with cosine `c` in (0, 1].
  FENESTRA_CPU_GPU float Transmittance(float c) const { return Sum(c, true); }
  FENESTRA_CPU_GPU float Reflectance(float c) const { return Sum(c, false); }

  // The transmissivity of a pane whose transmittance at normal incidence is `normal` (in [0,
  // the bare surfaces' limit]): Transmittance(1) = normal, by bisection.
  static float TransmissivityFor(float normal, float index = 1.52f) {
    float low = 0.0f, high = 1.0f;
    for (int i = 0; i < 60; ++i) {
      const float middle = 0.5f * (low + high);
      (GlassPane{middle, index}.Transmittance(1.0f) < normal ? low : high) = middle;
    }
    return 0.5f * (low + high);
  }

  // Transmittance(1) in double: at normal incidence both polarizations reflect
  // r = ((n - 1) / (n + 1))^2 at each face and T = (1 - r)^2 t / (1 - r^2 t^2). What a
  // Radiance glass of transmissivity `transmissivity` lets through straight on.
  static double NormalTransmittance(double transmissivity, double index = 1.52) {
    const double r = (index - 1.0) * (index - 1.0) / ((index + 1.0) * (index + 1.0));
    const double t = transmissivity;
    return (1.0 - r) * (1.0 - r) * t / (1.0 - r * r * t * t);
  }

 private:
  FENESTRA_CPU_GPU float Sum(float c, bool transmitted) const {
    if (!(c > 0.0f)) return 0.0f;
    const float n2 = index * index;
    const float ct = sqrtf(1.0f - (1.0f - c * c) / n2);
    const float t = powf(transmissivity, 1.0f / ct);
    const float rs = Square((c - index * ct) / (c + index * ct));
    const float rp = Square((1.0f / c - index / ct) / (1.0f / c + index / ct));
    return 0.5f * (Pane(rs, t, transmitted) + Pane(rp, t, transmitted));
  }
  // One polarization's share through (or back from) the pane: surface reflectance r, one
  // pass's transmittance t, every pass summed.
  FENESTRA_CPU_GPU static float Pane(float r, float t, bool transmitted) {
    return transmitted ? (1.0f - r) * (1.0f - r) * t / (1.0f - r * r * t * t)
                       : r * (1.0f + (1.0f - 2.0f * r) * t * t) / (1.0f - r * r * t * t);
  }
  FENESTRA_CPU_GPU static float Square(float x) { return x * x; }
};

}  // namespace fenestra
