#include "core/sky/perez.h"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <vector>

namespace fenestra {
namespace {

constexpr double kPi = std::numbers::pi;
constexpr double kDeg = kPi / 180;

// Horizontal illuminance [lx] of a sky column (sky bins only), by the patch-centre rule.
double HorizontalIlluminance(const SkyPatches& patches, const std::vector<double>& radiance) {
  double sum = 0;
  for (int i = 1; i < patches.size(); ++i) {
    sum += radiance[i] * std::sin(patches[i].altitude_rad) * patches[i].solid_angle_sr;
  }
  return sum * kWhiteEfficacyLmPerW;
}

TEST(PerezTest, ModelZenithIsClamped) {
  EXPECT_DOUBLE_EQ(PerezSunZenithRad(-10 * kDeg), kPi / 2);
  EXPECT_DOUBLE_EQ(PerezSunZenithRad(0), kPi / 2);
  EXPECT_NEAR(PerezSunZenithRad(30 * kDeg), 60 * kDeg, 1e-15);
  EXPECT_DOUBLE_EQ(PerezSunZenithRad(87 * kDeg), 3 * kDeg);
  EXPECT_DOUBLE_EQ(PerezSunZenithRad(90 * kDeg), 3 * kDeg);
}

TEST(PerezTest, AirMassEccentricityWater) {
  EXPECT_NEAR(RelativeAirMass(0), 1.0, 1e-3);
  EXPECT_NEAR(RelativeAirMass(60 * kDeg), 1.99, 0.01);
  EXPECT_NEAR(RelativeAirMass(kPi / 2), 36.2, 0.5);  // Kasten's horizon value (about 36)
  EXPECT_NEAR(EccentricityCorrection(1), 1.0350, 1e-3);
  EXPECT_NEAR(EccentricityCorrection(183), 0.9668, 1e-3);
  EXPECT_NEAR(PrecipitableWaterCm(11), std::exp(0.695), 1e-12);
}

TEST(PerezTest, ClearnessCategories) {
  EXPECT_EQ(ClearnessCategory(0.5), 0);
  EXPECT_EQ(ClearnessCategory(1.0), 0);
  EXPECT_EQ(ClearnessCategory(1.0649), 0);
  EXPECT_EQ(ClearnessCategory(1.065), 1);
  EXPECT_EQ(ClearnessCategory(1.23), 2);
  EXPECT_EQ(ClearnessCategory(1.5), 3);
  EXPECT_EQ(ClearnessCategory(1.95), 4);
  EXPECT_EQ(ClearnessCategory(2.8), 5);
  EXPECT_EQ(ClearnessCategory(4.5), 6);
  EXPECT_EQ(ClearnessCategory(6.2), 7);
  EXPECT_EQ(ClearnessCategory(11.9), 7);
  EXPECT_EQ(ClearnessCategory(1e9), 7);
}

TEST(PerezTest, ClearnessAndBrightnessClamps) {
  // No diffuse: infinitely clear, clamped to 11.9; brightness raised to 0.01
  PerezSkyCondition c = ComputePerezSkyCondition(800, 0, 40 * kDeg, 100, 11, SkyQuantity::kVisible);
  EXPECT_DOUBLE_EQ(c.clearness, 11.9);
  EXPECT_EQ(c.category, 7);
  EXPECT_DOUBLE_EQ(c.brightness, 0.01);
  EXPECT_DOUBLE_EQ(c.diffuse_illuminance, 0);
  EXPECT_GT(c.direct_illuminance, 800 * 80);
  // No direct: overcast, clearness exactly 1
  c = ComputePerezSkyCondition(0, 200, 40 * kDeg, 100, 11, SkyQuantity::kVisible);
  EXPECT_DOUBLE_EQ(c.clearness, 1);
  EXPECT_EQ(c.category, 0);
  EXPECT_DOUBLE_EQ(c.direct_illuminance, 0);
  // Bright diffuse at a low sun: brightness clamped to 0.6
  c = ComputePerezSkyCondition(0, 400, 2 * kDeg, 100, 11, SkyQuantity::kVisible);
  EXPECT_DOUBLE_EQ(c.brightness, 0.6);
  // Sun below the horizon: the model zenith is 90 degrees
  c = ComputePerezSkyCondition(50, 20, -3 * kDeg, 100, 11, SkyQuantity::kVisible);
  EXPECT_DOUBLE_EQ(c.sun_zenith_rad, kPi / 2);
  EXPECT_GE(c.clearness, 1);
  EXPECT_LE(c.clearness, 11.9);
  EXPECT_TRUE(std::isfinite(c.direct_illuminance));
}

TEST(PerezTest, BrightnessIsRaisedForIntermediateSkies) {
  PerezSkyCondition c;
  c.sun_zenith_rad = 40 * kDeg;
  c.clearness = 2.0;
  c.category = ClearnessCategory(2.0);
  c.brightness = 0.05;
  const PerezLuminanceParams low = ComputePerezLuminanceParams(c);
  c.brightness = 0.2;
  const PerezLuminanceParams raised = ComputePerezLuminanceParams(c);
  EXPECT_DOUBLE_EQ(low.a, raised.a);
  EXPECT_DOUBLE_EQ(low.c, raised.c);
  EXPECT_DOUBLE_EQ(low.e, raised.e);
}

TEST(PerezTest, LuminousEfficacyIsPlausible) {
  // Clear sky, sun at 50 degrees, dew point 11 C
  const PerezSkyCondition clear =
      ComputePerezSkyCondition(850, 90, 50 * kDeg, 172, 11, SkyQuantity::kVisible);
  EXPECT_EQ(clear.category, 7);
  EXPECT_GT(clear.direct_illuminance / 850, 90);
  EXPECT_LT(clear.direct_illuminance / 850, 110);
  EXPECT_GT(clear.diffuse_illuminance / 90, 110);
  EXPECT_LT(clear.diffuse_illuminance / 90, 150);
  // Overcast
  const PerezSkyCondition overcast =
      ComputePerezSkyCondition(0, 250, 50 * kDeg, 172, 11, SkyQuantity::kVisible);
  EXPECT_GT(overcast.diffuse_illuminance / 250, 105);
  EXPECT_LT(overcast.diffuse_illuminance / 250, 130);
}

TEST(PerezTest, SolarQuantityUsesWhiteEfficacy) {
  const PerezSkyCondition c =
      ComputePerezSkyCondition(600, 120, 35 * kDeg, 40, 5, SkyQuantity::kSolar);
  EXPECT_DOUBLE_EQ(c.diffuse_illuminance, 120 * 179);
  EXPECT_DOUBLE_EQ(c.direct_illuminance, 600 * 179);
}

TEST(PerezTest, OvercastSkyIsBrighterAtTheZenith) {
  absl::StatusOr<SkyPatches> patches = SkyPatches::Reinhart(1);
  ASSERT_TRUE(patches.ok());
  const SolarPosition sun{45 * kDeg, 0};
  const PerezSkyCondition c =
      ComputePerezSkyCondition(0, 200, sun.altitude_rad, 100, 11, SkyQuantity::kVisible);
  std::vector<double> radiance(patches->size());
  ComputePerezSkyRadiance(c, sun, *patches, radiance);
  // Overcast gradation: zenith 1.5 to 3.5 times the horizon (CIE overcast: 3)
  const double ratio = radiance[145] / radiance[16];
  EXPECT_GT(ratio, 1.5);
  EXPECT_LT(ratio, 3.5);
}

TEST(PerezTest, ClearSkyPeaksNearTheSun) {
  absl::StatusOr<SkyPatches> patches = SkyPatches::Reinhart(1);
  ASSERT_TRUE(patches.ok());
  const SolarPosition sun{30 * kDeg, 90 * kDeg};  // sun in the east, in row 3
  const PerezSkyCondition c =
      ComputePerezSkyCondition(800, 80, sun.altitude_rad, 100, 11, SkyQuantity::kVisible);
  std::vector<double> radiance(patches->size());
  ComputePerezSkyRadiance(c, sun, *patches, radiance);
  const int toward_sun = patches->Bin(DirectionFromAltAz(30 * kDeg, 90 * kDeg));
  const int away = patches->Bin(DirectionFromAltAz(30 * kDeg, 270 * kDeg));
  int brightest = 1;
  for (int i = 1; i < patches->size(); ++i) {
    if (radiance[i] > radiance[brightest]) brightest = i;
  }
  EXPECT_EQ(brightest, toward_sun);
  EXPECT_GT(radiance[toward_sun], 5 * radiance[away]);
}

TEST(PerezTest, SkyIsNormalizedToDiffuseIlluminance) {
  for (int mf : {1, 2}) {
    absl::StatusOr<SkyPatches> patches = SkyPatches::Reinhart(mf);
    ASSERT_TRUE(patches.ok());
    std::vector<double> radiance(patches->size());
    for (double alt : {-2.0, 1.0, 10.0, 45.0, 88.0}) {
      for (double dni : {0.0, 100.0, 900.0}) {
        const SolarPosition sun{alt * kDeg, 200 * kDeg};
        const PerezSkyCondition c =
            ComputePerezSkyCondition(dni, 150, sun.altitude_rad, 200, 11, SkyQuantity::kVisible);
        ComputePerezSkyRadiance(c, sun, *patches, radiance);
        EXPECT_EQ(radiance[0], 0);
        EXPECT_NEAR(HorizontalIlluminance(*patches, radiance), c.diffuse_illuminance,
                    1e-9 * c.diffuse_illuminance)
            << "MF " << mf << " altitude " << alt << " dni " << dni;
      }
    }
  }
}

TEST(PerezTest, ZeroDiffuseGivesBlackSky) {
  absl::StatusOr<SkyPatches> patches = SkyPatches::Reinhart(1);
  ASSERT_TRUE(patches.ok());
  const SolarPosition sun{40 * kDeg, 10 * kDeg};
  const PerezSkyCondition c =
      ComputePerezSkyCondition(700, 0, sun.altitude_rad, 10, 11, SkyQuantity::kVisible);
  std::vector<double> radiance(patches->size(), -1);
  ComputePerezSkyRadiance(c, sun, *patches, radiance);
  for (double v : radiance) EXPECT_EQ(v, 0);
}

TEST(PerezTest, FiniteAndNonNegativeOverInputRange) {
  absl::StatusOr<SkyPatches> patches = SkyPatches::Reinhart(1);
  ASSERT_TRUE(patches.ok());
  std::vector<double> radiance(patches->size());
  for (double alt = -10; alt <= 90; alt += 2.5) {
    for (double dni : {0.0, 1e-3, 5.0, 300.0, 1100.0}) {
      for (double dhi : {0.0, 1e-3, 2.0, 80.0, 600.0}) {
        if (dni + dhi <= 0) continue;
        for (double dew : {-40.0, 11.0, 30.0}) {
          const SolarPosition sun{alt * kDeg, 123 * kDeg};
          const PerezSkyCondition c =
              ComputePerezSkyCondition(dni, dhi, sun.altitude_rad, 50, dew, SkyQuantity::kVisible);
          ASSERT_TRUE(std::isfinite(c.diffuse_illuminance) && c.diffuse_illuminance >= 0);
          ASSERT_TRUE(std::isfinite(c.direct_illuminance) && c.direct_illuminance >= 0);
          ComputePerezSkyRadiance(c, sun, *patches, radiance);
          for (double v : radiance) {
            ASSERT_TRUE(std::isfinite(v) && v >= 0)
                << "altitude " << alt << " dni " << dni << " dhi " << dhi << " dew " << dew;
          }
        }
      }
    }
  }
}

}  // namespace
}  // namespace fenestra
