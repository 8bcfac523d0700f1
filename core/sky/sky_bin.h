// Sky-patch bin of a direction for the Tregenza 145-patch sky and its Reinhart MF:n
// subdivisions, usable on CPU and GPU.
//
// Tregenza, P. R. (1987), "Subdivision of the sky hemisphere for luminance measurements",
// Lighting Research and Technology 19(1):13-14: 8 rows of 30, 30, 24, 24, 18, 12, 6, 1
// patches in 12 degree bands with a 6 degree zenith cap. Reinhart MF:n splits every
// Tregenza row into n rows of n times as many patches, with row height
// 90 / (7 n + 0.5) degrees, as in Radiance's reinhart.cal and gendaymtx.
//
// Numbering follows gendaymtx: bin 0 is the ground (altitude below 0), bin 1 is centred on
// due north at the horizon and numbering runs north -> east (clockwise seen from above),
// row by row upwards, ending with the zenith cap. Directions are in the world frame
// (x = east, y = north, z = up) and need not be normalized.
#pragma once

#include <math.h>

#include "core/common/cpu_gpu.h"
#include "core/common/vec3.h"

namespace fenestra {

namespace sky_bin_internal {

FENESTRA_CPU_GPU inline float Atan2(float y, float x) { return atan2f(y, x); }
FENESTRA_CPU_GPU inline double Atan2(double y, double x) { return atan2(y, x); }
FENESTRA_CPU_GPU inline float Sqrt(float x) { return sqrtf(x); }
FENESTRA_CPU_GPU inline double Sqrt(double x) { return sqrt(x); }

// Patches per Tregenza band row 0..6 (the zenith cap is separate).
FENESTRA_CPU_GPU inline int TregenzaRowPatches(int row) {
  switch (row) {
    case 0:
    case 1:
      return 30;
    case 2:
    case 3:
      return 24;
    case 4:
      return 18;
    case 5:
      return 12;
    default:
      return 6;
  }
}

}  // namespace sky_bin_internal

// Number of bins of the Reinhart MF:`mf` basis, ground included: 144 mf^2 + 2.
FENESTRA_CPU_GPU inline int ReinhartBinCount(int mf) { return 144 * mf * mf + 2; }

// Bin (0 = ground, 1 .. 144 mf^2 + 1 = sky) of direction `dir` in the Reinhart MF:`mf`
// basis (mf >= 1; mf = 1 is the Tregenza sky). A zero or NaN direction maps to bin 0.
template <typename T>
FENESTRA_CPU_GPU inline int ReinhartBin(int mf, Vec3T<T> dir) {
  using sky_bin_internal::Atan2;
  using sky_bin_internal::Sqrt;
  const T kPi = T(3.14159265358979323846);
  const T horizontal = Sqrt(dir.x * dir.x + dir.y * dir.y);
  if (!(dir.z >= T(0)) || !(horizontal >= T(0)) || (dir.z == T(0) && horizontal == T(0))) {
    return 0;
  }
  // Altitude row; the zenith cap starts at 7 mf row heights.
  const T altitude = Atan2(dir.z, horizontal);
  const T row_height = (kPi / T(2)) / (T(7 * mf) + T(0.5));
  const int row = static_cast<int>(altitude / row_height);
  const int band_rows = 7 * mf;
  if (row >= band_rows) return ReinhartBinCount(mf) - 1;
  // Bins before this row.
  int first = 1;
  for (int r = 0; r < row; ++r) first += mf * sky_bin_internal::TregenzaRowPatches(r / mf);
  // Azimuth from north towards east, patches centred on multiples of 2 pi / n.
  const int n = mf * sky_bin_internal::TregenzaRowPatches(row / mf);
  T azimuth = Atan2(dir.x, dir.y);
  if (azimuth < T(0)) azimuth += T(2) * kPi;
  int column = static_cast<int>(azimuth * T(n) / (T(2) * kPi) + T(0.5));
  if (column >= n) column -= n;
  if (column < 0) column = 0;
  return first + column;
}

// Tregenza bin (0 = ground, 1..145) of direction `dir`: ReinhartBin with mf = 1.
template <typename T>
FENESTRA_CPU_GPU inline int TregenzaBin(Vec3T<T> dir) {
  return ReinhartBin(1, dir);
}

}  // namespace fenestra
