#include "core/metrics/annual_metrics.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <string>
#include <utility>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_join.h"
#include "core/metrics/illuminance.h"

namespace fenestra {
namespace {

constexpr std::array<std::pair<SceneMetric, std::string_view>, 11> kSceneMetricNames = {{
    {SceneMetric::kUdiAll, "udi_all"},
    {SceneMetric::kUdiAllFellShort, "udi_all_fell_short"},
    {SceneMetric::kUdiAllExceeded, "udi_all_exceeded"},
    {SceneMetric::kUdiMean, "udi_mean"},
    {SceneMetric::kUdiMeanFellShort, "udi_mean_fell_short"},
    {SceneMetric::kUdiMeanExceeded, "udi_mean_exceeded"},
    {SceneMetric::kDaMean, "da_mean"},
    {SceneMetric::kCdaMean, "cda_mean"},
    {SceneMetric::kSda, "sda"},
    {SceneMetric::kAse, "ase"},
    {SceneMetric::kMeanIlluminance, "mean_illuminance"},
}};

absl::Status CheckOptions(const MetricOptions& o) {
  if (!(o.udi_lower_lux >= 0 && o.udi_lower_lux <= o.udi_upper_lux) ||
      !std::isfinite(o.udi_upper_lux)) {
    return absl::InvalidArgumentError(absl::StrCat("UDI range [", o.udi_lower_lux, ", ",
                                                   o.udi_upper_lux,
                                                   "] lx: need 0 <= lower <= upper < inf"));
  }
  if (!(o.da_threshold_lux > 0) || !std::isfinite(o.da_threshold_lux)) {
    return absl::InvalidArgumentError(
        absl::StrCat("DA threshold ", o.da_threshold_lux, " lx: must be positive"));
  }
  if (!(o.sda_min_da_percent >= 0 && o.sda_min_da_percent <= 100)) {
    return absl::InvalidArgumentError(
        absl::StrCat("sDA minimum DA ", o.sda_min_da_percent, "%: must be in [0, 100]"));
  }
  if (!(o.ase_threshold_lux >= 0) || !std::isfinite(o.ase_threshold_lux) || o.ase_min_hours < 0) {
    return absl::InvalidArgumentError(absl::StrCat("ASE threshold ", o.ase_threshold_lux, " lx / ",
                                                   o.ase_min_hours, " h: must not be negative"));
  }
  return absl::OkStatus();
}

}  // namespace

double SceneMetricValue(const SceneMetrics& s, SceneMetric metric) {
  switch (metric) {
    case SceneMetric::kUdiAll:
      return s.udi_all_percent;
    case SceneMetric::kUdiAllFellShort:
      return s.udi_all_fell_short_percent;
    case SceneMetric::kUdiAllExceeded:
      return s.udi_all_exceeded_percent;
    case SceneMetric::kUdiMean:
      return s.udi_mean_percent;
    case SceneMetric::kUdiMeanFellShort:
      return s.udi_mean_fell_short_percent;
    case SceneMetric::kUdiMeanExceeded:
      return s.udi_mean_exceeded_percent;
    case SceneMetric::kDaMean:
      return s.da_mean_percent;
    case SceneMetric::kCdaMean:
      return s.cda_mean_percent;
    case SceneMetric::kSda:
      return s.sda_percent;
    case SceneMetric::kAse:
      return s.ase_percent;
    case SceneMetric::kMeanIlluminance:
      return s.mean_illuminance_lux;
  }
  return 0;
}

std::string_view SceneMetricName(SceneMetric metric) {
  for (const auto& [m, name] : kSceneMetricNames) {
    if (m == metric) return name;
  }
  return "";
}

absl::StatusOr<SceneMetric> SceneMetricFromName(std::string_view name) {
  for (const auto& [m, n] : kSceneMetricNames) {
    if (n == name) return m;
  }
  std::vector<std::string> names;
  for (const auto& entry : kSceneMetricNames) names.emplace_back(entry.second);
  return absl::InvalidArgumentError(absl::StrCat("unknown metric '", std::string(name),
                                                 "'; one of: ", absl::StrJoin(names, ", ")));
}

absl::StatusOr<AnnualMetrics> ComputeAnnualMetrics(const Matrix& illuminance_lux,
                                                   std::span<const int> columns,
                                                   const std::vector<bool>& occupied,
                                                   const MetricOptions& options,
                                                   const Matrix* direct_illuminance_lux) {
  const Matrix& e = illuminance_lux;
  const Eigen::Index n = e.rows();
  if (n == 0) return absl::InvalidArgumentError("no sensors");
  if (e.cols() != static_cast<Eigen::Index>(columns.size())) {
    return absl::InvalidArgumentError(
        absl::StrCat("illuminance has ", e.cols(), " columns for ", columns.size(), " time steps"));
  }
  if (direct_illuminance_lux != nullptr &&
      (direct_illuminance_lux->rows() != n || direct_illuminance_lux->cols() != e.cols())) {
    return absl::InvalidArgumentError(
        absl::StrCat("direct-only illuminance is ", direct_illuminance_lux->rows(), " x ",
                     direct_illuminance_lux->cols(), ", the illuminance ", n, " x ", e.cols()));
  }
  const absl::Status columns_ok = CheckColumns(columns, static_cast<int>(occupied.size()));
  if (!columns_ok.ok()) return columns_ok;
  const absl::Status options_ok = CheckOptions(options);
  if (!options_ok.ok()) return options_ok;
  if (!e.allFinite() ||
      (direct_illuminance_lux != nullptr && !direct_illuminance_lux->allFinite())) {
    return absl::InvalidArgumentError("illuminance has a non-finite value");
  }

  // Pick the analysed steps: those in `columns`, and the dark rest
  const bool all_hours = options.hours == HourBasis::kAllHours;
  int analysed_hours = 0;
  for (const bool o : occupied) analysed_hours += (all_hours || o) ? 1 : 0;
  if (analysed_hours == 0) return absl::InvalidArgumentError("no occupied hours to analyse");
  std::vector<Eigen::Index> used;  // positions in `columns`
  for (size_t c = 0; c < columns.size(); ++c) {
    if (all_hours || occupied[columns[c]]) used.push_back(static_cast<Eigen::Index>(c));
  }
  const double dark_hours = analysed_hours - static_cast<double>(used.size());

  const double a = options.udi_lower_lux;
  const double b = options.udi_upper_lux;
  const double da = options.da_threshold_lux;
  const double to_percent = 100.0 / analysed_hours;
  const bool dark_in_range = 0.0 >= a;  // E = 0 can only fall short or be in range

  AnnualMetrics result;
  result.analysed_hours = analysed_hours;
  result.has_ase = direct_illuminance_lux != nullptr;
  result.sensors.resize(n);
  std::vector<uint8_t> any_below(used.size(), 0);
  std::vector<uint8_t> any_above(used.size(), 0);

  // Count per sensor; note per hour whether some sensor left the range
  for (Eigen::Index i = 0; i < n; ++i) {
    const double* row = e.data() + i * e.cols();
    // Without branches: the comparisons are data, not control flow (hours fall either side
    // of the limits at random, which a branch predictor cannot learn)
    int64_t lit_below = 0, lit_above = 0, lit_da = 0;
    double credit = 0, sum = 0;
    for (size_t u = 0; u < used.size(); ++u) {
      const double v = row[used[u]];
      const uint8_t is_below = v<a, is_above = v> b;
      lit_below += is_below;
      lit_above += is_above;
      any_below[u] |= is_below;
      any_above[u] |= is_above;
      lit_da += v >= da;
      credit += std::min(v / da, 1.0);
      sum += v;
    }
    const double lit_in_range = static_cast<double>(used.size() - lit_below - lit_above);
    const double in_range = lit_in_range + (dark_in_range ? dark_hours : 0);
    const double below = static_cast<double>(lit_below) + (dark_in_range ? 0 : dark_hours);
    const double above = static_cast<double>(lit_above);
    const double da_hours = static_cast<double>(lit_da);
    SensorMetrics& s = result.sensors[i];
    s.udi_percent = in_range * to_percent;
    s.udi_fell_short_percent = below * to_percent;
    s.udi_exceeded_percent = above * to_percent;
    s.da_percent = da_hours * to_percent;
    s.cda_percent = credit * to_percent;
    s.mean_illuminance_lux = sum / analysed_hours;
    if (direct_illuminance_lux != nullptr) {
      const double* direct = direct_illuminance_lux->data() + i * e.cols();
      int sun_hours = 0;
      for (const Eigen::Index c : used) sun_hours += direct[c] > options.ase_threshold_lux;
      s.ase_hours = sun_hours;
    }
    // Compare counts, not rounded percentages, for the sDA cut
    SceneMetrics& scene = result.scene;
    scene.sda_percent += da_hours * 100.0 >= options.sda_min_da_percent * analysed_hours;
    scene.ase_percent += result.has_ase && s.ase_hours >= options.ase_min_hours;
    scene.udi_mean_percent += s.udi_percent;
    scene.udi_mean_fell_short_percent += s.udi_fell_short_percent;
    scene.udi_mean_exceeded_percent += s.udi_exceeded_percent;
    scene.da_mean_percent += s.da_percent;
    scene.cda_mean_percent += s.cda_percent;
    scene.mean_illuminance_lux += s.mean_illuminance_lux;
  }

  // Average over sensors; count the hours in which every sensor was in range
  SceneMetrics& scene = result.scene;
  const double per_sensor = 1.0 / static_cast<double>(n);
  scene.udi_mean_percent *= per_sensor;
  scene.udi_mean_fell_short_percent *= per_sensor;
  scene.udi_mean_exceeded_percent *= per_sensor;
  scene.da_mean_percent *= per_sensor;
  scene.cda_mean_percent *= per_sensor;
  scene.mean_illuminance_lux *= per_sensor;
  scene.sda_percent *= 100.0 * per_sensor;
  scene.ase_percent *= 100.0 * per_sensor;
  double all_in = dark_in_range ? dark_hours : 0;
  double all_below = dark_in_range ? 0 : dark_hours;
  double all_above = 0;
  for (size_t u = 0; u < used.size(); ++u) {
    all_in += !any_below[u] && !any_above[u];
    all_below += any_below[u];
    all_above += any_above[u];
  }
  scene.udi_all_percent = all_in * to_percent;
  scene.udi_all_fell_short_percent = all_below * to_percent;
  scene.udi_all_exceeded_percent = all_above * to_percent;
  return result;
}

}  // namespace fenestra
