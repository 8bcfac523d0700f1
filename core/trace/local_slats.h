#pragma once

// Whether a segment meets a Venetian blind's slats, computed from the blind's layout (a
// periodic stack of equal boxes, SlatStack in core/geometry/blind.h) rather than by
// traversing its triangles: the segment is clipped to the stack's slab, and only the few
// slats whose axes lie within reach of that piece are tested (box slab tests), so the cost
// does not grow with the slat count. The GPU's indoor replay tests its recorded shadow rays
// with it (core/dc/indoor_replay.h, LocalSlatsOfBlind).
#include <math.h>

#include "core/common/cpu_gpu.h"
#include "core/common/vec3.h"

namespace fenestra {

struct LocalSlats {
  Vec3f center;                    // the middle of the stack's axes (trace frame)
  Vec3f stack, length, into_room;  // unit axes
  float pitch = 0;
  float half_length = 0, half_width = 0, half_thickness = 0;
  float cos_tilt = 1, sin_tilt = 0;
  float reach = 0;  // every slat lies within this of its axis, across the length
  int count = 0;

  // Clips [*t0, *t1] to where x0 + t dx lies in [-half, half]; false when nothing is left.
  FENESTRA_CPU_GPU static bool Clip(float x0, float dx, float half, float* t0, float* t1) {
    if (dx == 0.0f) return x0 >= -half && x0 <= half;
    float a = (-half - x0) / dx, b = (half - x0) / dx;
    if (a > b) {
      const float swap = a;
      a = b;
      b = swap;
    }
    if (a > *t0) *t0 = a;
    if (b < *t1) *t1 = b;
    return *t0 <= *t1;
  }

  // Whether the segment from `origin` along the unit `direction` meets a slat before
  // `distance`.
  FENESTRA_CPU_GPU bool Occluded(Vec3f origin, Vec3f direction, float distance) const {
    const Vec3f r = origin - center;
    const float a0 = Dot(r, stack), l0 = Dot(r, length), z0 = Dot(r, into_room);
    const float da = Dot(direction, stack), dl = Dot(direction, length),
                dz = Dot(direction, into_room);
    // The piece of the segment along the slats' length and within their reach of the axes'
    // plane
    float t0 = 0.0f, t1 = distance;
    if (!Clip(l0, dl, half_length, &t0, &t1) || !Clip(z0, dz, reach, &t0, &t1)) return false;
    // The slats whose axes lie within reach of that piece along the stack
    const float a_start = a0 + da * t0, a_end = a0 + da * t1;
    const float low = (a_start < a_end ? a_start : a_end) - reach;
    const float high = (a_start < a_end ? a_end : a_start) + reach;
    const float middle = 0.5f * static_cast<float>(count - 1);
    const float first_k = ceilf(low / pitch + middle), last_k = floorf(high / pitch + middle);
    const int first = first_k > 0.0f ? static_cast<int>(first_k) : 0;
    const int last = last_k < static_cast<float>(count - 1) ? static_cast<int>(last_k) : count - 1;
    // Each one's box: across its width and its thickness (the length is clipped already)
    const float du = cos_tilt * da + sin_tilt * dz, dv = -sin_tilt * da + cos_tilt * dz;
    for (int k = first; k <= last; ++k) {
      const float y0 = a0 - (static_cast<float>(k) - middle) * pitch;
      float s0 = t0, s1 = t1;
      if (Clip(cos_tilt * y0 + sin_tilt * z0, du, half_width, &s0, &s1) &&
          Clip(-sin_tilt * y0 + cos_tilt * z0, dv, half_thickness, &s0, &s1)) {
        return true;
      }
    }
    return false;
  }
};

}  // namespace fenestra
