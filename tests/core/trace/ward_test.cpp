#include "core/trace/ward.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

namespace fenestra {
namespace {

constexpr double kPi = 3.14159265358979323846;
const Vec3f kNormal{0, 0, 1}, kU{1, 0, 0}, kW{0, 1, 0};

Vec3f Direction(double theta, double phi) {
  return Vec3f{static_cast<float>(std::sin(theta) * std::cos(phi)),
               static_cast<float>(std::sin(theta) * std::sin(phi)),
               static_cast<float>(std::cos(theta))};
}

// The lobe's albedo for light from `v` by quadrature: the integral of f_s cos over the
// hemisphere on a grid of equal steps in polar angle and azimuth, fine enough for the lobe
// (steps of at most a sixtieth of the lobe's width).
double AlbedoByQuadrature(const WardLobe& lobe, Vec3f v) {
  const int rings = std::max(600, static_cast<int>(120 / lobe.alpha)), sectors = 2 * rings;
  double sum = 0;
  for (int i = 0; i < rings; ++i) {
    const double t0 = 0.5 * kPi * i / rings, t1 = 0.5 * kPi * (i + 1) / rings;
    const double theta = 0.5 * (t0 + t1);
    const double cell = (std::cos(t0) - std::cos(t1)) * 2 * kPi / sectors;  // solid angle
    for (int j = 0; j < sectors; ++j) {
      const Vec3f l = Direction(theta, 2 * kPi * (j + 0.5) / sectors);
      sum += lobe.Lobe(kNormal, v, l) * l.z * cell;
    }
  }
  return sum;
}

struct Estimate {
  double mean, standard_error, largest_weight;
};

// The albedo by sampling the lobe: the mean of the samples' weights.
Estimate AlbedoBySampling(const WardLobe& lobe, Vec3f v, int samples, unsigned seed) {
  std::mt19937 random(seed);
  std::uniform_real_distribution<float> uniform(0.0f, 1.0f);
  double sum = 0, squares = 0, largest = 0;
  for (int k = 0; k < samples; ++k) {
    float weight = 0;
    lobe.SampleLobe(kNormal, kU, kW, v, uniform(random), uniform(random), &weight);
    sum += weight, squares += double{weight} * weight;
    largest = std::max<double>(largest, weight);
  }
  const double mean = sum / samples;
  return {mean, std::sqrt((squares / samples - mean * mean) / (samples - 1)), largest};
}

// The lobe is reciprocal: f_s(v, l) = f_s(l, v), for random pairs of directions (a rough lobe,
// so that most pairs have a value).
TEST(WardTest, LobeIsReciprocal) {
  std::mt19937 random(3);
  std::uniform_real_distribution<double> u(0, 1);
  const WardLobe lobe = WardLobe::Metal(0.8f, 0.9f, 0.5f);
  int compared = 0;
  for (int k = 0; k < 10000; ++k) {
    const Vec3f v = Direction(std::acos(u(random)), 2 * kPi * u(random));
    const Vec3f l = Direction(std::acos(u(random)), 2 * kPi * u(random));
    const float a = lobe.Lobe(kNormal, v, l), b = lobe.Lobe(kNormal, l, v);
    EXPECT_EQ(a, b);
    compared += a > 0;
  }
  EXPECT_GT(compared, 5000);
}

// Radiance's plastic keeps the lobe untinted, its metal tints it by the colour; either way the
// diffuse part is colour x (1 - specularity).
TEST(WardTest, PlasticAndMetalAsRadiance) {
  const WardLobe plastic = WardLobe::Plastic(0.8f, 0.05f, 0.1f);
  EXPECT_FLOAT_EQ(plastic.diffuse, 0.76f);
  EXPECT_FLOAT_EQ(plastic.specular, 0.05f);
  const WardLobe metal = WardLobe::Metal(0.8f, 0.9f, 0.05f);
  EXPECT_FLOAT_EQ(metal.diffuse, 0.08f);
  EXPECT_FLOAT_EQ(metal.specular, 0.72f);
}

// A sample's weight is the estimator's: f_s cos_l / pdf at the direction drawn, and below the
// surface nothing.
TEST(WardTest, SampleWeightIsTheLobeOverItsDensity) {
  std::mt19937 random(5);
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  for (const float alpha : {0.02f, 0.1f, 0.4f}) {
    const WardLobe lobe{0.0f, 0.9f, alpha};
    for (const double incidence : {0.0, 0.7, 1.3}) {
      const Vec3f v = Direction(incidence, 0.4);
      int valid = 0;
      for (int k = 0; k < 2000; ++k) {
        float weight = -1;
        const Vec3f l = lobe.SampleLobe(kNormal, kU, kW, v, u(random), u(random), &weight);
        if (!(l.z > 0.0f)) {
          EXPECT_EQ(weight, 0.0f);
          continue;
        }
        ++valid;
        const float expected = lobe.Lobe(kNormal, v, l) * l.z / lobe.LobePdf(kNormal, v, l);
        EXPECT_NEAR(weight, expected, 2e-3f * expected) << alpha << " " << incidence;
      }
      EXPECT_GT(valid, 1000);
    }
  }
}

// The lobe's albedo by sampling equals its integral by quadrature within 4 standard errors
// (400 000 samples, fixed seeds), at several roughnesses and incidences; with rho_s = 1 it stays
// at most 1 (the model's bounded albedo), and no weight exceeds 2 rho_s.
TEST(WardTest, SamplingIntegratesTheLobe) {
  for (const float alpha : {0.05f, 0.15f, 0.4f}) {
    const WardLobe lobe{0.0f, 1.0f, alpha};
    for (const double incidence : {0.0, 0.8, 1.4}) {
      const Vec3f v = Direction(incidence, 1.1);
      const double quadrature = AlbedoByQuadrature(lobe, v);
      const Estimate sampled = AlbedoBySampling(lobe, v, 400000, 17);
      EXPECT_LT(std::abs(sampled.mean - quadrature), 4 * sampled.standard_error + 1e-4)
          << "alpha " << alpha << ", incidence " << incidence << ": sampled " << sampled.mean
          << " +- " << sampled.standard_error << ", quadrature " << quadrature;
      EXPECT_LE(quadrature, 1.0 + 1e-3) << alpha << " " << incidence;
      EXPECT_LE(sampled.largest_weight, 2.0);
      EXPECT_GT(quadrature, 0.5);
    }
  }
}

// Nearly a mirror (roughness 1e-4): every weight finite and within [0, 2 rho_s], so the
// variance stays bounded, and at normal incidence the mirror's rho_s comes back.
TEST(WardTest, NearMirrorStaysFinite) {
  const WardLobe lobe{0.0f, 0.9f, 1e-4f};
  const Estimate normal = AlbedoBySampling(lobe, Direction(0.0, 0.0), 100000, 23);
  EXPECT_NEAR(normal.mean, 0.9, 1e-3);
  EXPECT_LE(normal.largest_weight, 1.8);
  const Estimate grazing = AlbedoBySampling(lobe, Direction(1.55, 0.0), 100000, 29);
  EXPECT_TRUE(std::isfinite(grazing.mean));
  EXPECT_NEAR(grazing.mean, 0.9, 0.01);
  EXPECT_LE(grazing.largest_weight, 1.8);
}

}  // namespace
}  // namespace fenestra
