#include "core/optimize/job.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <map>
#include <numbers>
#include <set>

#include "absl/strings/str_cat.h"
#include "core/common/content_hash.h"
#include "core/common/json_proto.h"
#include "core/common/status_macros.h"
#include "core/dc/two_stage.h"
#include "core/metrics/annual_metrics.h"
#include "core/metrics/illuminance.h"
#include "core/metrics/metric_errors.h"
#include "core/metrics/occupancy.h"
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

// The blind variables a job may set, with their physical limits.
struct VariableInfo {
  const char* name;
  double lowest;
  double highest;
  double BlindDesign::*field;
  ParameterRange BlindSpec::*range;
};
constexpr VariableInfo kVariables[] = {
    {"alpha", -std::numbers::pi / 2, std::numbers::pi / 2, &BlindDesign::tilt_rad,
     &BlindSpec::tilt_rad},
    {"width", 1e-6, 1e3, &BlindDesign::slat_width_m, &BlindSpec::slat_width_m},
    {"spacing", 0, 1e3, &BlindDesign::slat_spacing_m, &BlindSpec::slat_spacing_m},
    {"thickness", 1e-6, 1e3, &BlindDesign::slat_thickness_m, &BlindSpec::slat_thickness_m},
};

const VariableInfo* FindVariable(const std::string& name) {
  for (const VariableInfo& v : kVariables) {
    if (name == v.name) return &v;
  }
  return nullptr;
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

absl::Status ValidateVariables(const v1::Job& job, const Scene& scene) {
  if (job.variables_size() > 0 && !scene.blind) {
    return Invalid("variables", "the scene has no blind to design");
  }
  std::set<std::string> seen;
  for (int i = 0; i < job.variables_size(); ++i) {
    const v1::DesignVariable& v = job.variables(i);
    const std::string field = absl::StrCat("variables[", i, "]");
    const VariableInfo* info = FindVariable(v.name());
    if (!info) {
      return Invalid(field + ".name", absl::StrCat("unknown design variable '", v.name(),
                                                   "' (known: alpha, width, spacing, thickness)"));
    }
    if (!seen.insert(v.name()).second) {
      return Invalid(field + ".name", absl::StrCat("variable '", v.name(), "' given twice"));
    }
    for (double x : {v.lower(), v.upper(), v.start(), v.step()}) {
      if (!std::isfinite(x)) return Invalid(field, "lower, upper, start and step must be finite");
    }
    if (v.lower() > v.upper()) {
      return Invalid(field,
                     absl::StrCat("empty design range: lower ", v.lower(), " > upper ", v.upper()));
    }
    if (v.start() < v.lower() || v.start() > v.upper()) {
      return Invalid(field + ".start", absl::StrCat("start ", v.start(), " is outside [", v.lower(),
                                                    ", ", v.upper(), "]"));
    }
    if (v.lower() < info->lowest || v.upper() > info->highest) {
      return Invalid(field, absl::StrCat(v.name(), " must stay within [", info->lowest, ", ",
                                         info->highest, "]"));
    }
    if (v.step() < 0) return Invalid(field + ".step", "must be >= 0");
    if (v.name() == "width") {
      const double slats = MaxSlatCount(scene.window, *scene.blind, v.lower());
      if (!(slats <= kMaxBlindSlats)) {
        return Invalid(field + ".lower",
                       absl::StrCat("at width ", v.lower(), " m the blind would need up to ", slats,
                                    " slats; at most ", kMaxBlindSlats));
      }
    }
  }
  return absl::OkStatus();
}

absl::Status FillDefaults(v1::Job& job) {
  v1::Budget& budget = *job.mutable_budget();
  if (budget.max_evaluations() == 0) budget.set_max_evaluations(150);
  if (budget.max_evaluations() < 1) return Invalid("budget.max_evaluations", "must be >= 1");
  if (!(budget.max_seconds() >= 0)) return Invalid("budget.max_seconds", "must be >= 0");
  if (budget.failed_cycles_to_stop() == 0) budget.set_failed_cycles_to_stop(10);
  if (budget.failed_cycles_to_stop() < -1) {
    return Invalid("budget.failed_cycles_to_stop", "must be >= -1");
  }
  FENESTRA_ASSIGN_OR_RETURN(sampling, ResolveSampling(job.sampling()));
  *job.mutable_sampling() = sampling;

  v1::MetricSettings& m = *job.mutable_metrics();
  if (m.udi_lower_lux() == 0) m.set_udi_lower_lux(100);
  if (m.udi_upper_lux() == 0) m.set_udi_upper_lux(3000);
  if (m.da_threshold_lux() == 0) m.set_da_threshold_lux(300);
  if (m.sda_time_fraction_percent() == 0) m.set_sda_time_fraction_percent(50);
  if (m.occupied_start_h() == 0 && m.occupied_end_h() == 0) {
    m.set_occupied_start_h(8);
    m.set_occupied_end_h(18);
  }
  if (!(m.udi_lower_lux() >= 0 && m.udi_lower_lux() < m.udi_upper_lux())) {
    return Invalid("metrics", "need 0 <= udi_lower_lux < udi_upper_lux");
  }
  for (int i = 0; i < job.neighborhoods_size(); ++i) {
    const v1::Neighborhood& n = job.neighborhoods(i);
    if (n.variables() < 0 || !(n.radius() > 0 && n.radius() <= 1)) {
      return Invalid(absl::StrCat("neighborhoods[", i, "]"),
                     "needs variables >= 0 and radius in (0, 1]");
    }
  }
  if (job.objective().goal() == v1::GOAL_TARGET && !std::isfinite(job.objective().target())) {
    return Invalid("objective.target", "must be finite");
  }
  return ToSceneMetric(job.objective().metric()).status();
}

BlindDesign DesignAt(const PreparedJob& job, const std::vector<double>& x) {
  BlindDesign design = DefaultDesign(job.scene);
  for (int i = 0; i < job.job.variables_size(); ++i) {
    design.*(FindVariable(job.job.variables(i).name())->field) = x[i];
  }
  return design;
}

v1::Evaluation ToProto(const PreparedJob& job, const VnsRecord& record) {
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
  return e;
}

void SetEstimate(v1::Estimate* out, double value, double standard_error) {
  out->set_value(value);
  out->set_standard_error(standard_error);
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

}  // namespace

absl::StatusOr<v1::Job> ReadJobFile(const std::string& path) {
  v1::Job job;
  FENESTRA_RETURN_IF_ERROR(ReadJsonProtoFile(path, "job", &job));
  return job;
}

absl::StatusOr<v1::Sampling> ResolveSampling(const v1::Sampling& given) {
  v1::Sampling s = given;
  if (s.outdoor_paths() == 0) s.set_outdoor_paths(20'000'000);
  if (s.outdoor_bounces() == 0) s.set_outdoor_bounces(30);
  if (s.indoor_paths_per_sensor() == 0) s.set_indoor_paths_per_sensor(200'000);
  if (s.indoor_bounces() == 0) s.set_indoor_bounces(5);
  if (s.seed() == 0) s.set_seed(1);
  if (s.basis_cells() == 0) s.set_basis_cells(288);
  if (s.backend().empty()) s.set_backend("auto");
  if (s.batches() == 0) s.set_batches(8);
  if (s.basis_cells() != 288 && s.basis_cells() != 1152) {
    return Invalid("sampling.basis_cells", "must be 288 or 1152");
  }
  if (s.window_columns() < 0 || s.window_columns() > 16 || s.window_rows() < 0 ||
      s.window_rows() > 16) {
    return Invalid("sampling.window_columns/window_rows", "must be in [0, 16] (0 = automatic)");
  }
  const int64_t window_cells =
      int64_t{s.basis_cells()} * std::max(1, s.window_columns()) * std::max(1, s.window_rows());
  if (s.outdoor_paths() < 2 * window_cells) {
    return Invalid("sampling.outdoor_paths",
                   absl::StrCat("must be at least 2 per window cell (", 2 * window_cells, ")"));
  }
  if (s.batches() < 2 || s.batches() > 64) return Invalid("sampling.batches", "must be in [2, 64]");
  if (s.indoor_paths_per_sensor() < s.batches()) {
    return Invalid("sampling.indoor_paths_per_sensor", "must be at least the batch count");
  }
  if (s.outdoor_bounces() < -1 || s.indoor_bounces() < -1) {
    return Invalid("sampling", "bounces must be >= 1, or -1 for unlimited");
  }
  if (s.backend() != "auto" && s.backend() != "cpu" && s.backend() != "cuda") {
    return Invalid("sampling.backend",
                   absl::StrCat("must be cpu, cuda or auto, got '", s.backend(), "'"));
  }
  return s;
}

absl::StatusOr<PreparedJob> PrepareJob(const v1::Job& job, const std::string& base_dir) {
  PreparedJob prepared;
  prepared.job = job;
  const fs::path base(base_dir);

  // The scene: inline or from a file next to the job
  if (job.has_scene() && !job.scene_file().empty()) {
    return Invalid("scene", "give either scene or scene_file, not both");
  }
  if (!job.scene_file().empty()) {
    FENESTRA_ASSIGN_OR_RETURN(scene, LoadScene((base / job.scene_file()).string()));
    prepared.scene = std::move(scene);
  } else if (job.has_scene()) {
    FENESTRA_ASSIGN_OR_RETURN(scene, BuildScene(job.scene(), (base / "job.scene").string()));
    prepared.scene = std::move(scene);
  } else {
    return Invalid("scene", "a scene or scene_file is required");
  }

  // The weather: the job's, else the scene's site
  if (!job.weather_file().empty()) {
    prepared.weather_file = (base / job.weather_file()).lexically_normal().string();
  } else {
    prepared.weather_file = prepared.scene.site.weather_file;
  }
  if (prepared.weather_file.empty()) {
    return Invalid("weather_file", "no weather file (neither the job nor the scene's site)");
  }
  if (!fs::is_regular_file(prepared.weather_file)) {
    return Invalid("weather_file", absl::StrCat(prepared.weather_file, ": not found"));
  }
  FENESTRA_RETURN_IF_ERROR(ValidateVariables(job, prepared.scene));
  FENESTRA_RETURN_IF_ERROR(FillDefaults(prepared.job));
  // Enough outdoor paths for every window cell, the automatic parts resolved
  const WindowParts parts = SamplingWindowParts(prepared.job.sampling(), prepared.scene.window);
  const int64_t window_cells =
      int64_t{prepared.job.sampling().basis_cells()} * parts.columns * parts.rows;
  if (prepared.job.sampling().outdoor_paths() < 2 * window_cells) {
    return Invalid("sampling.outdoor_paths",
                   absl::StrCat("must be at least 2 per window cell (", 2 * window_cells, ": ",
                                parts.columns, "x", parts.rows, " window parts x ",
                                prepared.job.sampling().basis_cells(), " direction cells)"));
  }
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

  // Sky matrix, the occupied hours and the lit analysed ones (the rest are dark or not counted)
  if (callbacks.stage) callbacks.stage("sky");
  FENESTRA_ASSIGN_OR_RETURN(weather, ReadEpw(job.weather_file));
  SkyMatrixOptions sky_options;
  sky_options.ground_reflectance = job.scene.site.ground_reflectance;
  FENESTRA_ASSIGN_OR_RETURN(sky, BuildSkyMatrix(weather, sky_options));
  std::vector<double> hours;
  for (const SkyStep& step : sky.steps) hours.push_back(step.hour);
  FENESTRA_ASSIGN_OR_RETURN(occupied, OccupiedSteps(hours, {spec.metrics().occupied_start_h(),
                                                            spec.metrics().occupied_end_h()}));
  const HourBasis hour_basis =
      spec.metrics().all_hours() ? HourBasis::kAllHours : HourBasis::kOccupied;
  std::vector<int> columns;
  for (const int c : LitColumns(sky.radiance)) {
    if (hour_basis == HourBasis::kAllHours || occupied[c]) columns.push_back(c);
  }
  const int analysed_hours = AnalysedHours(occupied, hour_basis);
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
  MetricOptions metric_options;
  metric_options.udi_lower_lux = spec.metrics().udi_lower_lux();
  metric_options.udi_upper_lux = spec.metrics().udi_upper_lux();
  metric_options.da_threshold_lux = spec.metrics().da_threshold_lux();
  metric_options.sda_min_da_percent = spec.metrics().sda_time_fraction_percent();
  metric_options.hours = hour_basis;
  FENESTRA_ASSIGN_OR_RETURN(metric, ToSceneMetric(spec.objective().metric()));
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
  Matrix lit_sky(sky.radiance.rows(), static_cast<Eigen::Index>(columns.size()));
  for (size_t c = 0; c < columns.size(); ++c) {
    lit_sky.col(c) = kWhiteEfficacyLumensPerWatt * sky.radiance.col(columns[c]);
  }

  // Per design: the indoor stage, then the metrics from the tallies of E_b = (I_b O) S, as
  // the backend does it best (on the CPU the paths recorded once, then replayed per design;
  // on the GPU I and E never leave the device), for the designs within the job's ranges
  if (callbacks.stage) callbacks.stage("indoor paths");
  Scene ranged = job.scene;
  if (ranged.blind) {
    for (const v1::DesignVariable& v : spec.variables()) {
      ParameterRange& range = (*ranged.blind).*(FindVariable(v.name())->range);
      range.min = std::min(range.min, v.lower());
      range.max = std::max(range.max, v.upper());
    }
  }
  FENESTRA_ASSIGN_OR_RETURN(
      design_tallies,
      backend->MakeDesignTallies(ranged, indoor_options, outdoor->coefficients, lit_sky));
  const ObjectiveFunction objective =
      [&](const std::vector<double>& x) -> absl::StatusOr<Evaluation> {
    FENESTRA_ASSIGN_OR_RETURN(tallies, design_tallies->Tally(DesignAt(job, x), metric_options));
    FENESTRA_ASSIGN_OR_RETURN(metrics,
                              AnnualMetricsFromTallies(tallies, analysed_hours, metric_options));
    return MetricEvaluation(std::move(metrics), metric);
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
  if (callbacks.progress) {
    vns_callbacks.progress = [&](const VnsProgress& p) {
      JobProgress progress;
      progress.evaluations = p.evaluations;
      progress.max_evaluations = p.max_evaluations;
      progress.current = ToProto(job, *p.current);
      progress.best = ToProto(job, *p.best);
      progress.elapsed_seconds = Since(start);
      progress.remaining_seconds = p.remaining_seconds;
      callbacks.progress(progress);
    };
  }
  if (callbacks.stage) callbacks.stage("search");
  FENESTRA_ASSIGN_OR_RETURN(search, RunVns(variables, objective, vns, vns_callbacks));

  // The result
  for (size_t i = 0; i < variables.size(); ++i) {
    (*result.mutable_best_design())[variables[i].name] = search.best_x[i];
  }
  SetEstimate(result.mutable_best_value(), search.best.value, search.best.standard_error);
  if (const auto* metrics = std::any_cast<AnnualMetricsEstimate>(&search.best.payload)) {
    *result.mutable_best_metrics() = ToProto(*metrics);
  }
  for (const VnsRecord& record : search.history) *result.add_history() = ToProto(job, record);
  result.set_evaluations(search.evaluations);
  result.set_stop_reason(std::string(StopReasonName(search.stop_reason)));
  result.mutable_timings()->set_evaluation_seconds(search.evaluation_seconds);
  result.mutable_timings()->set_total_seconds(Since(start));
  result.set_outdoor_mean_relative_standard_error(
      MeanRelativeError(outdoor->coefficients, outdoor->standard_error, 0.01, false));
  result.set_backend(backend->Name());
  return result;
}

}  // namespace fenestra
