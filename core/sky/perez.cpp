#include "core/sky/perez.h"

#include <algorithm>
#include <cmath>
#include <numbers>

namespace fenestra {
namespace {

constexpr double kSolarConstantWm2 = 1367;

// Perez et al. (1990), Table 4: diffuse (eq. 7) and direct (eq. 8) luminous efficacy
// coefficients a, b, c, d per clearness category.
constexpr double kDiffuseEfficacy[8][4] = {
    {97.24, -0.46, 12.00, -8.91},   {107.22, 1.15, 0.59, -3.95},    {104.97, 2.96, -5.53, -8.77},
    {102.39, 5.59, -13.95, -13.90}, {100.71, 5.94, -22.75, -23.74}, {106.42, 3.83, -36.15, -28.83},
    {141.88, 1.90, -53.24, -14.03}, {152.23, 0.35, -45.27, -7.98}};
constexpr double kDirectEfficacy[8][4] = {
    {57.20, -4.55, -2.98, 117.12}, {98.99, -3.46, -1.21, 12.38},  {109.83, -4.90, -1.71, -8.81},
    {110.34, -5.84, -1.99, -4.56}, {106.36, -3.97, -1.75, -6.16}, {107.19, -1.25, -1.51, -26.73},
    {105.75, 0.77, -1.26, -34.44}, {101.18, 1.58, -1.10, -8.29}};

// Perez et al. (1993), Table 1: x1..x4 for each of a, b, c, d, e per clearness category.
constexpr double kLuminanceCoefficients[8][5][4] = {{{1.3525, -0.2576, -0.2690, -1.4366},
                                                     {-0.7670, 0.0007, 1.2734, -0.1233},
                                                     {2.8000, 0.6004, 1.2375, 1.0000},
                                                     {1.8734, 0.6297, 0.9738, 0.2809},
                                                     {0.0356, -0.1246, -0.5718, 0.9938}},
                                                    {{-1.2219, -0.7730, 1.4148, 1.1016},
                                                     {-0.2054, 0.0367, -3.9128, 0.9156},
                                                     {6.9750, 0.1774, 6.4477, -0.1239},
                                                     {-1.5798, -0.5081, -1.7812, 0.1080},
                                                     {0.2624, 0.0672, -0.2190, -0.4285}},
                                                    {{-1.1000, -0.2515, 0.8952, 0.0156},
                                                     {0.2782, -0.1812, -4.5000, 1.1766},
                                                     {24.7219, -13.0812, -37.7000, 34.8438},
                                                     {-5.0000, 1.5218, 3.9229, -2.6204},
                                                     {-0.0156, 0.1597, 0.4199, -0.5562}},
                                                    {{-0.5484, -0.6654, -0.2672, 0.7117},
                                                     {0.7234, -0.6219, -5.6812, 2.6297},
                                                     {33.3389, -18.3000, -62.2500, 52.0781},
                                                     {-3.5000, 0.0016, 1.1477, 0.1062},
                                                     {0.4659, -0.3296, -0.0876, -0.0329}},
                                                    {{-0.6000, -0.3566, -2.5000, 2.3250},
                                                     {0.2937, 0.0496, -5.6812, 1.8415},
                                                     {21.0000, -4.7656, -21.5906, 7.2492},
                                                     {-3.5000, -0.1554, 1.4062, 0.3988},
                                                     {0.0032, 0.0766, -0.0656, -0.1294}},
                                                    {{-1.0156, -0.3670, 1.0078, 1.4051},
                                                     {0.2875, -0.5328, -3.8500, 3.3750},
                                                     {14.0000, -0.9999, -7.1406, 7.5469},
                                                     {-3.4000, -0.1078, -1.0750, 1.5702},
                                                     {-0.0672, 0.4016, 0.3017, -0.4844}},
                                                    {{-1.0000, 0.0211, 0.5025, -0.5119},
                                                     {-0.3000, 0.1922, 0.7023, -1.6317},
                                                     {19.0000, -5.0000, 1.2438, -1.9094},
                                                     {-4.0000, 0.0250, 0.3844, 0.2656},
                                                     {1.0468, -0.3788, -2.4517, 1.4656}},
                                                    {{-1.0500, 0.0289, 0.4260, 0.3590},
                                                     {-0.3250, 0.1156, 0.7781, 0.0025},
                                                     {31.0625, -14.5000, -46.1148, 55.3750},
                                                     {-7.2312, 0.4050, 13.3500, 0.6234},
                                                     {1.5000, -0.6426, 1.8564, 0.5636}}};

// Upper edges of clearness categories 0..6 (category 7 is open above).
constexpr double kClearnessUpperEdges[7] = {1.065, 1.230, 1.500, 1.950, 2.800, 4.500, 6.200};

constexpr double kMinClearness = 1.0;
constexpr double kMaxClearness = 11.9;
constexpr double kMinBrightness = 0.01;
constexpr double kMaxBrightness = 0.6;

}  // namespace

double PerezSunZenithRad(double solar_altitude_rad) {
  if (solar_altitude_rad <= 0) return std::numbers::pi / 2;
  if (solar_altitude_rad >= 87 * std::numbers::pi / 180) return 3 * std::numbers::pi / 180;
  return std::numbers::pi / 2 - solar_altitude_rad;
}

double RelativeAirMass(double zenith_rad) {
  return 1 / (std::cos(zenith_rad) +
              0.15 * std::pow(93.885 - zenith_rad * 180 / std::numbers::pi, -1.253));
}

double EccentricityCorrection(int day_of_year) {
  const double day_angle = (day_of_year - 1) * (2 * std::numbers::pi / 365);
  return 1.00011 + 0.034221 * std::cos(day_angle) + 0.00128 * std::sin(day_angle) +
         0.000719 * std::cos(2 * day_angle) + 0.000077 * std::sin(2 * day_angle);
}

double PrecipitableWaterCm(double dew_point_c) { return std::exp(0.07 * dew_point_c - 0.075); }

int ClearnessCategory(double clearness) {
  int category = 0;
  while (category < 7 && !(clearness < kClearnessUpperEdges[category])) ++category;
  return category;
}

PerezSkyCondition ComputePerezSkyCondition(double direct_normal_wm2, double diffuse_horizontal_wm2,
                                           double solar_altitude_rad, int day_of_year,
                                           double dew_point_c, SkyQuantity quantity) {
  PerezSkyCondition sky;
  const double zenith = PerezSunZenithRad(solar_altitude_rad);
  sky.sun_zenith_rad = zenith;

  // Clearness (1990, eq. 1) and brightness (eq. 2), clamped as gendaymtx does
  const double zenith_cubed = zenith * zenith * zenith;
  const double clearness =
      diffuse_horizontal_wm2 > 0
          ? ((diffuse_horizontal_wm2 + direct_normal_wm2) / diffuse_horizontal_wm2 +
             1.041 * zenith_cubed) /
                (1 + 1.041 * zenith_cubed)
          : kMaxClearness;
  sky.clearness = std::clamp(clearness, kMinClearness, kMaxClearness);
  const double brightness = diffuse_horizontal_wm2 * RelativeAirMass(zenith) /
                            (kSolarConstantWm2 * EccentricityCorrection(day_of_year));
  sky.brightness = std::clamp(brightness, kMinBrightness, kMaxBrightness);
  sky.category = ClearnessCategory(sky.clearness);

  // Luminous efficacy (1990, eqs. 7 and 8)
  if (quantity == SkyQuantity::kSolar) {
    sky.diffuse_illuminance = diffuse_horizontal_wm2 * kWhiteEfficacyLmPerW;
    sky.direct_illuminance = direct_normal_wm2 * kWhiteEfficacyLmPerW;
  } else {
    const double water = PrecipitableWaterCm(dew_point_c);
    const double* kd = kDiffuseEfficacy[sky.category];
    const double* kb = kDirectEfficacy[sky.category];
    const double diffuse_efficacy =
        kd[0] + kd[1] * water + kd[2] * std::cos(zenith) + kd[3] * std::log(sky.brightness);
    const double direct_efficacy = std::max(
        0.0, kb[0] + kb[1] * water + kb[2] * std::exp(5.73 * zenith - 5) + kb[3] * sky.brightness);
    sky.diffuse_illuminance = diffuse_horizontal_wm2 * diffuse_efficacy;
    sky.direct_illuminance = direct_normal_wm2 * direct_efficacy;
  }
  return sky;
}

PerezLuminanceParams ComputePerezLuminanceParams(const PerezSkyCondition& sky) {
  const double z = sky.sun_zenith_rad;
  double delta = sky.brightness;
  if (sky.clearness > 1.065 && sky.clearness < 2.8 && delta < 0.2) delta = 0.2;
  const auto& x = kLuminanceCoefficients[sky.category];
  auto linear = [&](int i) { return x[i][0] + x[i][1] * z + delta * (x[i][2] + x[i][3] * z); };
  PerezLuminanceParams p;
  p.a = linear(0);
  p.b = linear(1);
  p.e = linear(4);
  if (sky.category == 0) {
    // First category: eqs. 7 and 8 of the 1993 paper
    p.c = std::exp(std::pow(delta * (x[2][0] + x[2][1] * z), x[2][2])) - x[2][3];
    p.d = -std::exp(delta * (x[3][0] + x[3][1] * z)) + x[3][2] + delta * x[3][3];
  } else {
    p.c = linear(2);
    p.d = linear(3);
  }
  return p;
}

namespace {

// Eq. 1 from the cosines the caller has: of gamma and of zeta.
double RelativeLuminance(const PerezLuminanceParams& p, double gamma_rad, double cos_gamma,
                         double cos_zeta) {
  return (1 + p.a * std::exp(p.b / cos_zeta)) *
         (1 + p.c * std::exp(p.d * gamma_rad) + p.e * cos_gamma * cos_gamma);
}

}  // namespace

double PerezRelativeLuminance(const PerezLuminanceParams& p, double gamma_rad, double zeta_rad) {
  return RelativeLuminance(p, gamma_rad, std::cos(gamma_rad), std::cos(zeta_rad));
}

void ComputePerezSkyRadiance(const PerezSkyCondition& sky, const SolarPosition& sun,
                             const SkyPatches& patches, std::span<double> radiance) {
  const PerezLuminanceParams params = ComputePerezLuminanceParams(sky);
  const double cos_z = std::cos(sky.sun_zenith_rad);
  const double sin_z = std::sin(sky.sun_zenith_rad);
  const double sin_azimuth = std::sin(sun.azimuth_rad), cos_azimuth = std::cos(sun.azimuth_rad);
  const int n = patches.size();
  radiance[0] = 0;

  // Relative luminance at the patch centres and its horizontal illuminance. From a patch's
  // unit direction (x east, y north, z up): cos zeta = z, and sin zeta cos(azimuth
  // difference) = x sin(sun azimuth) + y cos(sun azimuth).
  double horizontal = 0;
  for (int i = 1; i < n; ++i) {
    const SkyPatch& patch = patches[i];
    const Vec3d& d = patch.direction;
    const double cos_gamma =
        std::clamp(cos_z * d.z + sin_z * (d.x * sin_azimuth + d.y * cos_azimuth), -1.0, 1.0);
    const double lv =
        std::max(0.0, RelativeLuminance(params, std::acos(cos_gamma), cos_gamma, d.z));
    radiance[i] = std::isfinite(lv) ? lv : 0.0;
    horizontal += radiance[i] * d.z * patch.solid_angle_sr;
  }

  // Normalize to the diffuse horizontal illuminance (uniform sky if the model vanishes)
  if (!(horizontal > 1e-6)) {
    for (int i = 1; i < n; ++i) radiance[i] = 1;
    horizontal = std::numbers::pi;
  }
  const double scale = sky.diffuse_illuminance / horizontal / kWhiteEfficacyLmPerW;
  for (int i = 1; i < n; ++i) radiance[i] *= scale;
}

}  // namespace fenestra
