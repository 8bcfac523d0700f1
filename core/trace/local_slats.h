#pragma once

// Whether a segment meets a Venetian blind's slats, computed from the blind's layout (a
// periodic stack of equal boxes, SlatStack in core/geometry/blind.h) rather than by
// traversing its triangles: the segment is clipped to the stack's slab, and only the few
// slats whose axes lie within reach of that piece are tested (box slab tests), so the cost
// does not grow with the slat count. A piece that crosses the slats' whole depth, as the
// replays' shadow rays towards the window do, takes one test of its line against the stack's
// period instead. The GPU's indoor replay tests its recorded shadow rays
// with it (core/dc/indoor_replay.h, LocalSlatsOfBlind).
#include <math.h>

#include "core/common/cpu_gpu.h"
#include "core/common/vec3.h"

namespace fenestra {

// A segment in a stack's frame: where it starts along (stack, length, into_room) from the
// frame's centre, its unit direction along those axes, and its length.
struct StackSegment {
  float a = 0, l = 0, z = 0;
  float da = 0, dl = 0, dz = 0;
  float distance = 0;

  // The same segment seen from a centre moved by `shift` (along stack, length, into_room).
  FENESTRA_CPU_GPU StackSegment MovedBy(Vec3f shift) const {
    return {a - shift.x, l - shift.y, z - shift.z, da, dl, dz, distance};
  }
};

// `origin` + t `direction`, t in [0, distance], in the frame of `center` and the unit axes.
FENESTRA_CPU_GPU inline StackSegment SegmentInFrame(Vec3f center, Vec3f stack, Vec3f length,
                                                    Vec3f into_room, Vec3f origin, Vec3f direction,
                                                    float distance) {
  const Vec3f r = origin - center;
  return {Dot(r, stack),
          Dot(r, length),
          Dot(r, into_room),
          Dot(direction, stack),
          Dot(direction, length),
          Dot(direction, into_room),
          distance};
}

// A segment that crosses a slab |z| <= half_depth of a stack's frame from face to face (a
// shadow ray past every design's slats, in the frame of their envelope): its line a =
// intercept + slope z in the profile plane and where along the length it enters and leaves
// the slab. Only that part can meet slats within the slab.
struct SlabCrossing {
  float intercept = 0, slope = 0;
  float l_enter = 0, l_leave = 0;  // at z = half_depth and z = -half_depth

  // The part within the slab as a segment.
  FENESTRA_CPU_GPU StackSegment Segment(float half_depth) const {
    const float da = -2.0f * half_depth * slope, dl = l_leave - l_enter, dz = -2.0f * half_depth;
    const float distance = sqrtf(da * da + dl * dl + dz * dz);
    return {intercept + slope * half_depth,
            l_enter,
            half_depth,
            da / distance,
            dl / distance,
            dz / distance,
            distance};
  }

  // The crossing of `s`, when it runs from one face of the slab to the other.
  FENESTRA_CPU_GPU static bool Of(const StackSegment& s, float half_depth, SlabCrossing* crossing) {
    if (s.dz == 0.0f) return false;
    const float t_enter = (half_depth - s.z) / s.dz, t_leave = (-half_depth - s.z) / s.dz;
    if (t_enter < 0.0f || t_enter > s.distance || t_leave < 0.0f || t_leave > s.distance) {
      return false;
    }
    crossing->slope = s.da / s.dz;
    crossing->intercept = s.a - crossing->slope * s.z;
    crossing->l_enter = s.l + s.dl * t_enter;
    crossing->l_leave = s.l + s.dl * t_leave;
    return true;
  }
};

struct LocalSlats {
  Vec3f center;                    // the middle of the stack's axes (trace frame)
  Vec3f stack, length, into_room;  // unit axes
  float pitch = 0;
  float half_length = 0, half_width = 0, half_thickness = 0;
  float cos_tilt = 1, sin_tilt = 0;
  float reach = 0;  // every slat lies within this of its axis, across the length
  float depth = 0;  // every slat lies within this of its axes' plane, along into_room
  int count = 0;

  // Clips [*t0, *t1] to where x0 + t dx lies in [-half, half]; false when nothing is left.
  FENESTRA_CPU_GPU static bool Clip(float x0, float dx, float half, float* t0, float* t1) {
    if (dx == 0.0f) return x0 >= -half && x0 <= half;
    const float inverse = 1.0f / dx;
    float a = (-half - x0) * inverse, b = (half - x0) * inverse;
    if (a > b) {
      const float swap = a;
      a = b;
      b = swap;
    }
    if (a > *t0) *t0 = a;
    if (b < *t1) *t1 = b;
    return *t0 <= *t1;
  }

  // Where the slats' centre lies from `frame_center`, along the slats' axes.
  FENESTRA_CPU_GPU Vec3f ShiftFrom(Vec3f frame_center) const {
    const Vec3f moved = center - frame_center;
    return {Dot(moved, stack), Dot(moved, length), Dot(moved, into_room)};
  }

  // Whether the segment from `origin` along the unit `direction` meets a slat before
  // `distance`.
  FENESTRA_CPU_GPU bool Occluded(Vec3f origin, Vec3f direction, float distance) const {
    return Occluded(SegmentInFrame(center, stack, length, into_room, origin, direction, distance));
  }

  // The same for a segment in the stack's frame.
  FENESTRA_CPU_GPU bool Occluded(const StackSegment& s) const {
    // The piece of the segment along the slats' length and within their reach of the axes'
    // plane
    float t0 = 0.0f, t1 = s.distance;
    if (!Clip(s.l, s.dl, half_length, &t0, &t1) || !Clip(s.z, s.dz, reach, &t0, &t1)) return false;
    // A piece that crosses the slats' whole depth meets one where its line does
    const float z_start = s.z + s.dz * t0, z_end = s.z + s.dz * t1;
    if ((z_start <= -depth && z_end >= depth) || (z_end <= -depth && z_start >= depth)) {
      const float slope = s.da / s.dz;
      return LineOccluded(s.a - slope * s.z, slope);
    }
    // The slats whose axes lie within reach of that piece along the stack
    const float a_start = s.a + s.da * t0, a_end = s.a + s.da * t1;
    const float low = (a_start < a_end ? a_start : a_end) - reach;
    const float high = (a_start < a_end ? a_end : a_start) + reach;
    const float middle = 0.5f * static_cast<float>(count - 1);
    const float first_k = ceilf(low / pitch + middle), last_k = floorf(high / pitch + middle);
    const int first = first_k > 0.0f ? static_cast<int>(first_k) : 0;
    const int last = last_k < static_cast<float>(count - 1) ? static_cast<int>(last_k) : count - 1;
    // Each one's box: across its width and its thickness (the length is clipped already)
    const float du = cos_tilt * s.da + sin_tilt * s.dz, dv = -sin_tilt * s.da + cos_tilt * s.dz;
    for (int k = first; k <= last; ++k) {
      const float y0 = s.a - (static_cast<float>(k) - middle) * pitch;
      float s0 = t0, s1 = t1;
      if (Clip(cos_tilt * y0 + sin_tilt * s.z, du, half_width, &s0, &s1) &&
          Clip(-sin_tilt * y0 + cos_tilt * s.z, dv, half_thickness, &s0, &s1)) {
        return true;
      }
    }
    return false;
  }

  // Whether the line a = intercept + slope z of the profile plane (a along the stack, z into
  // the room, from the centre) meets a slat's cross-section. Slat k's box, centred at a_k =
  // (k - (count - 1) / 2) pitch, meets the line where intercept - a_k lies within +-h, the
  // range of a - slope z over a box centred at 0: h = half_width |cos - slope sin| +
  // half_thickness |sin + slope cos|. So some slat k in [0, count) must lie within that.
  // Branch-free: the answers of many lines in a row do not stall the CPU.
  FENESTRA_CPU_GPU bool LineOccluded(float intercept, float slope) const {
    const float h = half_width * fabsf(cos_tilt - slope * sin_tilt) +
                    half_thickness * fabsf(sin_tilt + slope * cos_tilt);
    const float last = static_cast<float>(count - 1);
    const float middle = 0.5f * last;
    const float from = (intercept - h) / pitch + middle, to = (intercept + h) / pitch + middle;
    // The first slat at or after `from` (within [0, count], so the conversion is exact)
    const float low = from > 0.0f ? (from < last + 1.0f ? from : last + 1.0f) : 0.0f;
    const float whole = static_cast<float>(static_cast<int>(low));
    const float first = whole < low ? whole + 1.0f : whole;
    return first <= (to < last ? to : last);
  }

  // Whether `crossing` of a slab of half depth `half_depth` that holds the slats, with their
  // centre at `shift` (along stack, length, into_room) in its frame, stays within their length
  // and crosses their whole depth, so that its line answers for it (LineOccludedAt).
  FENESTRA_CPU_GPU bool LineAnswers(const SlabCrossing& crossing, Vec3f shift,
                                    float half_depth) const {
    const float enter = fabsf(crossing.l_enter), leave = fabsf(crossing.l_leave);
    const float reach_l = (enter > leave ? enter : leave) + fabsf(shift.y);
    // Both compared, without a branch: SIMD code tests many crossings at once
    return (static_cast<int>(reach_l <= half_length) &
            static_cast<int>(fabsf(shift.z) + depth <= half_depth)) != 0;
  }

  // LineOccluded for the line of `crossing`, the slats' centre at `shift` in its frame.
  FENESTRA_CPU_GPU bool LineOccludedAt(const SlabCrossing& crossing, Vec3f shift) const {
    return LineOccluded(crossing.intercept - shift.x + crossing.slope * shift.z, crossing.slope);
  }

  // Whether the slats, with their centre at `shift` (along stack, length, into_room) in the
  // frame of `crossing` (a slab of half depth `half_depth` that holds them), meet it.
  FENESTRA_CPU_GPU bool Occluded(const SlabCrossing& crossing, Vec3f shift,
                                 float half_depth) const {
    if (LineAnswers(crossing, shift, half_depth)) return LineOccludedAt(crossing, shift);
    return Occluded(crossing.Segment(half_depth).MovedBy(shift));
  }
};

}  // namespace fenestra
