// Direction sampling shared by the CPU and GPU tracers.
//
// Orthonormal basis: Duff, Burgess, Christensen, Hery, Kensler, Liani and Villemin,
// "Building an Orthonormal Basis, Revisited", JCGT 6(1), 2017 (listing 3).
// Cosine-weighted hemisphere: Malley's method (uniform disk sample lifted to the
// hemisphere), pdf cos(theta) / pi.
#pragma once

#include <math.h>

#include "core/common/cpu_gpu.h"
#include "core/common/vec3.h"

namespace fenestra {

inline constexpr float kPiF = 3.14159265358979323846f;
inline constexpr double kPi = 3.14159265358979323846;

// Tangents t, b with (t, b, n) right-handed and orthonormal, for unit `n`.
FENESTRA_CPU_GPU inline void OrthonormalBasis(Vec3f n, Vec3f* t, Vec3f* b) {
  const float sign = copysignf(1.0f, n.z);
  const float a = -1.0f / (sign + n.z);
  const float c = n.x * n.y * a;
  *t = {1.0f + sign * n.x * n.x * a, sign * c, -sign * n.x};
  *b = {c, sign + n.y * n.y * a, -n.y};
}

// Cosine-weighted direction about unit `n` from uniforms u0, u1 in [0, 1). The result is
// unit length within rounding and strictly on n's side: cos(theta) >= 2^-12.
FENESTRA_CPU_GPU inline Vec3f SampleCosineHemisphere(Vec3f n, float u0, float u1) {
  const float r = sqrtf(u0);
  const float phi = 2.0f * kPiF * u1;
  const float cos_theta = sqrtf(1.0f - u0);
  Vec3f t, b;
  OrthonormalBasis(n, &t, &b);
  return t * (r * cosf(phi)) + b * (r * sinf(phi)) + n * cos_theta;
}

}  // namespace fenestra
