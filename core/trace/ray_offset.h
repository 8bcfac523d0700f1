// Ray origins that cannot re-hit the surface they leave.
//
// Wächter and Binder, "A Fast and Robust Method for Avoiding Self-Intersection", Ray Tracing
// Gems (2019), chapter 6: the hit point is computed from barycentrics (not origin + t d),
// then each coordinate is moved along the geometric normal by a fixed number of units in
// the last place (256 ulp times the normal's component), so the offset scales with the
// point's magnitude; coordinates near zero (|p| < 1/32) get a fixed absolute offset of
// 2^-16 times the normal's component instead. SurfacePoint applies the same offset within
// the surface, towards the triangle's interior, so that a point on a concave corner's edge
// cannot round to behind the adjacent surface.
#pragma once

#include <math.h>
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

// The point with barycentric coordinates (b1, b2) on triangle v0 v1 v2, for a new ray to
// leave from. The coordinates are clamped to the triangle, and the interpolated point is
// moved towards the triangle's centroid by the same ulp-scaled offset: rounding can place
// a point interpolated on an edge a few ulps beyond it, and at a concave corner "beyond"
// is behind the adjacent surface, where the next ray would leak out of the scene.
FENESTRA_CPU_GPU inline Vec3f SurfacePoint(Vec3f v0, Vec3f v1, Vec3f v2, float b1, float b2) {
  b1 = b1 > 0.0f ? b1 : 0.0f;
  b2 = b2 > 0.0f ? b2 : 0.0f;
  if (b1 + b2 > 1.0f) {
    const float scale = 1.0f / (b1 + b2);
    b1 *= scale;
    b2 *= scale;
  }
  const Vec3f p = v0 + (v1 - v0) * b1 + (v2 - v0) * b2;
  const Vec3f inward = (v0 + v1 + v2) * (1.0f / 3.0f) - p;
  const float length_squared = Dot(inward, inward);
  if (!(length_squared > 0.0f)) return p;
  return OffsetRayOrigin(p, inward * (1.0f / sqrtf(length_squared)));
}

}  // namespace fenestra
