#pragma once

// Equal-area partition of the hemisphere into rings of cells, after
// B. Beckers, P. Beckers, "A general rule for disk and hemisphere partition into equal-area
// cells", Computational Geometry 45(7):275-283, 2012.
//
// Ring i holds the cells K[i-1] .. K[i]-1 (K = cumulative counts, K[-1] = 0) and spans
// exactly the cap areas: cos θ from 1 - K[i-1]/n down to 1 - K[i]/n, so every cell has the
// solid angle 2π/n. Within a ring the cells split the azimuth φ = atan2(y, x) equally,
// cell 0 of each ring starting at φ = 0. Directions are in a local frame whose z axis is the
// hemisphere's pole (for a window: the outward normal).
#include <cmath>
#include <cstdint>

#include "core/common/cpu_gpu.h"
#include "core/common/vec3.h"

namespace fenestra {

// Plain data, usable in device code.
struct HemisphereBasis {
  static constexpr int kMaxRings = 64;
  int cell_count = 0;
  int ring_count = 0;
  int cumulative[kMaxRings] = {};  // K[i]: cells in rings 0..i
};

// The 288-cell partition (rings of 1, 8, 13, 19, 24, 29, 34, 37, 40, 41, 42 cells).
HemisphereBasis Beckers288();

// A partition into `cell_count` cells by the Beckers rule (rings about √(2π/n) wide, built
// from the horizon inwards, cell counts rounded, ring limits then set to exact equal area);
// 288 gives Beckers288(). Returns a basis with cell_count 0 for counts outside [1, 10000].
HemisphereBasis BeckersBasis(int cell_count);

// atan2 in the precision of T (the float overload on the host too).
template <typename T>
FENESTRA_CPU_GPU inline T BasisAtan2(T y, T x) {
  if constexpr (sizeof(T) == sizeof(float)) {
    return atan2f(y, x);
  } else {
    return atan2(y, x);
  }
}

// Cell of a local direction (need not be unit length), or -1 when it is not above the
// horizon (z <= 0).
template <typename T>
FENESTRA_CPU_GPU inline int BasisCell(const HemisphereBasis& basis, Vec3T<T> d) {
  const T length = sqrt(d.x * d.x + d.y * d.y + d.z * d.z);
  if (!(d.z > 0) || !(length > 0)) return -1;
  // n (1 - cos θ) is the number of cells in the cap down to θ
  const T cap = static_cast<T>(basis.cell_count) * (T(1) - d.z / length);
  int ring = 0;
  while (ring < basis.ring_count - 1 && static_cast<T>(basis.cumulative[ring]) <= cap) ++ring;
  const int first = ring == 0 ? 0 : basis.cumulative[ring - 1];
  const int count = basis.cumulative[ring] - first;
  T phi = BasisAtan2(d.y, d.x);
  if (phi < 0) phi += T(2 * 3.14159265358979323846);
  int j = static_cast<int>(phi * static_cast<T>(count) / T(2 * 3.14159265358979323846));
  if (j >= count) j = count - 1;
  if (j < 0) j = 0;
  return first + j;
}

// A direction within `cell` from two uniform numbers in [0, 1): distributed uniformly in
// solid angle, or with `projected` in projected solid angle (density proportional to
// cos θ, the measure in which radiance crossing the hemisphere's base carries flux).
// Returns a unit vector in the local frame.
template <typename T>
FENESTRA_CPU_GPU inline Vec3T<T> SampleBasisCell(const HemisphereBasis& basis, int cell, T u1, T u2,
                                                 bool projected = false) {
  int ring = 0;
  while (basis.cumulative[ring] <= cell) ++ring;
  const int first = ring == 0 ? 0 : basis.cumulative[ring - 1];
  const int count = basis.cumulative[ring] - first;
  const T n = static_cast<T>(basis.cell_count);
  const T cos_hi = T(1) - static_cast<T>(first) / n;
  const T cos_lo = T(1) - static_cast<T>(basis.cumulative[ring]) / n;
  // Uniform in cos θ (solid angle) or in cos² θ (projected solid angle)
  const T cos_theta =
      projected ? sqrt(fmax(T(0), cos_hi * cos_hi - u1 * (cos_hi * cos_hi - cos_lo * cos_lo)))
                : cos_hi - u1 * (cos_hi - cos_lo);
  const T sin_theta = sqrt(fmax(T(0), T(1) - cos_theta * cos_theta));
  const T phi =
      (static_cast<T>(cell - first) + u2) * T(2 * 3.14159265358979323846) / static_cast<T>(count);
  return {static_cast<T>(sin_theta * cos(phi)), static_cast<T>(sin_theta * sin(phi)), cos_theta};
}

// Centre direction of `cell` (mid-area in cos θ, mid-azimuth), unit, local frame.
Vec3d BasisCellCenter(const HemisphereBasis& basis, int cell);

// Solid angle of every cell: 2π / cell_count [sr].
inline double BasisCellSolidAngle(const HemisphereBasis& basis) {
  return 2 * 3.14159265358979323846 / basis.cell_count;
}

}  // namespace fenestra
