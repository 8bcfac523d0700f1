#include "core/sky/sky_matrix.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <optional>
#include <vector>

#include "absl/status/status.h"
#include "absl/strings/str_cat.h"
#include "core/common/status_macros.h"
#include "core/common/thread_pool.h"
#include "core/sky/solar_position.h"

namespace fenestra {
namespace {

constexpr int kSunPatches = 4;
constexpr double kNightThresholdWm2 = 1e-4;
constexpr double kDefaultDewPointC = 11;

// Dew point for the precipitable water: mean of this and the two previous records, as
// gendaymtx takes it; the history restarts after a missing value, which keeps the last mean.
class DewPointMean {
 public:
  double Update(const std::optional<double>& dew_point_c) {
    if (!dew_point_c) {
      have_history_ = false;
      return mean_;
    }
    if (!have_history_) {
      previous_[0] = previous_[1] = *dew_point_c;
      have_history_ = true;
    }
    mean_ = (previous_[0] + previous_[1] + *dew_point_c) / 3;
    previous_[0] = previous_[1];
    previous_[1] = *dew_point_c;
    return mean_;
  }

 private:
  bool have_history_ = false;
  double previous_[2] = {0, 0};
  double mean_ = kDefaultDewPointC;
};

}  // namespace

Vec3d SunDirection(const SkyStep& step) {
  return DirectionFromAltAz(step.solar_altitude_rad, step.solar_azimuth_rad);
}

double StepCentreHours(const EpwRecord& record, int records_per_hour) {
  if (records_per_hour <= 1) return record.hour - 0.5;
  const double interval_minutes = 60.0 / records_per_hour;
  return record.hour - 1 + (record.minute - interval_minutes / 2) / 60;
}

void AddSunToPatches(const SkyPatches& patches, Vec3d sun_direction, double direct_normal,
                     std::span<double> column) {
  // The kSunPatches patch centres nearest the sun, nearest first
  double near_cos[kSunPatches];
  int near_bin[kSunPatches];
  for (int i = 0; i < kSunPatches; ++i) {
    near_cos[i] = -1;
    near_bin[i] = 1;
  }
  for (int bin = 1; bin < patches.size(); ++bin) {
    const double c = Dot(patches[bin].direction, sun_direction);
    for (int i = 0; i < kSunPatches; ++i) {
      if (c > near_cos[i]) {
        for (int j = kSunPatches - 1; j > i; --j) {
          near_cos[j] = near_cos[j - 1];
          near_bin[j] = near_bin[j - 1];
        }
        near_cos[i] = c;
        near_bin[i] = bin;
        break;
      }
    }
  }

  // Share the flux by proximity and turn it into radiance over each patch
  double weight[kSunPatches];
  double total = 0;
  for (int i = 0; i < kSunPatches; ++i) total += weight[i] = 1 / (1.002 - near_cos[i]);
  for (int i = 0; i < kSunPatches; ++i) {
    column[near_bin[i]] += weight[i] / total * direct_normal / patches[near_bin[i]].solid_angle_sr;
  }
}

absl::StatusOr<SkyMatrix> BuildSkyMatrix(const EpwData& weather, const SkyMatrixOptions& options) {
  if (!(options.ground_reflectance >= 0 && options.ground_reflectance <= 1)) {
    return absl::InvalidArgumentError(
        absl::StrCat("ground reflectance must be in [0, 1], got ", options.ground_reflectance));
  }
  FENESTRA_ASSIGN_OR_RETURN(patches, SkyPatches::Reinhart(options.mf));

  const SolarSite site{weather.location.latitude_deg, weather.location.longitude_deg,
                       weather.location.time_zone_hours};
  const int bins = patches.size();
  const int steps = static_cast<int>(weather.records.size());
  SkyMatrix sky;
  sky.radiance = Matrix::Zero(bins, steps);
  sky.steps.resize(steps);
  std::vector<SolarPosition> suns(steps);
  std::vector<double> dew_points(steps);
  DewPointMean dew_point;
  bool after_leap_day = false;

  // The steps in order (the dew point's running mean and the leap day carry over)
  for (int t = 0; t < steps; ++t) {
    const EpwRecord& record = weather.records[t];
    SkyStep& step = sky.steps[t];
    dew_points[t] = dew_point.Update(record.dew_point_c);

    // Sun position at the centre of the step
    step.month = record.month;
    step.day = record.day;
    step.hour = StepCentreHours(record, weather.records_per_hour);
    step.day_of_year = DayOfYear(record.month, record.day, &after_leap_day);
    suns[t] = ComputeSolarPosition(site, step.day_of_year, step.hour);
    step.solar_altitude_rad = suns[t].altitude_rad;
    step.solar_azimuth_rad = suns[t].azimuth_rad;
    step.sun_in_sky = SunInSky(suns[t].altitude_rad);

    // Night: no light at all, the column stays 0
    const double direct = record.direct_normal_wm2;
    const double diffuse = record.diffuse_horizontal_wm2;
    if (direct + diffuse <= kNightThresholdWm2) continue;
    step.daytime = true;
    ++sky.daytime_steps;
    if (!step.sun_in_sky && direct > 0) ++sky.direct_with_sun_down_steps;
  }

  // The daytime columns, each on its own: Perez sky and ground, then the sun
  ParallelFor(steps, ResolveThreadCount(0), [&](uint64_t i) {
    const int t = static_cast<int>(i);
    const SkyStep& step = sky.steps[t];
    if (!step.daytime) return;
    const EpwRecord& record = weather.records[t];
    const SolarPosition& sun = suns[t];
    const PerezSkyCondition condition = ComputePerezSkyCondition(
        record.direct_normal_wm2, record.diffuse_horizontal_wm2, sun.altitude_rad, step.day_of_year,
        dew_points[t], options.quantity);
    std::vector<double> column(bins, 0.0);
    if (options.include_sky) {
      ComputePerezSkyRadiance(condition, sun, patches, column);
      const double horizontal_illuminance =
          condition.diffuse_illuminance +
          (sun.altitude_rad > 0 ? condition.direct_illuminance * std::sin(sun.altitude_rad) : 0);
      column[0] = options.ground_reflectance * horizontal_illuminance /
                  (std::numbers::pi * kWhiteEfficacyLmPerW);
    }
    if (condition.direct_illuminance > kMinDirectIlluminanceLux) {
      const double direct_normal = condition.direct_illuminance / kWhiteEfficacyLmPerW;
      sky.steps[t].direct_normal = direct_normal;  // each step is written by one thread
      if (options.include_sun) {
        AddSunToPatches(patches, DirectionFromAltAz(sun.altitude_rad, sun.azimuth_rad),
                        direct_normal, column);
      }
    }
    for (int bin = 0; bin < bins; ++bin) sky.radiance(bin, t) = column[bin];
  });
  return sky;
}

}  // namespace fenestra
