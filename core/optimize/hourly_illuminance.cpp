#include "core/optimize/hourly_illuminance.h"

#include <cmath>
#include <vector>

#include "absl/strings/str_cat.h"
#include "core/common/status_macros.h"
#include "core/metrics/illuminance.h"
#include "core/metrics/metric_errors.h"

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

Matrix SkyColumnsInLux(const Matrix& radiance, std::span<const int> columns) {
  // Row by row, as both matrices lie in memory
  Matrix lux(radiance.rows(), static_cast<Eigen::Index>(columns.size()));
  for (Eigen::Index i = 0; i < radiance.rows(); ++i) {
    for (size_t c = 0; c < columns.size(); ++c) {
      lux(i, static_cast<Eigen::Index>(c)) = kWhiteEfficacyLumensPerWatt * radiance(i, columns[c]);
    }
  }
  return lux;
}

absl::StatusOr<v1::HourlyIlluminance> DesignHourlyIlluminance(
    const Scene& scene, const SkyMatrix& sky, const DesignIlluminanceOf& illuminance) {
  v1::HourlyIlluminance out;
  SetAxes(scene, sky, out);
  const int64_t sensors = static_cast<int64_t>(scene.sensors.size());
  const int64_t steps = static_cast<int64_t>(sky.steps.size());
  out.mutable_illuminance_lux()->Resize(static_cast<int>(sensors * steps), 0.0f);
  out.mutable_standard_error_lux()->Resize(static_cast<int>(sensors * steps), 0.0f);
  const std::vector<int> lit = LitColumns(sky.radiance);
  if (lit.empty()) return out;

  // E_b = (I_b O_b) S over the steps with daylight, for each batch b
  FENESTRA_ASSIGN_OR_RETURN(batches, illuminance(SkyColumnsInLux(sky.radiance, lit)));
  FENESTRA_RETURN_IF_ERROR(CheckErrorBatches(static_cast<int>(batches.size())));
  for (const Matrix& batch : batches) {
    if (batch.rows() != sensors || batch.cols() != static_cast<Eigen::Index>(lit.size())) {
      return absl::InvalidArgumentError(absl::StrCat("a batch of the illuminance is ", batch.rows(),
                                                     " x ", batch.cols(), ", expected ", sensors,
                                                     " x ", lit.size()));
    }
  }

  // Their mean, and its standard error from the spread of the batches
  Matrix mean, standard_error;
  MeanAndError(batches, &mean, &standard_error);
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
