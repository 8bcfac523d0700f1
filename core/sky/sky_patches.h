// Patch centres and solid angles of the Tregenza sky (MF:1) and its Reinhart MF:n
// subdivisions, as gendaymtx defines them.
//
// Tregenza, P. R. (1987), "Subdivision of the sky hemisphere for luminance measurements",
// Lighting Research and Technology 19(1):13-14; Reinhart MF:n as in Radiance's reinhart.cal.
// Band patch of row r (height a = 90 / (7 n + 0.5) degrees, m patches in the row):
// centre altitude (r + 1/2) a, azimuth 2 pi j / m east of north,
// solid angle 2 pi [sin((r + 1) a) - sin(r a)] / m. Zenith cap: half-angle a / 2,
// solid angle 2 pi (1 - cos(a / 2)). Ground (bin 0): altitude -90 degrees, solid angle 2 pi.
#pragma once

#include <vector>

#include "absl/status/statusor.h"
#include "core/common/vec3.h"
#include "core/sky/sky_bin.h"

namespace fenestra {

// One bin of a sky basis: its centre direction and solid angle.
struct SkyPatch {
  double altitude_rad = 0;  // centre altitude above the horizon
  double azimuth_rad = 0;   // centre azimuth from north towards east, in [0, 2 pi)
  double solid_angle_sr = 0;
  Vec3d direction{0, 0, 0};  // unit centre direction, x = east, y = north, z = up
};

// The bins of a Reinhart MF:n sky, bin 0 = ground, 1 .. 144 n^2 + 1 = sky (zenith last).
class SkyPatches {
 public:
  // Largest subdivision accepted by Reinhart().
  static constexpr int kMaxMf = 30;

  // Builds the MF:`mf` basis; mf = 1 is the Tregenza sky. InvalidArgument unless
  // 1 <= mf <= kMaxMf.
  static absl::StatusOr<SkyPatches> Reinhart(int mf);

  int mf() const { return mf_; }
  // Number of bins, ground included (146 for MF:1).
  int size() const { return static_cast<int>(patches_.size()); }
  const SkyPatch& operator[](int bin) const { return patches_[bin]; }
  const std::vector<SkyPatch>& patches() const { return patches_; }

  // Bin of a direction (world frame, need not be normalized); below the horizon -> 0.
  int Bin(Vec3d direction) const { return ReinhartBin(mf_, direction); }

 private:
  SkyPatches(int mf, std::vector<SkyPatch> patches) : mf_(mf), patches_(std::move(patches)) {}

  int mf_;
  std::vector<SkyPatch> patches_;
};

// Unit direction (x = east, y = north, z = up) of altitude and azimuth (east of north).
Vec3d DirectionFromAltAz(double altitude_rad, double azimuth_rad);

}  // namespace fenestra
