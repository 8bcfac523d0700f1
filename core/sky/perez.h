// Perez all-weather sky: sky condition and luminous efficacy from direct normal and diffuse
// horizontal irradiance, and the relative sky luminance distribution, as gendaymtx applies
// them (Radiance gendaymtx.c, 2024 revision with its clamps).
//
// Perez, R., P. Ineichen, R. Seals, J. Michalsky, R. Stewart (1990), "Modeling daylight
// availability and irradiance components from direct and global irradiance", Solar Energy
// 44(5):271-289: clearness eq. 1, brightness eq. 2, precipitable water eq. 3, diffuse and
// direct luminous efficacy eqs. 7 and 8 with the coefficients of Table 4.
// Perez, R., R. Seals, J. Michalsky (1993), "All-weather model for sky luminance
// distribution - preliminary configuration and validation", Solar Energy 50(3):235-245,
// and erratum 51(5):423: relative luminance eq. 1, parameters a..e eq. 6 (eqs. 7 and 8 for
// c and d of the first clearness category), coefficients of Table 1.
// Air mass: Kasten (1966). Eccentricity correction: Sen (2008), p. 72.
#pragma once

#include <span>

#include "core/sky/sky_patches.h"
#include "core/sky/solar_position.h"

namespace fenestra {

// Radiance's luminous efficacy of equal-energy white, lm/W: "visible" W to lumens.
inline constexpr double kWhiteEfficacyLmPerW = 179;

// What a sky matrix holds: visible radiance (luminance / 179) or broadband solar radiance.
enum class SkyQuantity { kVisible, kSolar };

// Perez (1990) description of one time step, after gendaymtx's clamps.
struct PerezSkyCondition {
  double sun_zenith_rad = 0;  // zenith angle used by the model, in [3, 90] degrees
  double clearness = 1;       // epsilon, clamped to [1, 11.9]
  double brightness = 0.01;   // delta, clamped to [0.01, 0.6]
  int category = 0;           // clearness category 0..7
  // Diffuse horizontal and direct normal illuminance [lx]; for SkyQuantity::kSolar the
  // irradiance times kWhiteEfficacyLmPerW, so that dividing by it gives W/m2 again.
  double diffuse_illuminance = 0;
  double direct_illuminance = 0;
};

// Coefficients a..e of the Perez (1993) relative luminance.
struct PerezLuminanceParams {
  double a = 0, b = 0, c = 0, d = 0, e = 0;
};

// Zenith angle the model uses for a solar altitude: 90 degrees at or below the horizon,
// 3 degrees at or above 87 degrees altitude, 90 degrees - altitude otherwise.
double PerezSunZenithRad(double solar_altitude_rad);

// Kasten (1966) relative optical air mass at zenith angle `zenith_rad`.
double RelativeAirMass(double zenith_rad);

// Earth-orbit eccentricity correction factor on day `day_of_year`.
double EccentricityCorrection(int day_of_year);

// Atmospheric precipitable water [cm] from the surface dew point [degrees C] (1990, eq. 3).
double PrecipitableWaterCm(double dew_point_c);

// Clearness category 0..7 of a clearness epsilon (edges 1.065, 1.23, 1.5, 1.95, 2.8, 4.5,
// 6.2); values outside [1, 12.01) fall into the first or last category.
int ClearnessCategory(double clearness);

// Sky condition of a time step with direct normal and diffuse horizontal irradiance
// [W/m2], both >= 0 with a positive sum.
PerezSkyCondition ComputePerezSkyCondition(double direct_normal_wm2, double diffuse_horizontal_wm2,
                                           double solar_altitude_rad, int day_of_year,
                                           double dew_point_c, SkyQuantity quantity);

// Perez (1993) parameters a..e for a sky condition (brightness raised to 0.2 when
// 1.065 < epsilon < 2.8, as gendaymtx does).
PerezLuminanceParams ComputePerezLuminanceParams(const PerezSkyCondition& condition);

// Relative luminance (1993, eq. 1) of a sky point at zenith angle `zeta_rad` and angle
// `gamma_rad` from the sun; may be negative for unphysical parameters.
double PerezRelativeLuminance(const PerezLuminanceParams& params, double gamma_rad,
                              double zeta_rad);

// Fills `radiance` (one entry per bin of `patches`) with the diffuse sky radiance
// [W sr-1 m-2] of the condition, evaluated at the patch centres and normalized so that
// the patches' horizontal illuminance equals the diffuse horizontal illuminance; the
// ground entry (bin 0) is set to 0. A sky whose relative luminance vanishes everywhere is
// made uniform.
void ComputePerezSkyRadiance(const PerezSkyCondition& condition, const SolarPosition& sun,
                             const SkyPatches& patches, std::span<double> radiance);

}  // namespace fenestra
