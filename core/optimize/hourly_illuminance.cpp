#include "core/optimize/hourly_illuminance.h"

#include <algorithm>
#include <cmath>
#include <vector>

#include "absl/strings/str_cat.h"
#include "core/common/status_macros.h"
#include "core/metrics/illuminance.h"
#include "core/metrics/metric_errors.h"
#include "core/sky/sky_patches.h"

namespace fenestra {
namespace {

// Month, day and hour of each step, and the sensors' names.
void SetAxes(const Scene& scene, const SkyMatrix& sky, v1::HourlyIlluminance& out) {
  for (const Sensor& s : scene.sensors) out.add_sensors(s.name);
  for (const SkyStep& step : sky.steps) {
    out.add_month(step.month);
    out.add_day(step.day);
    out.add_hour(step.hour);
  }
}

}  // namespace

Matrix SkyColumnsInLux(const Matrix& radiance, std::span<const int> columns, double scale) {
  // Row by row, as both matrices lie in memory
  Matrix lux(radiance.rows(), static_cast<Eigen::Index>(columns.size()));
  for (Eigen::Index i = 0; i < radiance.rows(); ++i) {
    for (size_t c = 0; c < columns.size(); ++c) {
      lux(i, static_cast<Eigen::Index>(c)) = scale * radiance(i, columns[c]);
    }
  }
  return lux;
}

absl::StatusOr<Matrix> SplitSkyColumnsInLux(const SkyMatrix& sky, std::span<const int> columns,
                                            double scale) {
  if (sky.radiance.rows() != kDaylightBins) {
    return absl::InvalidArgumentError(absl::StrCat("a split sky needs the ", kDaylightBins,
                                                   " Tregenza bins, not ", sky.radiance.rows()));
  }
  FENESTRA_ASSIGN_OR_RETURN(patches, SkyPatches::Reinhart(1));
  Matrix split(kSplitSkyRows, static_cast<Eigen::Index>(columns.size()));
  split.topRows(kDaylightBins) = SkyColumnsInLux(sky.radiance, columns, scale);
  std::vector<double> sun(kDaylightBins);
  for (size_t c = 0; c < columns.size(); ++c) {
    const SkyStep& step = sky.steps[columns[c]];
    std::fill(sun.begin(), sun.end(), 0.0);
    if (step.direct_normal > 0) {
      AddSunToPatches(patches, SunDirection(step), step.direct_normal, sun);
    }
    for (int j = 0; j < kDaylightBins; ++j) {
      split(kDaylightBins + j, static_cast<Eigen::Index>(c)) = -scale * sun[j];
    }
  }
  return split;
}

std::vector<SunColumn> SunColumnsOf(const SkyMatrix& sky, std::span<const int> columns,
                                    double scale) {
  std::vector<SunColumn> suns;
  for (size_t c = 0; c < columns.size(); ++c) {
    const SkyStep& step = sky.steps[columns[c]];
    if (!(step.direct_normal > 0) || !(step.solar_altitude_rad > 0)) continue;
    suns.push_back({static_cast<int>(c), SunDirection(step), scale * step.direct_normal});
  }
  return suns;
}

absl::StatusOr<v1::HourlyIlluminance> DesignHourlyIlluminance(
    const Scene& scene, const SkyMatrix& sky, const DesignIlluminanceOf& illuminance,
    std::span<const SunEntry> sun, const std::vector<bool>& blind_in_place) {
  v1::HourlyIlluminance out;
  SetAxes(scene, sky, out);
  const int64_t sensors = static_cast<int64_t>(scene.sensors.size());
  const int64_t steps = static_cast<int64_t>(sky.steps.size());
  out.mutable_illuminance_lux()->Resize(static_cast<int>(sensors * steps), 0.0f);
  out.mutable_standard_error_lux()->Resize(static_cast<int>(sensors * steps), 0.0f);
  // Only where there is something to say: a static blind is always in place, and a design
  // the sun never reaches has no direct sun
  for (const bool b : blind_in_place) out.add_blind_in_place(b);
  if (!sun.empty()) out.mutable_direct_sun_lux()->Resize(static_cast<int>(sensors * steps), 0.0f);
  for (const SunEntry& e : sun) {
    if (e.sensor < 0 || e.sensor >= sensors || e.column < 0 || e.column >= steps) {
      return absl::InvalidArgumentError("a direct-sun entry out of range");
    }
    out.set_direct_sun_lux(static_cast<int>(e.sensor * steps + e.column),
                           static_cast<float>(e.lux));
  }
  const std::vector<int> lit = LitColumns(sky.radiance);
  if (lit.empty()) return out;

  // E_b = (I_b O_b) S - D_0 S_sun over the steps with daylight, for each batch b
  FENESTRA_ASSIGN_OR_RETURN(split, SplitSkyColumnsInLux(sky, lit));
  FENESTRA_ASSIGN_OR_RETURN(batches, illuminance(split));
  FENESTRA_RETURN_IF_ERROR(CheckErrorBatches(static_cast<int>(batches.size())));
  for (const Matrix& batch : batches) {
    if (batch.rows() != sensors || batch.cols() != static_cast<Eigen::Index>(lit.size())) {
      return absl::InvalidArgumentError(absl::StrCat("a batch of the illuminance is ", batch.rows(),
                                                     " x ", batch.cols(), ", expected ", sensors,
                                                     " x ", lit.size()));
    }
  }

  // Their mean, and its standard error from the spread of the batches; then the direct sun,
  // the same in every batch
  Matrix mean, standard_error;
  MeanAndError(batches, &mean, &standard_error);
  std::vector<int> lit_column(steps, -1);
  for (size_t c = 0; c < lit.size(); ++c) lit_column[lit[c]] = static_cast<int>(c);
  for (const SunEntry& e : sun) {
    if (lit_column[e.column] >= 0) mean(e.sensor, lit_column[e.column]) += e.lux;
  }
  for (int64_t i = 0; i < sensors; ++i) {
    for (size_t c = 0; c < lit.size(); ++c) {
      const int k = static_cast<int>(i * steps + lit[c]);
      out.set_illuminance_lux(k, static_cast<float>(mean(i, c)));
      out.set_standard_error_lux(k, static_cast<float>(standard_error(i, c)));
    }
  }
  return out;
}

}  // namespace fenestra
