// Annual sky matrix from a weather file, following Radiance's gendaymtx: per time step the
// sun position (solar_position.h), the Perez all-weather sky normalized to the diffuse
// horizontal illuminance (perez.h), the sun spread over the 4 patches nearest to it, and a
// ground bin of reflectance x global horizontal illuminance / pi.
//
// Sun spreading (gendaymtx AddDirect): patch i of the 4 whose centres are nearest the sun
// gets weight w_i = 1 / (1.002 - cos d_i), d_i its angle to the sun, and radiance
// (w_i / sum w) E_direct / (179 Omega_i), which conserves the sun's normal flux.
#pragma once

#include <span>
#include <vector>

#include "absl/status/statusor.h"
#include "core/common/radiance_matrix.h"
#include "core/common/vec3.h"
#include "core/sky/epw.h"
#include "core/sky/perez.h"
#include "core/sky/sky_patches.h"

namespace fenestra {

struct SkyMatrixOptions {
  int mf = 1;  // Reinhart subdivision; 1 = Tregenza, 146 bins
  SkyQuantity quantity = SkyQuantity::kVisible;
  double ground_reflectance = 0.2;  // grey, in [0, 1]
  bool include_sky = true;          // false: sun only, ground 0 (gendaymtx -d)
  bool include_sun = true;          // false: no sun patches; the ground keeps it (gendaymtx -s)

  bool operator==(const SkyMatrixOptions&) const = default;
};

// What one column of the matrix stands for.
struct SkyStep {
  int month = 1;
  int day = 1;
  double hour = 0;  // local standard time at the centre of the step, decimal hours
  int day_of_year = 1;
  bool daytime = false;     // the step has light; otherwise its column is all 0
  bool sun_in_sky = false;  // part of the solar disc above the horizon
  double solar_altitude_rad = 0;
  double solar_azimuth_rad = 0;  // from north towards east
  // The sun's direct normal irradiance in the matrix's quantity [W m-2] (visible: direct
  // normal illuminance / 179), whether or not the matrix holds the sun; 0 without one (at
  // most kMinDirectIlluminanceLux).
  double direct_normal = 0;
};

// Direct normal illuminance below which a step has no sun [lx], as gendaymtx.
inline constexpr double kMinDirectIlluminanceLux = 1e-4;

// The unit direction towards the sun of `step` (x east, y north, z up).
Vec3d SunDirection(const SkyStep& step);

struct SkyMatrix {
  // Rows = bins (0 = ground), columns = time steps; radiance [W sr-1 m-2], visible
  // ("luminance / 179") or solar according to SkyMatrixOptions::quantity.
  Matrix radiance;
  std::vector<SkyStep> steps;
  int daytime_steps = 0;
  // Steps with direct normal radiation > 0 while the sun is below the horizon; like
  // gendaymtx, their sun is still added, to the patches nearest its direction.
  int direct_with_sun_down_steps = 0;
};

// Builds the sky matrix of every record of `weather`, its daytime columns on every core.
// InvalidArgument for a bad option.
absl::StatusOr<SkyMatrix> BuildSkyMatrix(const EpwData& weather,
                                         const SkyMatrixOptions& options = {});

// Local standard time [h] of the centre of a record's interval: hour - 0.5 for hourly
// files; hour - 1 + (minute - 60 / records_per_hour / 2) / 60 for sub-hourly ones.
double StepCentreHours(const EpwRecord& record, int records_per_hour);

// Adds a sun of direct normal irradiance `direct_normal` (W/m2 of the matrix quantity) in
// `sun_direction` to the 4 nearest sky patches of `column` (one entry per bin).
void AddSunToPatches(const SkyPatches& patches, Vec3d sun_direction, double direct_normal,
                     std::span<double> column);

}  // namespace fenestra
