// Ray origins that cannot re-hit the surface they leave.
//
// Wächter and Binder, "A Fast and Robust Method for Avoiding Self-Intersection", Ray Tracing
// Gems (2019), chapter 6: the hit point is computed from barycentrics (not origin + t d),
// then each coordinate is moved along the geometric normal by a fixed number of units in
// the last place (256 ulp times the normal's component), so the offset scales with the
// point's magnitude; coordinates near zero (|p| < 1/32) get a fixed absolute offset of
// 2^-16 times the normal's component instead.
#pragma once

#include <stdint.h>
#include <string.h>

#include "core/common/cpu_gpu.h"
#include "core/common/vec3.h"

namespace fenestra {

namespace ray_offset_internal {

FENESTRA_CPU_GPU inline int32_t FloatAsInt(float f) {
  int32_t i;
  memcpy(&i, &f, sizeof(i));
  return i;
}

FENESTRA_CPU_GPU inline float IntAsFloat(int32_t i) {
  float f;
  memcpy(&f, &i, sizeof(f));
  return f;
}

FENESTRA_CPU_GPU inline float OffsetComponent(float p, float n) {
  constexpr float kOrigin = 1.0f / 32.0f;
  constexpr float kFloatScale = 1.0f / 65536.0f;
  constexpr float kIntScale = 256.0f;
  if (fabsf(p) < kOrigin) return p + kFloatScale * n;
  const int32_t ulps = static_cast<int32_t>(kIntScale * n);
  return IntAsFloat(FloatAsInt(p) + (p < 0 ? -ulps : ulps));
}

}  // namespace ray_offset_internal

// `p` moved off its surface along `n` (unit; pointing to the side the new ray leaves on).
FENESTRA_CPU_GPU inline Vec3f OffsetRayOrigin(Vec3f p, Vec3f n) {
  using ray_offset_internal::OffsetComponent;
  return {OffsetComponent(p.x, n.x), OffsetComponent(p.y, n.y), OffsetComponent(p.z, n.z)};
}

}  // namespace fenestra
