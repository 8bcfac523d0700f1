#include "core/metrics/annual_metrics.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <string>
#include <utility>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_join.h"
#include "core/metrics/hour_class.h"
#include "core/metrics/illuminance.h"

namespace fenestra {
namespace {

constexpr std::array<std::pair<SceneMetric, std::string_view>, 16> kSceneMetricNames = {{
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
    {SceneMetric::kBlindInPlace, "blind_in_place"},
    {SceneMetric::kGlareAutonomy, "glare_autonomy"},
    {SceneMetric::kGlareHours, "glare_hours"},
    {SceneMetric::kSolarGain, "solar_gain"},
    {SceneMetric::kCoolingSolarGain, "cooling_solar_gain"},
}};

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
    case SceneMetric::kBlindInPlace:
      return s.blind_in_place_percent;
    case SceneMetric::kGlareAutonomy:
      return s.glare_autonomy_percent;
    case SceneMetric::kGlareHours:
      return s.glare_hours_percent;
    case SceneMetric::kSolarGain:
      return s.solar_gain_kwh;
    case SceneMetric::kCoolingSolarGain:
      return s.cooling_solar_gain_kwh;
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

absl::Status CheckMetricOptions(const MetricOptions& o) {
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

int AnalysedHours(const std::vector<bool>& occupied, HourBasis hours) {
  if (hours == HourBasis::kAllHours) return static_cast<int>(occupied.size());
  return static_cast<int>(std::count(occupied.begin(), occupied.end(), true));
}

HourTallyBuilder::HourTallyBuilder(int sensors, int64_t hours, const MetricOptions& options)
    : any_below_(hours, 0),
      any_above_(hours, 0),
      lower_(options.udi_lower_lux),
      upper_(options.udi_upper_lux),
      da_(options.da_threshold_lux) {
  tally_.hours = hours;
  tally_.sensors.resize(sensors);
}

void HourTallyBuilder::AddRow(int sensor, const double* row) {
  // Without branches: the comparisons are data, not control flow (hours fall either side of
  // the limits at random, which a branch predictor cannot learn); noting per hour whether
  // some sensor left the range
  int64_t below = 0, above = 0, da_hours = 0;
  double credit = 0, sum = 0;
  uint8_t* any_below = any_below_.data();
  uint8_t* any_above = any_above_.data();
  const int64_t hours = tally_.hours;  // read once: the flags' stores may alias it
  for (int64_t h = 0; h < hours; ++h) {
    const double v = row[h];
    const HourClass c = ClassifyHour(v, lower_, upper_, da_);
    below += c.below;
    above += c.above;
    any_below[h] |= c.below;
    any_above[h] |= c.above;
    da_hours += c.da;
    credit += c.credit;
    sum += v;
  }
  tally_.sensors[sensor] = {below, above, da_hours, credit, sum};
}

HourTally HourTallyBuilder::Finish() {
  for (int64_t h = 0; h < tally_.hours; ++h) {
    tally_.all_in += !any_below_[h] && !any_above_[h];
    tally_.any_below += any_below_[h];
    tally_.any_above += any_above_[h];
  }
  return std::move(tally_);
}

HourTally TallyHours(const Matrix& illuminance_lux, const MetricOptions& options) {
  const Matrix& e = illuminance_lux;
  HourTallyBuilder builder(static_cast<int>(e.rows()), e.cols(), options);
  for (Eigen::Index i = 0; i < e.rows(); ++i) {
    builder.AddRow(static_cast<int>(i), e.data() + i * e.cols());
  }
  return builder.Finish();
}

int LeedDaylightPoints(double sda_percent) {
  return sda_percent >= 75 ? 3 : sda_percent >= 55 ? 2 : sda_percent >= 40 ? 1 : 0;
}

std::vector<int64_t> SunlitHours(const Matrix& direct_illuminance_lux,
                                 const MetricOptions& options) {
  std::vector<int64_t> hours(direct_illuminance_lux.rows());
  for (Eigen::Index i = 0; i < direct_illuminance_lux.rows(); ++i) {
    hours[i] = (direct_illuminance_lux.row(i).array() > options.ase_threshold_lux).count();
  }
  return hours;
}

namespace {

// ASE in `metrics` from each sensor's sunlit hours.
void SetAse(const std::vector<int64_t>& sunlit, const MetricOptions& options,
            AnnualMetrics* metrics) {
  metrics->has_ase = true;
  double sensors_with_ase = 0;
  for (size_t i = 0; i < metrics->sensors.size() && i < sunlit.size(); ++i) {
    metrics->sensors[i].ase_hours = static_cast<double>(sunlit[i]);
    sensors_with_ase += sunlit[i] >= options.ase_min_hours;
  }
  metrics->scene.ase_percent =
      sensors_with_ase * (100.0 * (1.0 / static_cast<double>(metrics->sensors.size())));
}

}  // namespace

AnnualMetrics MetricsFromTally(const HourTally& tally, int analysed_hours,
                               const MetricOptions& options) {
  const double dark_hours = analysed_hours - static_cast<double>(tally.hours);
  const double to_percent = 100.0 / analysed_hours;
  const bool dark_in_range = 0.0 >= options.udi_lower_lux;  // E = 0 falls short or is in range
  const size_t n = tally.sensors.size();

  AnnualMetrics result;
  result.analysed_hours = analysed_hours;
  result.sensors.resize(n);
  SceneMetrics& scene = result.scene;
  for (size_t i = 0; i < n; ++i) {
    const SensorHourTally& t = tally.sensors[i];
    const double lit_in_range = static_cast<double>(tally.hours - t.below - t.above);
    const double in_range = lit_in_range + (dark_in_range ? dark_hours : 0);
    const double below = static_cast<double>(t.below) + (dark_in_range ? 0 : dark_hours);
    const double da_hours = static_cast<double>(t.da);
    SensorMetrics& s = result.sensors[i];
    s.udi_percent = in_range * to_percent;
    s.udi_fell_short_percent = below * to_percent;
    s.udi_exceeded_percent = static_cast<double>(t.above) * to_percent;
    s.da_percent = da_hours * to_percent;
    s.cda_percent = t.credit * to_percent;
    s.mean_illuminance_lux = t.sum / analysed_hours;
    // Compare counts, not rounded percentages, for the sDA cut
    scene.sda_percent += da_hours * 100.0 >= options.sda_min_da_percent * analysed_hours;
    scene.udi_mean_percent += s.udi_percent;
    scene.udi_mean_fell_short_percent += s.udi_fell_short_percent;
    scene.udi_mean_exceeded_percent += s.udi_exceeded_percent;
    scene.da_mean_percent += s.da_percent;
    scene.cda_mean_percent += s.cda_percent;
    scene.mean_illuminance_lux += s.mean_illuminance_lux;
  }

  // Average over sensors; the hours in which every sensor was in range, dark ones included
  const double per_sensor = 1.0 / static_cast<double>(n);
  scene.udi_mean_percent *= per_sensor;
  scene.udi_mean_fell_short_percent *= per_sensor;
  scene.udi_mean_exceeded_percent *= per_sensor;
  scene.da_mean_percent *= per_sensor;
  scene.cda_mean_percent *= per_sensor;
  scene.mean_illuminance_lux *= per_sensor;
  scene.sda_percent *= 100.0 * per_sensor;
  const double all_in = static_cast<double>(tally.all_in) + (dark_in_range ? dark_hours : 0);
  const double all_below = static_cast<double>(tally.any_below) + (dark_in_range ? 0 : dark_hours);
  scene.udi_all_percent = all_in * to_percent;
  scene.udi_all_fell_short_percent = all_below * to_percent;
  scene.udi_all_exceeded_percent = static_cast<double>(tally.any_above) * to_percent;
  if (!tally.sunlit.empty()) SetAse(tally.sunlit, options, &result);
  if (tally.blind_hours >= 0) {
    scene.blind_in_place_percent = static_cast<double>(tally.blind_hours) * to_percent;
  }
  return result;
}

void AddAse(const Matrix& direct_illuminance_lux, const MetricOptions& options,
            AnnualMetrics* metrics) {
  SetAse(SunlitHours(direct_illuminance_lux, options), options, metrics);
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
  const absl::Status options_ok = CheckMetricOptions(options);
  if (!options_ok.ok()) return options_ok;
  if (!e.allFinite() ||
      (direct_illuminance_lux != nullptr && !direct_illuminance_lux->allFinite())) {
    return absl::InvalidArgumentError("illuminance has a non-finite value");
  }
  const int analysed_hours = AnalysedHours(occupied, options.hours);
  if (analysed_hours == 0) return absl::InvalidArgumentError("no occupied hours to analyse");

  // Keep the analysed steps among `columns` (the dark rest is counted, not stored)
  std::vector<Eigen::Index> used;  // positions in `columns`
  for (size_t c = 0; c < columns.size(); ++c) {
    if (options.hours == HourBasis::kAllHours || occupied[columns[c]]) {
      used.push_back(static_cast<Eigen::Index>(c));
    }
  }
  const bool every_column = used.size() == columns.size();
  const Matrix selected = every_column ? Matrix() : Matrix(e(Eigen::all, used));
  AnnualMetrics result =
      MetricsFromTally(TallyHours(every_column ? e : selected, options), analysed_hours, options);
  if (direct_illuminance_lux != nullptr) {
    AddAse(every_column ? *direct_illuminance_lux
                        : Matrix((*direct_illuminance_lux)(Eigen::all, used)),
           options, &result);
  }
  return result;
}

}  // namespace fenestra
