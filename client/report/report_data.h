#pragma once

// What the report shows, gathered and checked from a job result (job.proto, JobResult).
#include <map>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "absl/status/statusor.h"
#include "core/geometry/scene.h"
#include "fenestra/v1/job.pb.h"

namespace fenestra {

// One evaluation of the search.
struct SearchPoint {
  int number = 0;      // 1, 2, ... in the order of the search
  double seconds = 0;  // evaluation time spent up to and including this one [s]
  double value = 0;    // the objective's metric [%]
  double standard_error = 0;
  bool improved = false;  // became the best design
  bool cached = false;
  std::map<std::string, double> design;
};

// The best value's standard error at a time of the search.
struct ErrorPoint {
  double seconds = 0;
  double standard_error = 0;  // [% points]
};

// One constraint of the objective at the best design.
struct ConstraintRow {
  v1::Constraint constraint;
  // The best design's value of its metric [%]; unset when the result holds none.
  std::optional<v1::Estimate> estimate;
  bool holds = false;
};

// A free design variable: its name, unit and the range the search explored.
struct FreeVariable {
  std::string name;
  std::string label;  // e.g. "tilt α [rad]"
  double lower = 0, upper = 0;
};

struct ReportData {
  v1::JobResult result;
  std::string source;  // the result's file, or the job id, for messages and the page
  // The scene as the job ran it; unset for results that do not hold it.
  std::optional<Scene> scene;
  BlindDesign best_design;
  std::vector<FreeVariable> free_variables;
  std::string metric_name;   // the objective's metric, e.g. "UDI 100–3000 lx"
  std::string metric_label;  // with its unit, e.g. "UDI 100–3000 lx [%]"
  std::vector<SearchPoint> search;
  // The best design's standard error after each evaluation, from the history.
  std::vector<ErrorPoint> best_error;
  // The job's own record of its error against time and its final one-stage check, when the
  // result holds them (as label -> value rows); unset: not recorded.
  std::optional<std::vector<ErrorPoint>> recorded_error;
  std::optional<std::vector<std::pair<std::string, std::string>>> final_check;
  // The sensor the temporal map shows (index into the scene's sensors); -1 without hourly
  // illuminance.
  int map_sensor = -1;
  // Per time step of the hourly illuminance: occupied by the job's schedule.
  std::vector<bool> occupied;
  // The objective's constraints at the best design: the result's best_constraints, or, for
  // results without them, worked out from best_metrics with constraint_standard_errors.
  std::vector<ConstraintRow> constraints;
  double constraint_standard_errors = 1;
  // The scene's blind is operated (VenetianBlind.AUTOMATED_SUN): in place only in some hours.
  bool operated_blind = false;
  // ASE's direct-sun threshold [lx] and hours, the job's (defaults where it has none).
  double ase_threshold_lux = 1000;
  int ase_min_hours = 250;
};

// Checks `result` and gathers what the report needs. `sensor` picks the temporal map's
// sensor by name or by index from 0; empty = the sensor with the lowest UDI. `source` names
// the result in messages. InvalidArgument naming the field for inconsistent results (sizes
// that do not match, values that are not finite, an unknown sensor).
absl::StatusOr<ReportData> GatherReportData(const v1::JobResult& result, const std::string& source,
                                            const std::string& sensor);

// The objective's metric, e.g. "UDI 100–3000 lx", "DA300" (its unit is %).
std::string MetricName(const v1::Job& job);

// A metric with the job's settings, e.g. "sDA300/50%", "ASE1000,250", "blind in place".
std::string MetricName(v1::Metric metric, const v1::MetricSettings& settings);

// The estimate of `metric` in `metrics`; nullptr when `metrics` does not hold it.
const v1::Estimate* MetricEstimate(const v1::Metrics& metrics, v1::Metric metric);

// A design variable's value with its unit: "0.3487 rad (20.0°)", "0.1500 m"; a finish's index
// with its materials' names: "1: white / aluminium outer".
std::string DesignValue(const v1::DesignVariable& variable, double value);

// Index of the sensor with the lowest UDI in `metrics` (0 when there are none).
int WorstSensorByUdi(const v1::Metrics& metrics);

}  // namespace fenestra
