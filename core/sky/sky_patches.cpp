#include "core/sky/sky_patches.h"

#include <cmath>
#include <numbers>
#include <utility>

#include "absl/status/status.h"
#include "absl/strings/str_cat.h"

namespace fenestra {

Vec3d DirectionFromAltAz(double altitude_rad, double azimuth_rad) {
  const double horizontal = std::cos(altitude_rad);
  return {horizontal * std::sin(azimuth_rad), horizontal * std::cos(azimuth_rad),
          std::sin(altitude_rad)};
}

absl::StatusOr<SkyPatches> SkyPatches::Reinhart(int mf) {
  if (mf < 1 || mf > kMaxMf) {
    return absl::InvalidArgumentError(
        absl::StrCat("sky subdivision MF must be in [1, ", kMaxMf, "], got ", mf));
  }
  const double row_height = (std::numbers::pi / 2) / (7 * mf + 0.5);
  std::vector<SkyPatch> patches;
  patches.reserve(ReinhartBinCount(mf));

  // Ground
  patches.push_back({-std::numbers::pi / 2, 0, 2 * std::numbers::pi, {0, 0, -1}});

  // Band rows, north -> east, from the horizon up
  for (int row = 0; row < 7 * mf; ++row) {
    const int n = mf * sky_bin_internal::TregenzaRowPatches(row / mf);
    const double altitude = (row + 0.5) * row_height;
    const double solid_angle =
        2 * std::numbers::pi * (std::sin((row + 1) * row_height) - std::sin(row * row_height)) / n;
    for (int j = 0; j < n; ++j) {
      const double azimuth = 2 * std::numbers::pi * j / n;
      patches.push_back({altitude, azimuth, solid_angle, DirectionFromAltAz(altitude, azimuth)});
    }
  }

  // Zenith cap
  patches.push_back(
      {std::numbers::pi / 2, 0, 2 * std::numbers::pi * (1 - std::cos(row_height / 2)), {0, 0, 1}});
  return SkyPatches(mf, std::move(patches));
}

}  // namespace fenestra
