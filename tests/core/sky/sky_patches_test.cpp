#include "core/sky/sky_patches.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <numbers>
#include <random>
#include <vector>

#include "core/sky/sky_bin.h"

namespace fenestra {
namespace {

constexpr double kPi = std::numbers::pi;
constexpr double kDeg = kPi / 180;

Vec3f ToFloat(Vec3d v) {
  return {static_cast<float>(v.x), static_cast<float>(v.y), static_cast<float>(v.z)};
}

TEST(SkyPatchesTest, TregenzaLayout) {
  absl::StatusOr<SkyPatches> sky = SkyPatches::Reinhart(1);
  ASSERT_TRUE(sky.ok()) << sky.status();
  ASSERT_EQ(sky->size(), 146);
  EXPECT_EQ(ReinhartBinCount(1), 146);
  // First bin of each row, its altitude and the solid angle of its patches
  const int first[8] = {1, 31, 61, 85, 109, 127, 139, 145};
  const double omega[8] = {0.043545, 0.041642, 0.047398, 0.040673,
                           0.042893, 0.044522, 0.045517, 0.0344199465};
  for (int row = 0; row < 8; ++row) {
    const SkyPatch& p = (*sky)[first[row]];
    EXPECT_NEAR(p.altitude_rad / kDeg, row < 7 ? 6 + 12 * row : 90, 1e-9) << row;
    EXPECT_NEAR(p.azimuth_rad, 0, 1e-12);
    EXPECT_NEAR(p.solid_angle_sr, omega[row], row < 7 ? 5e-7 : 1e-10) << row;
  }
  // Patch 1 due north, patch 2 12 degrees east of north
  EXPECT_NEAR((*sky)[1].direction.y, std::cos(6 * kDeg), 1e-12);
  EXPECT_NEAR((*sky)[1].direction.x, 0, 1e-12);
  EXPECT_NEAR((*sky)[2].azimuth_rad / kDeg, 12, 1e-9);
  EXPECT_GT((*sky)[2].direction.x, 0);
  // Ground
  EXPECT_NEAR((*sky)[0].altitude_rad, -kPi / 2, 1e-12);
  EXPECT_NEAR((*sky)[0].solid_angle_sr, 2 * kPi, 1e-12);
}

TEST(SkyPatchesTest, SolidAnglesSumToHemisphere) {
  for (int mf : {1, 2, 3, 4, 6}) {
    absl::StatusOr<SkyPatches> sky = SkyPatches::Reinhart(mf);
    ASSERT_TRUE(sky.ok());
    EXPECT_EQ(sky->size(), 144 * mf * mf + 2);
    double total = 0;
    for (int bin = 1; bin < sky->size(); ++bin) total += (*sky)[bin].solid_angle_sr;
    EXPECT_NEAR(total, 2 * kPi, 1e-12) << "MF " << mf;
  }
}

TEST(SkyPatchesTest, Mf2RowStarts) {
  absl::StatusOr<SkyPatches> sky = SkyPatches::Reinhart(2);
  ASSERT_TRUE(sky.ok());
  EXPECT_EQ(sky->size(), 578);
  const int first[] = {1, 61, 121, 181, 241, 289, 337, 385, 433, 469, 505, 529, 553, 565, 577};
  const double row_height = 90.0 / 14.5;
  for (int row = 0; row < 15; ++row) {
    const SkyPatch& p = (*sky)[first[row]];
    EXPECT_NEAR(p.azimuth_rad, 0, 1e-12) << row;
    EXPECT_NEAR(p.altitude_rad / kDeg, row < 14 ? (row + 0.5) * row_height : 90, 1e-9) << row;
    if (row > 0) {
      EXPECT_GT((*sky)[first[row] - 1].azimuth_rad, 300 * kDeg) << row;
    }
  }
  EXPECT_NEAR((*sky)[577].solid_angle_sr, 0.0092148, 1e-7);
}

TEST(SkyPatchesTest, RejectsBadSubdivision) {
  EXPECT_FALSE(SkyPatches::Reinhart(0).ok());
  EXPECT_FALSE(SkyPatches::Reinhart(-1).ok());
  EXPECT_FALSE(SkyPatches::Reinhart(SkyPatches::kMaxMf + 1).ok());
}

TEST(SkyPatchesTest, PatchCentresMapToThemselves) {
  for (int mf : {1, 2, 4}) {
    absl::StatusOr<SkyPatches> sky = SkyPatches::Reinhart(mf);
    ASSERT_TRUE(sky.ok());
    for (int bin = 1; bin < sky->size(); ++bin) {
      const Vec3d d = (*sky)[bin].direction;
      ASSERT_EQ(sky->Bin(d), bin) << "MF " << mf;
      ASSERT_EQ(ReinhartBin(mf, ToFloat(d)), bin) << "MF " << mf;
      if (mf == 1) {
        ASSERT_EQ(TregenzaBin(d), bin);
        ASSERT_EQ(TregenzaBin(ToFloat(d)), bin);
      }
    }
  }
}

TEST(SkyPatchesTest, TregenzaBinEdges) {
  auto dir = [](double alt_deg, double az_deg) {
    return DirectionFromAltAz(alt_deg * kDeg, az_deg * kDeg);
  };
  // Patch 1 spans azimuth [-6, 6) degrees around north
  EXPECT_EQ(TregenzaBin(dir(3, -5.9)), 1);
  EXPECT_EQ(TregenzaBin(dir(3, 5.9)), 1);
  EXPECT_EQ(TregenzaBin(dir(3, 6.1)), 2);
  EXPECT_EQ(TregenzaBin(dir(3, -6.1)), 30);
  EXPECT_EQ(TregenzaBin(dir(3, 96)), 9);    // the patch centred 96 degrees east of north
  EXPECT_EQ(TregenzaBin(dir(3, 264)), 23);  // and its mirror in the west
  // Rows
  EXPECT_EQ(TregenzaBin(dir(11.9, 0)), 1);
  EXPECT_EQ(TregenzaBin(dir(12.1, 0)), 31);
  EXPECT_EQ(TregenzaBin(dir(83.9, 0)), 139);
  EXPECT_EQ(TregenzaBin(dir(84.1, 0)), 145);
  EXPECT_EQ(TregenzaBin(Vec3d{0, 0, 1}), 145);
  EXPECT_EQ(TregenzaBin(Vec3f{0, 0, 1}), 145);
  // Horizon belongs to the sky, anything below to the ground
  EXPECT_EQ(TregenzaBin(Vec3d{0, 1, 0}), 1);
  EXPECT_EQ(TregenzaBin(Vec3d{0, 1, -1e-9}), 0);
  EXPECT_EQ(TregenzaBin(Vec3f{0.3f, 0.2f, -0.9f}), 0);
  EXPECT_EQ(TregenzaBin(Vec3d{0, 0, -1}), 0);
  // Unnormalized directions
  EXPECT_EQ(TregenzaBin(Vec3d{0, 0, 7}), 145);
  EXPECT_EQ(TregenzaBin(dir(30, 90) * 12.5), TregenzaBin(dir(30, 90)));
  // Degenerate input
  EXPECT_EQ(TregenzaBin(Vec3d{0, 0, 0}), 0);
  const double nan = std::numeric_limits<double>::quiet_NaN();
  EXPECT_EQ(TregenzaBin(Vec3d{nan, 0, 1}), 0);
  EXPECT_EQ(TregenzaBin(Vec3d{0, 0, nan}), 0);
}

// Uniform directions over the sphere fall into each sky bin in proportion to its solid
// angle: the bin lookup and the solid angles describe the same partition.
TEST(SkyPatchesTest, BinFrequenciesMatchSolidAngles) {
  for (int mf : {1, 2}) {
    absl::StatusOr<SkyPatches> sky = SkyPatches::Reinhart(mf);
    ASSERT_TRUE(sky.ok());
    std::mt19937_64 rng(12345 + mf);
    std::uniform_real_distribution<double> u(0, 1);
    const int n = 1'000'000;
    std::vector<int> count(sky->size(), 0);
    int float_mismatch = 0;
    for (int i = 0; i < n; ++i) {
      const double z = 2 * u(rng) - 1;
      const double phi = 2 * kPi * u(rng);
      const double r = std::sqrt(1 - z * z);
      const Vec3d d{r * std::cos(phi), r * std::sin(phi), z};
      const int bin = sky->Bin(d);
      ++count[bin];
      if (ReinhartBin(mf, ToFloat(d)) != bin) ++float_mismatch;
    }
    EXPECT_NEAR(count[0] / double(n), 0.5, 5 * std::sqrt(0.25 / n));
    double worst_z = 0;
    for (int bin = 1; bin < sky->size(); ++bin) {
      const double p = (*sky)[bin].solid_angle_sr / (4 * kPi);
      const double z = (count[bin] - n * p) / std::sqrt(n * p * (1 - p));
      worst_z = std::max(worst_z, std::fabs(z));
    }
    // Max of |z| over up to 577 bins: beyond 5 standard errors is a partition mismatch.
    EXPECT_LT(worst_z, 5) << "MF " << mf;
    // Float and double differ only on bin edges.
    EXPECT_LT(float_mismatch, n / 10000) << "MF " << mf;
  }
}

}  // namespace
}  // namespace fenestra
