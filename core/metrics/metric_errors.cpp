#include "core/metrics/metric_errors.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <utility>

#include "absl/strings/str_cat.h"
#include "core/common/status_macros.h"
#include "core/metrics/illuminance.h"

namespace fenestra {
namespace {

constexpr std::array kSensorFields = {
    &SensorMetrics::udi_percent,
    &SensorMetrics::udi_fell_short_percent,
    &SensorMetrics::udi_exceeded_percent,
    &SensorMetrics::da_percent,
    &SensorMetrics::cda_percent,
    &SensorMetrics::mean_illuminance_lux,
    &SensorMetrics::ase_hours,
};

constexpr std::array kSceneFields = {
    &SceneMetrics::udi_all_percent,
    &SceneMetrics::udi_all_fell_short_percent,
    &SceneMetrics::udi_all_exceeded_percent,
    &SceneMetrics::udi_mean_percent,
    &SceneMetrics::udi_mean_fell_short_percent,
    &SceneMetrics::udi_mean_exceeded_percent,
    &SceneMetrics::da_mean_percent,
    &SceneMetrics::cda_mean_percent,
    &SceneMetrics::sda_percent,
    &SceneMetrics::ase_percent,
    &SceneMetrics::mean_illuminance_lux,
    &SceneMetrics::blind_in_place_percent,
};

// Every number of `m` in a fixed order: the scene's, then each sensor's.
void Flatten(const AnnualMetrics& m, double* out) {
  for (const auto field : kSceneFields) *out++ = m.scene.*field;
  for (const SensorMetrics& s : m.sensors) {
    for (const auto field : kSensorFields) *out++ = s.*field;
  }
}

void Unflatten(const double* in, AnnualMetrics& m) {
  for (const auto field : kSceneFields) m.scene.*field = *in++;
  for (SensorMetrics& s : m.sensors) {
    for (const auto field : kSensorFields) s.*field = *in++;
  }
}

// The time steps that count: the positions in `columns` of the analysed ones.
struct AnalysedColumns {
  std::vector<int> steps;
  std::vector<int> positions;
};

absl::StatusOr<AnalysedColumns> SelectAnalysed(std::span<const int> columns,
                                               const std::vector<bool>& occupied,
                                               const MetricOptions& options) {
  FENESTRA_RETURN_IF_ERROR(CheckColumns(columns, static_cast<int>(occupied.size())));
  AnalysedColumns selected;
  for (size_t c = 0; c < columns.size(); ++c) {
    if (options.hours == HourBasis::kAllHours || occupied[columns[c]]) {
      selected.steps.push_back(columns[c]);
      selected.positions.push_back(static_cast<int>(c));
    }
  }
  return selected;
}

// Metrics and standard errors of the analysed columns of B >= 2 batch illuminances, with
// ASE from the analysed columns of the direct-only illuminance (n x column_count) if given.
absl::StatusOr<AnnualMetricsEstimate> Jackknife(std::span<const Matrix> batches,
                                                const AnalysedColumns& analysed,
                                                size_t column_count,
                                                const std::vector<bool>& occupied,
                                                const MetricOptions& options,
                                                const Matrix* direct_illuminance_lux) {
  const Eigen::Index n = batches[0].rows();
  if (direct_illuminance_lux != nullptr) {
    if (direct_illuminance_lux->rows() != n ||
        direct_illuminance_lux->cols() != static_cast<Eigen::Index>(column_count)) {
      return absl::InvalidArgumentError(
          absl::StrCat("direct-only illuminance is ", direct_illuminance_lux->rows(), " x ",
                       direct_illuminance_lux->cols(), ", expected ", n, " x ", column_count));
    }
    if (!direct_illuminance_lux->allFinite()) {
      return absl::InvalidArgumentError("illuminance has a non-finite value");
    }
  }
  FENESTRA_RETURN_IF_ERROR(CheckMetricOptions(options));
  FENESTRA_ASSIGN_OR_RETURN(versions, TallyBatchVersions(batches, options));
  FENESTRA_ASSIGN_OR_RETURN(
      estimate,
      AnnualMetricsFromTallies(versions, AnalysedHours(occupied, options.hours), options));
  // The direct-only illuminance is exact: ASE has no standard error
  if (direct_illuminance_lux != nullptr) {
    AddAse((*direct_illuminance_lux)(Eigen::all, analysed.positions), options, &estimate.value);
    estimate.standard_error.has_ase = true;
  }
  return estimate;
}

// The tallies of the versions of E (TallyBatchVersions) from B >= 2 batches of `sensors` x
// `hours` finite values, batch b's row of sensor i at row_of(b, i), one sensor at a time and
// without a matrix per version: E of the mean of all batches (summed in batch order, then
// divided), then of the mean without each batch in turn, (B E - E_b) / (B - 1), the same
// arithmetic as those matrices' and so the same tallies.
template <class RowOf>
std::vector<HourTally> TallyVersions(int batches, Eigen::Index sensors, Eigen::Index hours,
                                     const MetricOptions& options, const RowOf& row_of) {
  static_assert(Matrix::IsRowMajor, "a sensor's hours lie side by side");
  std::vector<HourTallyBuilder> builders;
  for (int v = 0; v <= batches; ++v) {
    builders.emplace_back(static_cast<int>(sensors), hours, options);
  }
  const double scale = 1.0 / (batches - 1);
  std::vector<double> mean(hours), left_out(hours);
  for (Eigen::Index i = 0; i < sensors; ++i) {
    const double* first = row_of(0, i);
    std::copy(first, first + hours, mean.begin());
    for (int b = 1; b < batches; ++b) {
      const double* e_b = row_of(b, i);
      for (Eigen::Index h = 0; h < hours; ++h) mean[h] += e_b[h];
    }
    for (double& e : mean) e /= batches;
    builders[0].AddRow(static_cast<int>(i), mean.data());
    for (int b = 0; b < batches; ++b) {
      const double* e_b = row_of(b, i);
      for (Eigen::Index h = 0; h < hours; ++h) left_out[h] = (batches * mean[h] - e_b[h]) * scale;
      builders[1 + b].AddRow(static_cast<int>(i), left_out.data());
    }
  }
  std::vector<HourTally> versions;
  versions.reserve(batches + 1);
  for (HourTallyBuilder& builder : builders) versions.push_back(builder.Finish());
  return versions;
}

}  // namespace

absl::Status CheckErrorBatches(int batches) {
  if (batches >= 2) return absl::OkStatus();
  return absl::InvalidArgumentError(
      absl::StrCat("standard errors need at least 2 batches, got ", batches));
}

double JackknifeStandardError(std::span<const double> leave_one_out_values) {
  const size_t b = leave_one_out_values.size();
  if (b < 2) return 0;
  double mean = 0;
  for (const double v : leave_one_out_values) mean += v;
  mean /= static_cast<double>(b);
  double squares = 0;
  for (const double v : leave_one_out_values) squares += (v - mean) * (v - mean);
  return std::sqrt(squares * static_cast<double>(b - 1) / static_cast<double>(b));
}

absl::StatusOr<std::vector<HourTally>> TallyBatchVersions(
    std::span<const Matrix> illuminance_batches_lux, const MetricOptions& options) {
  const int batches = static_cast<int>(illuminance_batches_lux.size());
  FENESTRA_RETURN_IF_ERROR(CheckErrorBatches(batches));
  const Matrix& first = illuminance_batches_lux[0];
  for (const Matrix& e : illuminance_batches_lux) {
    if (e.rows() != first.rows() || e.cols() != first.cols()) {
      return absl::InvalidArgumentError(absl::StrCat("illuminance batches of ", first.rows(), " x ",
                                                     first.cols(), " and ", e.rows(), " x ",
                                                     e.cols()));
    }
    if (!e.allFinite()) return absl::InvalidArgumentError("illuminance has a non-finite value");
  }
  return TallyVersions(batches, first.rows(), first.cols(), options, [&](int b, Eigen::Index i) {
    return illuminance_batches_lux[b].data() + i * first.cols();
  });
}

absl::StatusOr<std::vector<HourTally>> TallyStackedVersions(const Matrix& stacked, int batches,
                                                            const MetricOptions& options) {
  FENESTRA_RETURN_IF_ERROR(CheckErrorBatches(batches));
  if (stacked.rows() % batches != 0) {
    return absl::InvalidArgumentError(absl::StrCat(
        stacked.rows(), " rows of illuminance do not split into ", batches, " batches"));
  }
  if (!stacked.allFinite()) return absl::InvalidArgumentError("illuminance has a non-finite value");
  const Eigen::Index sensors = stacked.rows() / batches;
  return TallyVersions(batches, sensors, stacked.cols(), options, [&](int b, Eigen::Index i) {
    return stacked.data() + (b * sensors + i) * stacked.cols();
  });
}

absl::StatusOr<AnnualMetricsEstimate> AnnualMetricsFromTallies(
    std::span<const HourTally> versions, int analysed_hours, const MetricOptions& options,
    std::vector<AnnualMetrics>* version_metrics) {
  if (versions.size() < 3) {
    return absl::InvalidArgumentError(
        absl::StrCat("standard errors need the tallies of the mean and of at least 2 "
                     "leave-one-out versions, got ",
                     versions.size(), " tallies"));
  }
  const HourTally& mean = versions[0];
  if (mean.sensors.empty()) return absl::InvalidArgumentError("no sensors");
  for (const HourTally& v : versions) {
    if (v.sensors.size() != mean.sensors.size() || v.hours != mean.hours) {
      return absl::InvalidArgumentError(
          absl::StrCat("tallies of ", mean.sensors.size(), " sensors x ", mean.hours, " hours and ",
                       v.sensors.size(), " sensors x ", v.hours, " hours"));
    }
  }
  if (analysed_hours < 1) return absl::InvalidArgumentError("no occupied hours to analyse");
  if (mean.hours > analysed_hours) {
    return absl::InvalidArgumentError(absl::StrCat(
        "tallies of ", mean.hours, " hours, more than the ", analysed_hours, " analysed hours"));
  }
  FENESTRA_RETURN_IF_ERROR(CheckMetricOptions(options));

  const int batches = static_cast<int>(versions.size()) - 1;
  AnnualMetricsEstimate estimate;
  estimate.batches = batches;
  estimate.value = MetricsFromTally(mean, analysed_hours, options);
  if (version_metrics != nullptr) version_metrics->assign(1, estimate.value);

  // Leave each batch out in turn
  const size_t fields = kSceneFields.size() + kSensorFields.size() * mean.sensors.size();
  Matrix loo(batches, static_cast<Eigen::Index>(fields));
  for (int b = 0; b < batches; ++b) {
    const AnnualMetrics left_out = MetricsFromTally(versions[1 + b], analysed_hours, options);
    Flatten(left_out, loo.row(b).data());
    if (version_metrics != nullptr) version_metrics->push_back(left_out);
  }
  std::vector<double> se(fields);
  std::vector<double> column(batches);
  for (size_t f = 0; f < fields; ++f) {
    for (int b = 0; b < batches; ++b) column[b] = loo(b, static_cast<Eigen::Index>(f));
    se[f] = JackknifeStandardError(column);
  }
  estimate.standard_error.analysed_hours = analysed_hours;
  estimate.standard_error.sensors.resize(mean.sensors.size());
  Unflatten(se.data(), estimate.standard_error);
  return estimate;
}

absl::StatusOr<AnnualMetricsEstimate> AnnualMetricsWithErrors(
    std::span<const Matrix> dc_batches, std::span<const Matrix> sky_channels,
    std::span<const int> columns, const std::vector<bool>& occupied, const MetricOptions& options,
    const Matrix* direct_illuminance_lux) {
  const int batches = static_cast<int>(dc_batches.size());
  FENESTRA_RETURN_IF_ERROR(CheckErrorBatches(batches));
  for (const Matrix& d : dc_batches) {
    if (d.rows() != dc_batches[0].rows() || d.cols() != dc_batches[0].cols()) {
      return absl::InvalidArgumentError("daylight coefficient batches differ in shape");
    }
  }
  if (!sky_channels.empty() &&
      sky_channels[0].cols() != static_cast<Eigen::Index>(occupied.size())) {
    return absl::InvalidArgumentError(absl::StrCat("the sky has ", sky_channels[0].cols(),
                                                   " time steps, the occupancy ", occupied.size()));
  }
  FENESTRA_ASSIGN_OR_RETURN(analysed, SelectAnalysed(columns, occupied, options));

  // Every batch's illuminance in one product (the sky is sliced once); E of the mean D is
  // the mean of the batches' E
  const Eigen::Index n = dc_batches[0].rows();
  Matrix stacked(batches * n, dc_batches[0].cols());
  for (int b = 0; b < batches; ++b) stacked.middleRows(b * n, n) = dc_batches[b];
  FENESTRA_ASSIGN_OR_RETURN(
      all, Illuminance(std::span<const Matrix>(&stacked, 1), sky_channels, analysed.steps));
  std::vector<Matrix> e(batches);
  for (int b = 0; b < batches; ++b) e[b] = all.middleRows(b * n, n);
  all.resize(0, 0);
  return Jackknife(e, analysed, columns.size(), occupied, options, direct_illuminance_lux);
}

absl::StatusOr<AnnualMetricsEstimate> AnnualMetricsFromIlluminanceBatches(
    std::span<const Matrix> illuminance_batches_lux, std::span<const int> columns,
    const std::vector<bool>& occupied, const MetricOptions& options,
    const Matrix* direct_illuminance_lux) {
  const int batches = static_cast<int>(illuminance_batches_lux.size());
  FENESTRA_RETURN_IF_ERROR(CheckErrorBatches(batches));
  for (const Matrix& e : illuminance_batches_lux) {
    if (e.rows() != illuminance_batches_lux[0].rows() ||
        e.cols() != static_cast<Eigen::Index>(columns.size())) {
      return absl::InvalidArgumentError(
          absl::StrCat("every illuminance batch must be ", illuminance_batches_lux[0].rows(), " x ",
                       columns.size(), "; got ", e.rows(), " x ", e.cols()));
    }
  }
  FENESTRA_ASSIGN_OR_RETURN(analysed, SelectAnalysed(columns, occupied, options));

  std::vector<Matrix> e;
  for (const Matrix& batch : illuminance_batches_lux) {
    e.emplace_back(batch(Eigen::all, analysed.positions));
  }
  return Jackknife(e, analysed, columns.size(), occupied, options, direct_illuminance_lux);
}

}  // namespace fenestra
