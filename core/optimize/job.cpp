#include "core/optimize/job.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <map>
#include <span>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_join.h"
#include "core/common/content_hash.h"
#include "core/common/json_proto.h"
#include "core/common/status_macros.h"
#include "core/dc/two_stage.h"
#include "core/geometry/scene_proto.h"
#include "core/metrics/annual_metrics.h"
#include "core/metrics/illuminance.h"
#include "core/metrics/metric_errors.h"
#include "core/metrics/occupancy.h"
#include "core/optimize/build_info.h"
#include "core/optimize/design_variables.h"
#include "core/optimize/final_check.h"
#include "core/optimize/hourly_illuminance.h"
#include "core/optimize/metric_objective.h"
#include "core/optimize/vns.h"
#include "core/sky/epw.h"
#include "core/sky/sky_matrix.h"

namespace fenestra {
namespace {

namespace fs = std::filesystem;

double Since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

absl::Status Invalid(const std::string& field, const std::string& reason) {
  return absl::InvalidArgumentError(absl::StrCat("job ", field, ": ", reason));
}

absl::StatusOr<SceneMetric> ToSceneMetric(v1::Metric metric) {
  switch (metric) {
    case v1::METRIC_UNSPECIFIED:
    case v1::METRIC_UDI:
      return SceneMetric::kUdiMean;
    case v1::METRIC_UDI_ALL_SENSORS:
      return SceneMetric::kUdiAll;
    case v1::METRIC_DA:
      return SceneMetric::kDaMean;
    case v1::METRIC_CDA:
      return SceneMetric::kCdaMean;
    case v1::METRIC_SDA:
      return SceneMetric::kSda;
    case v1::METRIC_UDI_FELL_SHORT:
      return SceneMetric::kUdiMeanFellShort;
    case v1::METRIC_UDI_EXCEEDED:
      return SceneMetric::kUdiMeanExceeded;
    default:
      return Invalid("objective.metric", "unknown metric");
  }
}

BlindDesign DesignAt(const PreparedJob& job, const std::vector<double>& x) {
  BlindDesign design = DefaultDesign(job.scene);
  for (int i = 0; i < job.job.variables_size(); ++i) {
    design.*(FindDesignVariable(job.job.variables(i).name())->field) = x[i];
  }
  return design;
}

// `search_start_seconds`: when the search started, in the job's time.
v1::Evaluation ToProto(const PreparedJob& job, const VnsRecord& record,
                       double search_start_seconds) {
  v1::Evaluation e;
  e.set_index(record.index);
  for (int i = 0; i < job.job.variables_size(); ++i) {
    (*e.mutable_design())[job.job.variables(i).name()] = record.x[i];
  }
  e.mutable_value()->set_value(record.evaluation.value);
  e.mutable_value()->set_standard_error(record.evaluation.standard_error);
  e.set_seconds(record.evaluation_seconds);
  e.set_cached(record.cached);
  e.set_improved(record.improved);
  e.set_neighborhood(record.neighborhood);
  e.set_elapsed_seconds(search_start_seconds + record.elapsed_seconds);
  return e;
}

// The best value against time: the evaluations that moved the incumbent.
void AddBestOverTime(v1::JobResult& result) {
  for (const v1::Evaluation& e : result.history()) {
    if (!e.improved()) continue;
    v1::BestSoFar& best = *result.add_best_over_time();
    best.set_elapsed_seconds(e.elapsed_seconds());
    best.set_evaluation(e.index());
    *best.mutable_value() = e.value();
  }
}

void SetEstimate(v1::Estimate* out, double value, double standard_error) {
  out->set_value(value);
  out->set_standard_error(standard_error);
}

// What a result says about how it was made: the job as run (its scene self-contained), the
// weather's location and the versions.
void DescribeRun(const v1::Job& spec, const Scene& scene, const EpwLocation& location,
                 v1::JobResult& result) {
  v1::Job& job = *result.mutable_job();
  job = spec;
  job.clear_scene_file();
  job.clear_weather_file();
  *job.mutable_scene() = SelfContainedSceneProto(scene);
  std::vector<std::string> place;
  for (const std::string& part : {location.city, location.region, location.country}) {
    if (!part.empty() && part != "-") place.push_back(part);
  }
  result.set_weather_location(absl::StrJoin(place, ", "));
  for (const auto& [name, version] : ComponentVersions()) {
    (*result.mutable_versions())[name] = version;
  }
}

v1::Metrics ToProto(const AnnualMetricsEstimate& m) {
  v1::Metrics out;
  const SceneMetrics &v = m.value.scene, &se = m.standard_error.scene;
  SetEstimate(out.mutable_udi(), v.udi_mean_percent, se.udi_mean_percent);
  SetEstimate(out.mutable_udi_fell_short(), v.udi_mean_fell_short_percent,
              se.udi_mean_fell_short_percent);
  SetEstimate(out.mutable_udi_exceeded(), v.udi_mean_exceeded_percent,
              se.udi_mean_exceeded_percent);
  SetEstimate(out.mutable_udi_all_sensors(), v.udi_all_percent, se.udi_all_percent);
  SetEstimate(out.mutable_da(), v.da_mean_percent, se.da_mean_percent);
  SetEstimate(out.mutable_cda(), v.cda_mean_percent, se.cda_mean_percent);
  SetEstimate(out.mutable_sda(), v.sda_percent, se.sda_percent);
  for (size_t s = 0; s < m.value.sensors.size(); ++s) {
    SetEstimate(out.add_sensor_udi(), m.value.sensors[s].udi_percent,
                m.standard_error.sensors[s].udi_percent);
    SetEstimate(out.add_sensor_da(), m.value.sensors[s].da_percent,
                m.standard_error.sensors[s].da_percent);
  }
  return out;
}

// What the annual metrics of a job's designs need: the sky matrix, the occupied steps and
// the lit analysed ones (the rest are dark or not counted), the metric settings and the
// objective's metric.
struct AnnualSetting {
  SkyMatrix sky;
  std::vector<bool> occupied;
  std::vector<int> columns;  // lit analysed steps, ascending
  int analysed_hours = 0;
  MetricOptions options;
  SceneMetric metric = SceneMetric::kUdiMean;
};

absl::StatusOr<AnnualSetting> MakeAnnualSetting(const PreparedJob& job) {
  const v1::MetricSettings& m = job.job.metrics();
  AnnualSetting setting;
  SkyMatrixOptions sky_options;
  sky_options.ground_reflectance = job.scene.site.ground_reflectance;
  FENESTRA_ASSIGN_OR_RETURN(sky, BuildSkyMatrix(job.weather, sky_options));
  setting.sky = std::move(sky);
  std::vector<double> hours;
  for (const SkyStep& step : setting.sky.steps) hours.push_back(step.hour);
  FENESTRA_ASSIGN_OR_RETURN(occupied,
                            OccupiedSteps(hours, {m.occupied_start_h(), m.occupied_end_h()}));
  setting.occupied = std::move(occupied);
  const HourBasis hour_basis = m.all_hours() ? HourBasis::kAllHours : HourBasis::kOccupied;
  for (const int c : LitColumns(setting.sky.radiance)) {
    if (hour_basis == HourBasis::kAllHours || setting.occupied[c]) setting.columns.push_back(c);
  }
  setting.analysed_hours = AnalysedHours(setting.occupied, hour_basis);
  setting.options.udi_lower_lux = m.udi_lower_lux();
  setting.options.udi_upper_lux = m.udi_upper_lux();
  setting.options.da_threshold_lux = m.da_threshold_lux();
  setting.options.sda_min_da_percent = m.sda_time_fraction_percent();
  setting.options.hours = hour_basis;
  FENESTRA_ASSIGN_OR_RETURN(metric, ToSceneMetric(job.job.objective().metric()));
  setting.metric = metric;
  return setting;
}

// The final check (final_check.h) of design `x` against `two_stage`, the one-stage metrics
// taken as the search takes the two-stage ones. Cancelled as RunFinalCheck.
absl::StatusOr<v1::FinalCheck> CheckDesign(const PreparedJob& job, const AnnualSetting& setting,
                                           const std::vector<double>& x,
                                           const v1::Estimate& two_stage, DcBackend* backend,
                                           const std::function<bool()>& cancelled) {
  const DaylightMetric metric =
      [&](std::span<const Matrix> dc_batches) -> absl::StatusOr<Evaluation> {
    FENESTRA_ASSIGN_OR_RETURN(
        metrics,
        AnnualMetricsWithErrors(dc_batches, std::span<const Matrix>(&setting.sky.radiance, 1),
                                setting.columns, setting.occupied, setting.options));
    return MetricEvaluation(std::move(metrics), setting.metric);
  };
  FinalCheckOptions options;
  options.batches = job.job.sampling().batches();
  options.seed = job.job.sampling().seed();
  options.cancelled = cancelled;
  absl::StatusOr<FinalCheckOutcome> outcome =
      RunFinalCheck(job.scene, DesignAt(job, x), two_stage, metric, options, backend);
  if (absl::IsCancelled(outcome.status())) return outcome.status();
  if (!outcome.ok()) {
    return absl::Status(outcome.status().code(),
                        absl::StrCat("final check: ", outcome.status().message()));
  }
  if (const auto* metrics = std::any_cast<AnnualMetricsEstimate>(&outcome->one_stage.payload)) {
    *outcome->check.mutable_one_stage_metrics() = ToProto(*metrics);
  }
  return std::move(outcome->check);
}

// The final check of the search's best design into `result` (which holds the search's
// history), then reported once more with the check. A cancel during the check leaves it out.
absl::Status CheckBestDesign(const PreparedJob& job, const AnnualSetting& setting,
                             const VnsResult& search, DcBackend* backend,
                             const JobCallbacks& callbacks,
                             std::chrono::steady_clock::time_point start, v1::JobResult& result) {
  if (callbacks.stage) callbacks.stage("check");
  absl::StatusOr<v1::FinalCheck> check =
      CheckDesign(job, setting, search.best_x, result.best_value(), backend, callbacks.cancelled);
  if (absl::IsCancelled(check.status())) return absl::OkStatus();
  if (!check.ok()) return check.status();
  *result.mutable_final_check() = *check;
  if (callbacks.progress) {
    JobProgress last;
    last.evaluations = search.evaluations;
    last.max_evaluations = job.job.budget().max_evaluations();
    last.current = result.history(result.history_size() - 1);
    last.best = result.history(search.best_index);
    last.elapsed_seconds = Since(start);
    last.final_check = *std::move(check);
    callbacks.progress(last);
  }
  return absl::OkStatus();
}

}  // namespace

absl::StatusOr<v1::Job> ReadJobFile(const std::string& path) {
  v1::Job job;
  FENESTRA_RETURN_IF_ERROR(ReadJsonProtoFile(path, "job", &job));
  return job;
}

absl::StatusOr<PreparedJob> PrepareJob(const v1::Job& job, const std::string& base_dir) {
  FENESTRA_ASSIGN_OR_RETURN(prepared, ValidateJob(job, base_dir));
  // The weather: the job's, else the scene's site
  if (!job.weather_file().empty()) {
    prepared.weather_file = (fs::path(base_dir) / job.weather_file()).lexically_normal().string();
  } else {
    prepared.weather_file = prepared.scene.site.weather_file;
  }
  if (prepared.weather_file.empty()) {
    return Invalid("weather_file", "no weather file (neither the job nor the scene's site)");
  }
  FENESTRA_ASSIGN_OR_RETURN(weather, ReadEpw(prepared.weather_file));
  prepared.weather = std::move(weather);
  return prepared;
}

std::string OutdoorMatrixKey(const Scene& scene, const v1::Sampling& sampling) {
  ContentHash hash;
  hash.String("fenestra outdoor matrix v1");
  const TriangleMesh& mesh = scene.fixed;
  for (size_t t = 0; t < mesh.TriangleCount(); ++t) {
    if (mesh.side[t] != Side::kOutdoor) continue;
    for (int k = 0; k < 3; ++k) {
      const Vec3d v = mesh.vertices[3 * t + k];
      hash.Value(v.x), hash.Value(v.y), hash.Value(v.z);
    }
    const Material& m = scene.materials[mesh.material[t]];
    hash.Value(m.reflectance), hash.Value(m.transmittance);
  }
  const Window& w = scene.window;
  for (const Vec3d& v : {w.center, w.normal, w.up})
    hash.Value(v.x), hash.Value(v.y), hash.Value(v.z);
  hash.Value(w.width_m), hash.Value(w.height_m);
  hash.Value(sampling.outdoor_paths()), hash.Value(sampling.outdoor_bounces());
  hash.Value(sampling.seed()), hash.Value(sampling.basis_cells());
  const WindowParts parts = SamplingWindowParts(sampling, scene.window);
  hash.Value(parts.columns), hash.Value(parts.rows);
  return hash.Hex();
}

WindowParts SamplingWindowParts(const v1::Sampling& sampling, const Window& window) {
  const WindowParts automatic = AutomaticWindowParts(window);
  return {sampling.window_columns() > 0 ? sampling.window_columns() : automatic.columns,
          sampling.window_rows() > 0 ? sampling.window_rows() : automatic.rows};
}

absl::StatusOr<OutdoorMatrix> ComputeOutdoorMatrix(const Scene& scene, const v1::Sampling& sampling,
                                                   const std::function<bool()>& cancelled) {
  if (cancelled && cancelled()) return absl::CancelledError("cancelled before the outdoor stage");
  OutdoorOptions options;
  options.paths = sampling.outdoor_paths();
  options.max_bounces = sampling.outdoor_bounces();
  options.seed = sampling.seed();
  options.basis_cells = sampling.basis_cells();
  options.parts = SamplingWindowParts(sampling, scene.window);
  FENESTRA_ASSIGN_OR_RETURN(backend, MakeBackend(sampling.backend()));
  FENESTRA_ASSIGN_OR_RETURN(result, ComputeOutdoorStage(scene, options, backend.get()));
  OutdoorMatrix matrix;
  matrix.coefficients = std::move(result.coefficients);
  matrix.standard_error = std::move(result.standard_error);
  matrix.basis_cells = result.basis_cells;
  matrix.parts = result.parts;
  matrix.paths = result.paths_per_cell * result.coefficients.rows();
  matrix.bounces = sampling.outdoor_bounces();
  matrix.seed = sampling.seed();
  matrix.wall_seconds = result.wall_seconds;
  matrix.backend = result.backend;
  matrix.key = OutdoorMatrixKey(scene, sampling);
  return matrix;
}

absl::StatusOr<v1::JobResult> RunJob(const PreparedJob& job, const OutdoorMatrix* outdoor,
                                     const JobCallbacks& callbacks) {
  const auto start = std::chrono::steady_clock::now();
  const v1::Job& spec = job.job;
  v1::JobResult result;

  // Sky matrix, the occupied hours and the lit analysed ones, the metric settings
  if (callbacks.stage) callbacks.stage("sky");
  FENESTRA_ASSIGN_OR_RETURN(setting, MakeAnnualSetting(job));
  const std::vector<int>& columns = setting.columns;
  const MetricOptions& metric_options = setting.options;
  result.mutable_timings()->set_sky_seconds(Since(start));

  // Outdoor matrix: the cached one, or traced now
  const std::string key = OutdoorMatrixKey(job.scene, spec.sampling());
  OutdoorMatrix computed;
  if (outdoor != nullptr) {
    if (outdoor->key != key) {
      return absl::InvalidArgumentError("the cached outdoor matrix belongs to another site");
    }
  } else {
    if (callbacks.stage) callbacks.stage("outdoor");
    FENESTRA_ASSIGN_OR_RETURN(
        matrix, ComputeOutdoorMatrix(job.scene, spec.sampling(), callbacks.cancelled));
    computed = std::move(matrix);
    outdoor = &computed;
    result.mutable_timings()->set_outdoor_seconds(computed.wall_seconds);
  }

  // The objective: indoor stage with the same random streams for every design
  FENESTRA_ASSIGN_OR_RETURN(backend, MakeBackend(spec.sampling().backend()));
  IndoorOptions indoor_options;
  indoor_options.paths_per_sensor = spec.sampling().indoor_paths_per_sensor();
  indoor_options.max_bounces = spec.sampling().indoor_bounces();
  indoor_options.seed = spec.sampling().seed();
  indoor_options.basis_cells = spec.sampling().basis_cells();
  indoor_options.parts = SamplingWindowParts(spec.sampling(), job.scene.window);
  indoor_options.batches = spec.sampling().batches();
  if (!(outdoor->parts == indoor_options.parts)) {
    return absl::InvalidArgumentError("the outdoor matrix has other window parts than the job");
  }
  // S over the lit analysed hours, in lux
  const Matrix lit_sky = SkyColumnsInLux(setting.sky.radiance, columns);

  // Per design: the indoor stage, then the metrics from the tallies of E_b = (I_b O) S, as
  // the backend does it best (on the CPU the paths recorded once, then replayed per design;
  // on the GPU I and E never leave the device), for the designs within the job's ranges
  if (callbacks.stage) callbacks.stage("indoor paths");
  const Scene ranged = WithJobRanges(job.scene, spec);
  FENESTRA_ASSIGN_OR_RETURN(
      design_tallies,
      backend->MakeDesignTallies(ranged, indoor_options, outdoor->coefficients, lit_sky));
  const ObjectiveFunction objective =
      [&](const std::vector<double>& x) -> absl::StatusOr<Evaluation> {
    FENESTRA_ASSIGN_OR_RETURN(tallies, design_tallies->Tally(DesignAt(job, x), metric_options));
    FENESTRA_ASSIGN_OR_RETURN(
        metrics, AnnualMetricsFromTallies(tallies, setting.analysed_hours, metric_options));
    return MetricEvaluation(std::move(metrics), setting.metric);
  };

  // The search
  std::vector<DesignVariable> variables;
  for (const v1::DesignVariable& v : spec.variables()) {
    variables.push_back({v.name(), v.lower(), v.upper(), v.start(), v.fixed(), v.step()});
  }
  VnsOptions vns;
  if (spec.neighborhoods_size() > 0) {
    vns.neighborhoods.clear();
    for (const v1::Neighborhood& n : spec.neighborhoods()) {
      vns.neighborhoods.push_back({n.variables(), n.radius()});
    }
  }
  switch (spec.objective().goal()) {
    case v1::GOAL_MINIMIZE:
      vns.objective.sense = ObjectiveSense::kMinimize;
      break;
    case v1::GOAL_TARGET:
      vns.objective.sense = ObjectiveSense::kTarget;
      vns.objective.target = spec.objective().target();
      vns.objective.target_tolerance = spec.objective().target_tolerance();
      break;
    default:
      vns.objective.sense = ObjectiveSense::kMaximize;
  }
  vns.max_evaluations = spec.budget().max_evaluations();
  vns.max_seconds = spec.budget().max_seconds();
  vns.failed_cycles_to_stop = std::max(0, spec.budget().failed_cycles_to_stop());
  vns.seed = spec.sampling().seed();
  VnsCallbacks vns_callbacks;
  vns_callbacks.cancelled = callbacks.cancelled;
  if (callbacks.stage) callbacks.stage("search");
  const double search_start = Since(start);
  if (callbacks.progress) {
    vns_callbacks.progress = [&](const VnsProgress& p) {
      JobProgress progress;
      progress.evaluations = p.evaluations;
      progress.max_evaluations = p.max_evaluations;
      progress.current = ToProto(job, *p.current, search_start);
      progress.best = ToProto(job, *p.best, search_start);
      progress.elapsed_seconds = Since(start);
      progress.remaining_seconds = p.remaining_seconds;
      callbacks.progress(progress);
    };
  }
  FENESTRA_ASSIGN_OR_RETURN(search, RunVns(variables, objective, vns, vns_callbacks));

  // The best design's hourly illuminance, for reports and other tools
  design_tallies.reset();  // the search's paths are no longer needed
  if (search.evaluations > 0 && search.stop_reason != StopReason::kCancelled &&
      static_cast<int64_t>(job.scene.sensors.size() * setting.sky.steps.size()) <=
          kMaxHourlyIlluminanceValues) {
    const auto hourly_start = std::chrono::steady_clock::now();
    FENESTRA_ASSIGN_OR_RETURN(
        hourly, DesignHourlyIlluminance(job.scene, DesignAt(job, search.best_x), indoor_options,
                                        outdoor->coefficients, setting.sky, *backend));
    *result.mutable_best_hourly() = std::move(hourly);
    result.mutable_timings()->set_best_hourly_seconds(Since(hourly_start));
  }
  DescribeRun(spec, ranged, job.weather.location, result);

  // The result
  for (size_t i = 0; i < variables.size(); ++i) {
    (*result.mutable_best_design())[variables[i].name] = search.best_x[i];
  }
  SetEstimate(result.mutable_best_value(), search.best.value, search.best.standard_error);
  if (const auto* metrics = std::any_cast<AnnualMetricsEstimate>(&search.best.payload)) {
    *result.mutable_best_metrics() = ToProto(*metrics);
  }
  for (const VnsRecord& record : search.history) {
    *result.add_history() = ToProto(job, record, search_start);
  }
  AddBestOverTime(result);
  result.set_evaluations(search.evaluations);
  result.set_stop_reason(std::string(StopReasonName(search.stop_reason)));
  result.mutable_timings()->set_evaluation_seconds(search.evaluation_seconds);
  result.set_outdoor_mean_relative_standard_error(
      MeanRelativeError(outdoor->coefficients, outdoor->standard_error, 0.01, false));
  result.set_backend(backend->Name());

  // The final check: the best design by the one-stage method
  if (spec.sampling().final_check() && search.stop_reason != StopReason::kCancelled) {
    FENESTRA_RETURN_IF_ERROR(
        CheckBestDesign(job, setting, search, backend.get(), callbacks, start, result));
  }
  result.mutable_timings()->set_total_seconds(Since(start));
  return result;
}

absl::StatusOr<v1::FinalCheck> CheckJobDesign(
    const PreparedJob& job, const google::protobuf::Map<std::string, double>& design,
    const v1::Estimate& two_stage) {
  std::vector<double> x;
  for (const v1::DesignVariable& v : job.job.variables()) {
    const auto it = design.find(v.name());
    x.push_back(it == design.end() ? v.start() : it->second);
  }
  FENESTRA_ASSIGN_OR_RETURN(setting, MakeAnnualSetting(job));
  FENESTRA_ASSIGN_OR_RETURN(backend, MakeBackend(job.job.sampling().backend()));
  return CheckDesign(job, setting, x, two_stage, backend.get(), {});
}

}  // namespace fenestra
