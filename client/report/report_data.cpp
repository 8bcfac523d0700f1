#include "client/report/report_data.h"

#include <fmt/format.h>

#include <cmath>
#include <numbers>

#include "absl/strings/numbers.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/str_join.h"
#include "core/common/status_macros.h"
#include "core/metrics/occupancy.h"
#include "core/optimize/design_variables.h"

namespace fenestra {
namespace {

absl::Status Inconsistent(const std::string& source, const std::string& field,
                          const std::string& reason) {
  return absl::InvalidArgumentError(absl::StrCat(source, ": ", field, ": ", reason));
}

std::string VariableLabel(const std::string& name) {
  if (name == "alpha") return "tilt α [rad]";
  if (name == "width") return "slat width w [m]";
  if (name == "spacing") return "slat spacing s [m]";
  if (name == "thickness") return "slat thickness t [m]";
  if (name == kFinishVariable) return "slat finish [index]";
  return name;
}

// The evaluations in order, with their cumulative time, and the best one's error after each.
absl::Status GatherSearch(const std::string& source, ReportData& data) {
  double seconds = 0;
  double best_error = 0;
  for (int i = 0; i < data.result.history_size(); ++i) {
    const v1::Evaluation& e = data.result.history(i);
    const double se = e.value().standard_error();
    if (!std::isfinite(e.value().value()) || !std::isfinite(se) || se < 0 ||
        !std::isfinite(e.seconds()) || e.seconds() < 0) {
      return Inconsistent(source, absl::StrCat("history[", i, "]"),
                          "value, standard_error and seconds must be finite and >= 0");
    }
    seconds += e.seconds();
    SearchPoint point{i + 1, seconds, e.value().value(), se, e.improved(), e.cached(), {}};
    for (const auto& [name, value] : e.design()) point.design[name] = value;
    data.search.push_back(std::move(point));
    if (e.improved() || i == 0) best_error = se;
    data.best_error.push_back({seconds, best_error});
  }
  return absl::OkStatus();
}

void GatherVariables(ReportData& data) {
  const v1::Job& job = data.result.job();
  for (const v1::DesignVariable& v : job.variables()) {
    if (v.fixed() || !(v.upper() > v.lower())) continue;
    data.free_variables.push_back({v.name(), VariableLabel(v.name()), v.lower(), v.upper()});
  }
}

// The scene and the best design, for results that hold the job.
absl::Status GatherScene(const std::string& source, ReportData& data) {
  if (!data.result.job().has_scene()) return absl::OkStatus();
  FENESTRA_ASSIGN_OR_RETURN(scene, BuildScene(data.result.job().scene(), source + ": job.scene"));
  std::map<std::string, double> best(data.result.best_design().begin(),
                                     data.result.best_design().end());
  absl::StatusOr<BlindDesign> design = JobDesignWithOverrides(scene, data.result.job(), best);
  if (!design.ok())
    return Inconsistent(source, "best_design", std::string(design.status().message()));
  data.best_design = *design;
  const int sensors = static_cast<int>(scene.sensors.size());
  const v1::Metrics& m = data.result.best_metrics();
  if ((m.sensor_udi_size() != 0 && m.sensor_udi_size() != sensors) ||
      (m.sensor_da_size() != 0 && m.sensor_da_size() != sensors)) {
    return Inconsistent(source, "best_metrics",
                        absl::StrCat("per-sensor metrics for ", m.sensor_udi_size(),
                                     " sensors, the scene has ", sensors));
  }
  if (m.sensor_sunlit_hours_size() != 0 && m.sensor_sunlit_hours_size() != sensors) {
    return Inconsistent(
        source, "best_metrics.sensor_sunlit_hours",
        absl::StrCat("holds ", m.sensor_sunlit_hours_size(), " sensors, the scene has ", sensors));
  }
  for (const int hours : m.sensor_sunlit_hours()) {
    if (hours < 0) return Inconsistent(source, "best_metrics.sensor_sunlit_hours", "must be >= 0");
  }
  data.operated_blind = scene.blind() && scene.blind()->automated_sun;
  data.scene = std::move(scene);
  return absl::OkStatus();
}

absl::Status CheckHourly(const std::string& source, const ReportData& data) {
  const v1::HourlyIlluminance& h = data.result.best_hourly();
  const int64_t steps = h.month_size();
  const int64_t values = static_cast<int64_t>(h.sensors_size()) * steps;
  if (h.day_size() != steps || h.hour_size() != steps || h.illuminance_lux_size() != values ||
      (h.standard_error_lux_size() != 0 && h.standard_error_lux_size() != values)) {
    return Inconsistent(
        source, "best_hourly",
        absl::StrCat("needs ", values, " values for ", h.sensors_size(), " sensors x ", steps,
                     " steps, has ", h.illuminance_lux_size()));
  }
  if (!data.scene || h.sensors_size() != static_cast<int>(data.scene->sensors.size())) {
    return Inconsistent(source, "best_hourly.sensors", "do not match the scene's sensors");
  }
  for (int64_t j = 0; j < steps; ++j) {
    if (h.month(j) < 1 || h.month(j) > 12 || h.day(j) < 1 || h.day(j) > 31 ||
        !(h.hour(j) >= 0 && h.hour(j) <= 24)) {
      return Inconsistent(source, absl::StrCat("best_hourly step ", j),
                          "month, day or hour out of range");
    }
  }
  if ((h.direct_sun_lux_size() != 0 && h.direct_sun_lux_size() != values) ||
      (h.blind_in_place_size() != 0 && h.blind_in_place_size() != steps)) {
    return Inconsistent(
        source, "best_hourly",
        absl::StrCat("direct_sun_lux needs ", values, " values and blind_in_place ", steps,
                     ", has ", h.direct_sun_lux_size(), " and ", h.blind_in_place_size()));
  }
  for (const auto& [field, lux] : {std::pair{"illuminance_lux", &h.illuminance_lux()},
                                   std::pair{"direct_sun_lux", &h.direct_sun_lux()}}) {
    for (const float e : *lux) {
      if (!std::isfinite(e) || e < 0) {
        return Inconsistent(source, absl::StrCat("best_hourly.", field),
                            "values must be finite and >= 0");
      }
    }
  }
  return absl::OkStatus();
}

// The temporal map's sensor: by name, else by index; the worst by UDI when not given.
absl::StatusOr<int> PickSensor(const Scene& scene, const v1::Metrics& metrics,
                               const std::string& sensor) {
  if (sensor.empty()) return WorstSensorByUdi(metrics);
  for (size_t i = 0; i < scene.sensors.size(); ++i) {
    if (scene.sensors[i].name == sensor) return static_cast<int>(i);
  }
  int index;
  if (absl::SimpleAtoi(sensor, &index) && index >= 0 &&
      index < static_cast<int>(scene.sensors.size())) {
    return index;
  }
  std::vector<std::string> names;
  for (const Sensor& s : scene.sensors) names.push_back(s.name);
  if (names.size() > 12) names.resize(12), names.push_back("...");
  return absl::InvalidArgumentError(
      absl::StrCat("--sensor: no sensor '", sensor, "' (give a name: ", absl::StrJoin(names, ", "),
                   "; or an index from 0 to ", scene.sensors.size() - 1, ")"));
}

}  // namespace

std::string MetricName(v1::Metric metric, const v1::MetricSettings& m) {
  const std::string udi = fmt::format("UDI {:g}–{:g} lx", m.udi_lower_lux(), m.udi_upper_lux());
  switch (metric) {
    case v1::METRIC_UDI_ALL_SENSORS:
      return udi + ", all sensors at once";
    case v1::METRIC_DA:
      return fmt::format("DA{:g}", m.da_threshold_lux());
    case v1::METRIC_CDA:
      return fmt::format("cDA{:g}", m.da_threshold_lux());
    case v1::METRIC_SDA:
      return fmt::format("sDA{:g}/{:g}%", m.da_threshold_lux(), m.sda_time_fraction_percent());
    case v1::METRIC_UDI_FELL_SHORT:
      return udi + ", fell short";
    case v1::METRIC_UDI_EXCEEDED:
      return udi + ", exceeded";
    case v1::METRIC_ASE:
      return fmt::format("ASE{:g},{}", m.ase_threshold_lux() > 0 ? m.ase_threshold_lux() : 1000,
                         m.ase_min_hours() > 0 ? m.ase_min_hours() : 250);
    case v1::METRIC_BLIND_IN_PLACE:
      return "blind in place";
    default:
      return udi;
  }
}

std::string MetricName(const v1::Job& job) {
  return MetricName(job.objective().metric(), job.metrics());
}

const v1::Estimate* MetricEstimate(const v1::Metrics& m, v1::Metric metric) {
  const auto held = [](bool has, const v1::Estimate& e) { return has ? &e : nullptr; };
  switch (metric) {
    case v1::METRIC_UDI_ALL_SENSORS:
      return held(m.has_udi_all_sensors(), m.udi_all_sensors());
    case v1::METRIC_DA:
      return held(m.has_da(), m.da());
    case v1::METRIC_CDA:
      return held(m.has_cda(), m.cda());
    case v1::METRIC_SDA:
      return held(m.has_sda(), m.sda());
    case v1::METRIC_UDI_FELL_SHORT:
      return held(m.has_udi_fell_short(), m.udi_fell_short());
    case v1::METRIC_UDI_EXCEEDED:
      return held(m.has_udi_exceeded(), m.udi_exceeded());
    case v1::METRIC_ASE:
      return held(m.has_ase(), m.ase());
    case v1::METRIC_BLIND_IN_PLACE:
      return held(m.has_blind_in_place(), m.blind_in_place());
    default:
      return held(m.has_udi(), m.udi());
  }
}

std::string DesignValue(const v1::DesignVariable& variable, double value) {
  if (variable.name() == "alpha") {
    return fmt::format("{:.4f} rad ({:.1f}°)", value, value * 180 / std::numbers::pi);
  }
  if (variable.name() == kFinishVariable) {
    const std::optional<size_t> index = FinishIndex(value, variable.finishes_size());
    if (!index) return fmt::format("{:g}", value);
    return fmt::format("{}: {}", *index, FinishName(variable.finishes(static_cast<int>(*index))));
  }
  return fmt::format("{:.4f} m", value);
}

int WorstSensorByUdi(const v1::Metrics& metrics) {
  int worst = 0;
  for (int i = 1; i < metrics.sensor_udi_size(); ++i) {
    if (metrics.sensor_udi(i).value() < metrics.sensor_udi(worst).value()) worst = i;
  }
  return worst;
}

namespace {

// What the job itself recorded: its best value's error against time and the final one-stage
// check; left unset (the page says "not recorded") for results without them.
void GatherRecordedChecks(ReportData& data) {
  const v1::JobResult& result = data.result;
  if (result.best_over_time_size() > 0) {
    std::vector<ErrorPoint>& points = data.recorded_error.emplace();
    for (const v1::BestSoFar& best : result.best_over_time()) {
      points.push_back({best.elapsed_seconds(), best.value().standard_error()});
    }
  }
  if (result.has_final_check()) {
    const v1::FinalCheck& c = result.final_check();
    const auto estimate = [](const v1::Estimate& e) {
      return fmt::format("{:.2f} ± {:.2f} %", e.value(), e.standard_error());
    };
    data.final_check = std::vector<std::pair<std::string, std::string>>{
        {"two-stage (the search)", estimate(c.two_stage())},
        {"one-stage check", estimate(c.one_stage())},
        {"difference", estimate(c.difference())},
        {"verdict",
         c.disagrees() ? "disagrees: beyond 3 standard errors" : "agrees within 3 standard errors"},
        {"one-stage paths per sensor",
         fmt::format("{} (pilot {}){}", c.paths_per_sensor(), c.pilot_paths_per_sensor(),
                     c.paths_limited() ? ", at the limit" : "")},
        {"check time", fmt::format("{:.2f} s", c.seconds())}};
  }
}

// The objective's constraints at the best design: as the result records them, else from its
// metrics (older results): a constraint holds unless its metric is beyond the bound by more
// than constraint_standard_errors of its standard errors.
void GatherConstraints(ReportData& data) {
  const v1::JobResult& result = data.result;
  const v1::Objective& objective = result.job().objective();
  if (objective.constraint_standard_errors() > 0) {
    data.constraint_standard_errors = objective.constraint_standard_errors();
  }
  if (result.best_constraints_size() > 0) {
    for (const v1::ConstraintResult& c : result.best_constraints()) {
      data.constraints.push_back({c.constraint(), c.estimate(), c.holds()});
    }
    return;
  }
  for (const v1::Constraint& c : objective.constraints()) {
    ConstraintRow row{c, std::nullopt, false};
    if (const v1::Estimate* e = MetricEstimate(result.best_metrics(), c.metric())) {
      const double slack = data.constraint_standard_errors * e->standard_error();
      row.estimate = *e;
      row.holds = c.bound() == v1::Constraint::AT_LEAST ? e->value() + slack >= c.value()
                                                        : e->value() - slack <= c.value();
    }
    data.constraints.push_back(std::move(row));
  }
}

}  // namespace

absl::StatusOr<ReportData> GatherReportData(const v1::JobResult& result, const std::string& source,
                                            const std::string& sensor) {
  ReportData data;
  data.result = result;
  data.source = source;
  data.metric_name = MetricName(result.job());
  data.metric_label = data.metric_name + " [%]";
  FENESTRA_RETURN_IF_ERROR(GatherSearch(source, data));
  GatherVariables(data);
  FENESTRA_RETURN_IF_ERROR(GatherScene(source, data));
  if (result.has_best_hourly()) {
    FENESTRA_RETURN_IF_ERROR(CheckHourly(source, data));
    FENESTRA_ASSIGN_OR_RETURN(index, PickSensor(*data.scene, result.best_metrics(), sensor));
    data.map_sensor = index;
    const std::vector<double> hours(result.best_hourly().hour().begin(),
                                    result.best_hourly().hour().end());
    const v1::MetricSettings& m = result.job().metrics();
    FENESTRA_ASSIGN_OR_RETURN(occupied,
                              OccupiedSteps(hours, {m.occupied_start_h(), m.occupied_end_h()}));
    data.occupied = std::move(occupied);
  } else if (!sensor.empty()) {
    return absl::InvalidArgumentError("--sensor: the result holds no hourly illuminance to map");
  }
  GatherRecordedChecks(data);
  GatherConstraints(data);
  const v1::MetricSettings& settings = result.job().metrics();
  if (settings.ase_threshold_lux() > 0) data.ase_threshold_lux = settings.ase_threshold_lux();
  if (settings.ase_min_hours() > 0) data.ase_min_hours = settings.ase_min_hours();
  return data;
}

}  // namespace fenestra
