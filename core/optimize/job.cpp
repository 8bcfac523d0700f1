#include "core/optimize/job.h"

#include <algorithm>
#include <chrono>
#include <climits>
#include <cmath>
#include <filesystem>
#include <future>
#include <map>
#include <optional>
#include <span>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_join.h"
#include "core/common/content_hash.h"
#include "core/common/json_proto.h"
#include "core/common/seconds.h"
#include "core/common/status_macros.h"
#include "core/common/thread_pool.h"
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
#include "core/optimize/racing.h"
#include "core/optimize/vns.h"
#include "core/sky/epw.h"
#include "core/sky/sky_matrix.h"
#include "google/protobuf/io/coded_stream.h"
#include "google/protobuf/io/zero_copy_stream_impl_lite.h"

namespace fenestra {
namespace {

namespace fs = std::filesystem;

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
      return InvalidJobField("objective.metric", "unknown metric");
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
  e.set_raced_out(record.evaluation.partial);
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
  std::shared_ptr<const SkyMatrix> sky;
  std::vector<bool> occupied;
  std::vector<int> columns;  // lit analysed steps, ascending
  Matrix lit_sky;            // S over those steps, in lux (146 x columns)
  int analysed_hours = 0;
  MetricOptions options;
  SceneMetric metric = SceneMetric::kUdiMean;
};

absl::StatusOr<AnnualSetting> MakeAnnualSetting(const PreparedJob& job) {
  const v1::MetricSettings& m = job.job.metrics();
  AnnualSetting setting;
  setting.sky = job.sky;
  if (!setting.sky) {
    FENESTRA_ASSIGN_OR_RETURN(sky, JobSkyMatrix(job));
    setting.sky = std::move(sky);
  }
  std::vector<double> hours;
  for (const SkyStep& step : setting.sky->steps) hours.push_back(step.hour);
  FENESTRA_ASSIGN_OR_RETURN(occupied,
                            OccupiedSteps(hours, {m.occupied_start_h(), m.occupied_end_h()}));
  setting.occupied = std::move(occupied);
  const HourBasis hour_basis = m.all_hours() ? HourBasis::kAllHours : HourBasis::kOccupied;
  for (const int c : LitColumns(setting.sky->radiance)) {
    if (hour_basis == HourBasis::kAllHours || setting.occupied[c]) setting.columns.push_back(c);
  }
  setting.analysed_hours = AnalysedHours(setting.occupied, hour_basis);
  setting.lit_sky = SkyColumnsInLux(setting.sky->radiance, setting.columns);
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
  // E_b = D_b S and its tallies by the backend, as the search's designs: a one-stage D_b
  // already holds the sky bins' light, so the product is the sky's alone (on a GPU the
  // check's 32 pilot batches take a product there instead of one on the host), made once
  // for the pilot and the check
  std::unique_ptr<AnnualProduct> product;
  const DaylightMetric metric =
      [&](std::span<const Matrix> dc_batches) -> absl::StatusOr<Evaluation> {
    if (product == nullptr) {
      FENESTRA_ASSIGN_OR_RETURN(made, backend->MakeSkyProduct(setting.lit_sky));
      product = std::move(made);
    }
    FENESTRA_ASSIGN_OR_RETURN(
        versions, product->Tally({dc_batches.begin(), dc_batches.end()}, setting.options));
    FENESTRA_ASSIGN_OR_RETURN(
        metrics, AnnualMetricsFromTallies(versions, setting.analysed_hours, setting.options));
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

// A job's clock: this process's time since RunJob started, after the time of the checkpoint
// it resumed from [s].
struct JobClock {
  std::chrono::steady_clock::time_point start;
  double resumed_seconds = 0;
  double Seconds() const { return resumed_seconds + SecondsSince(start); }
};

// The final check of the search's best design into `result` (which holds the search's
// history), then reported once more with the check. A cancel during the check leaves it out.
absl::Status CheckBestDesign(const PreparedJob& job, const AnnualSetting& setting,
                             const VnsResult& search, DcBackend* backend,
                             const JobCallbacks& callbacks, const JobClock& clock,
                             v1::JobResult& result) {
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
    last.elapsed_seconds = clock.Seconds();
    last.final_check = *std::move(check);
    callbacks.progress(last);
  }
  return absl::OkStatus();
}

// The best design's hourly illuminance, for reports and other tools, by the search's replay
// and annual product (`tallies`, its O_b already on the device), on a thread of its own; beside
// it, on a backend of its own, the final check of the best design by the one-stage method.
absl::Status HourlyAndCheck(const PreparedJob& job, const AnnualSetting& setting,
                            const VnsResult& search, DesignTallies& tallies,
                            const JobCallbacks& callbacks, const JobClock& clock,
                            v1::JobResult& result) {
  if (search.stop_reason == StopReason::kCancelled) return absl::OkStatus();
  double hourly_seconds = 0;
  std::future<absl::StatusOr<v1::HourlyIlluminance>> hourly;
  if (search.evaluations > 0 &&
      static_cast<int64_t>(job.scene.sensors.size() * setting.sky->steps.size()) <=
          kMaxHourlyIlluminanceValues) {
    hourly = std::async(
        std::launch::async,
        [&, design = DesignAt(job, search.best_x)]() -> absl::StatusOr<v1::HourlyIlluminance> {
          const auto hourly_start = std::chrono::steady_clock::now();
          absl::StatusOr<v1::HourlyIlluminance> values = DesignHourlyIlluminance(
              job.scene, *setting.sky,
              [&](const Matrix& sky) { return tallies.DesignIlluminance(design, sky); });
          hourly_seconds = SecondsSince(hourly_start);
          return values;
        });
  }
  if (job.job.sampling().final_check()) {
    FENESTRA_ASSIGN_OR_RETURN(backend, MakeBackend(job.job.sampling().backend()));
    FENESTRA_RETURN_IF_ERROR(
        CheckBestDesign(job, setting, search, backend.get(), callbacks, clock, result));
  }
  if (hourly.valid()) {
    FENESTRA_ASSIGN_OR_RETURN(values, hourly.get());
    *result.mutable_best_hourly() = std::move(values);
    result.mutable_timings()->set_best_hourly_seconds(hourly_seconds);
  }
  return absl::OkStatus();
}

// The search of a job: its variables, in the job's order, and its options.
struct SearchSettings {
  std::vector<DesignVariable> variables;
  VnsOptions options;
};

SearchSettings MakeSearchSettings(const v1::Job& spec) {
  SearchSettings search;
  for (const v1::DesignVariable& v : spec.variables()) {
    search.variables.push_back({v.name(), v.lower(), v.upper(), v.start(), v.fixed(), v.step()});
  }
  VnsOptions& vns = search.options;
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
  return search;
}

absl::Status CheckCheckpointFormat(const v1::SearchCheckpoint& checkpoint) {
  if (checkpoint.format() == kSearchCheckpointFormat) return absl::OkStatus();
  return absl::InvalidArgumentError(absl::StrCat("search checkpoint: format ", checkpoint.format(),
                                                 ", but this build reads format ",
                                                 kSearchCheckpointFormat, " only"));
}

// The search so far that `checkpoint` holds, once it is known to be of this format, of the
// job whose content hash is `job_hash` and a history its search makes (CheckVnsResume).
absl::StatusOr<VnsResult> ResumedSearch(const std::string& job_hash, const SearchSettings& search,
                                        const v1::SearchCheckpoint& checkpoint) {
  FENESTRA_RETURN_IF_ERROR(CheckCheckpointFormat(checkpoint));
  if (checkpoint.job_hash() != job_hash) {
    return absl::InvalidArgumentError(
        "search checkpoint: it belongs to another job (its content hash differs)");
  }
  if (checkpoint.history_size() == 0) {
    return absl::InvalidArgumentError("search checkpoint: no steps");
  }
  const double job_seconds = checkpoint.history(checkpoint.history_size() - 1).elapsed_seconds();
  if (!(job_seconds >= 0) || !std::isfinite(job_seconds)) {
    return absl::InvalidArgumentError(absl::StrCat(
        "search checkpoint: the last step's elapsed_seconds ", job_seconds, " is not a time"));
  }
  // The history on the search's clock
  const double search_start = job_seconds - checkpoint.search_seconds();
  VnsResult so_far;
  so_far.elapsed_seconds = checkpoint.search_seconds();
  for (const v1::Evaluation& e : checkpoint.history()) {
    VnsRecord record;
    record.index = e.index();
    for (const DesignVariable& v : search.variables) {
      const auto value = e.design().find(v.name);
      if (value == e.design().end()) {
        return absl::InvalidArgumentError(absl::StrCat("search checkpoint: step ", e.index(),
                                                       " has no value of variable '", v.name, "'"));
      }
      record.x.push_back(value->second);
    }
    if (e.design_size() != static_cast<int>(search.variables.size())) {
      return absl::InvalidArgumentError(absl::StrCat("search checkpoint: step ", e.index(),
                                                     " has variables the job does not have"));
    }
    record.evaluation.value = e.value().value();
    record.evaluation.standard_error = e.value().standard_error();
    record.evaluation.partial = e.raced_out();
    record.evaluation_seconds = e.seconds();
    record.elapsed_seconds = e.elapsed_seconds() - search_start;
    record.cached = e.cached();
    record.improved = e.improved();
    record.neighborhood = e.neighborhood();
    so_far.history.push_back(std::move(record));
  }
  if (absl::Status replay = CheckVnsResume(search.variables, search.options, so_far);
      !replay.ok()) {
    return absl::InvalidArgumentError(absl::StrCat("search checkpoint: ", replay.message()));
  }
  return so_far;
}

// Where a job's search starts: from nothing, or from a checkpoint.
struct SearchStart {
  v1::SearchCheckpoint checkpoint;  // kept up to date after each step
  std::optional<VnsResult> so_far;  // the search resumed
  double resumed_seconds = 0;       // the job's clock at the checkpoint [s]
};

// The start of the job's search: from `resume` when given (ResumedSearch), else new.
absl::StatusOr<SearchStart> StartOfSearch(const PreparedJob& job, const SearchSettings& settings,
                                          const v1::SearchCheckpoint* resume) {
  SearchStart start;
  if (resume == nullptr) {
    start.checkpoint.set_format(kSearchCheckpointFormat);
    start.checkpoint.set_job_hash(JobContentHash(job));
    return start;
  }
  FENESTRA_ASSIGN_OR_RETURN(so_far, ResumedSearch(JobContentHash(job), settings, *resume));
  start.so_far = std::move(so_far);
  start.checkpoint = *resume;
  start.resumed_seconds = resume->history(resume->history_size() - 1).elapsed_seconds();
  return start;
}

// The indoor stage of the job's designs.
IndoorOptions JobIndoorOptions(const PreparedJob& job) {
  const v1::Sampling& sampling = job.job.sampling();
  IndoorOptions options;
  options.paths_per_sensor = sampling.indoor_paths_per_sensor();
  options.max_bounces = sampling.indoor_bounces();
  options.seed = sampling.seed();
  options.basis_cells = sampling.basis_cells();
  options.parts = SamplingWindowParts(sampling, job.scene.window);
  options.batches = sampling.batches();
  return options;
}

// What racing did, into `result`.
void AddRacing(const Racer& racer, v1::JobResult& result) {
  const RacingStats& stats = racer.stats();
  const RacingSettings& settings = racer.settings();
  v1::Racing& out = *result.mutable_racing();
  for (const int parts : settings.rounds) {
    out.add_round_fractions(static_cast<double>(parts) / kDesignParts);
  }
  out.set_standard_errors(settings.standard_errors);
  out.set_candidates(stats.candidates);
  for (const int n : stats.rejected) out.add_raced_out(n);
  if (stats.parts_in_full > 0) {
    out.set_paths_fraction(static_cast<double>(stats.parts_traced) /
                           static_cast<double>(stats.parts_in_full));
  }
  out.set_rays_traced(stats.rays_traced);
  if (stats.parts_traced > 0) {
    out.set_rays_saved(static_cast<uint64_t>(
        static_cast<double>(stats.rays_traced) / static_cast<double>(stats.parts_traced) *
        static_cast<double>(std::max<int64_t>(0, stats.parts_in_full - stats.parts_traced))));
  }
  out.set_audited(stats.rejected_audited);
  out.set_audited_would_improve(stats.rejected_would_improve);
  out.set_audited_better_beyond_error(stats.rejected_better_beyond_error);
}

// The search into `result`: the best design and its value and metrics, every step (moved
// from `checkpoint`, which holds them in the job's terms), the counts and why it stopped.
void AddSearch(const SearchSettings& settings, const VnsResult& search,
               v1::SearchCheckpoint& checkpoint, v1::JobResult& result) {
  for (size_t i = 0; i < settings.variables.size(); ++i) {
    (*result.mutable_best_design())[settings.variables[i].name] = search.best_x[i];
  }
  SetEstimate(result.mutable_best_value(), search.best.value, search.best.standard_error);
  if (checkpoint.has_best_metrics()) *result.mutable_best_metrics() = checkpoint.best_metrics();
  result.mutable_history()->Swap(checkpoint.mutable_history());
  AddBestOverTime(result);
  result.set_evaluations(search.evaluations);
  result.set_stop_reason(std::string(StopReasonName(search.stop_reason)));
  result.mutable_timings()->set_evaluation_seconds(search.evaluation_seconds);
}

// The lanes a job's designs are evaluated on at once (Sampling.candidates_at_once): the
// job's backend and as many more as asked (on CUDA each on the next GPU in use after the one
// before, MakeLaneBackend), each with the indoor stage's design tallies.
struct Lanes {
  std::vector<std::unique_ptr<DcBackend>> more;  // the backends after the job's
  std::vector<std::unique_ptr<DesignTallies>> tallies;

  std::vector<DesignTallies*> Tallies() const {
    std::vector<DesignTallies*> out;
    for (const auto& t : tallies) out.push_back(t.get());
    return out;
  }
};

// How the search's designs are evaluated: on the lanes, in rounds where the job asks for racing
// (by default where the backend's rounds pay).
Racer::Setting RacerSetting(const v1::Sampling& sampling, const Lanes& lanes,
                            const AnnualSetting& setting, const SearchSettings& search) {
  return {.lanes = lanes.Tallies(),
          .options = setting.options,
          .analysed_hours = setting.analysed_hours,
          .metric = setting.metric,
          .objective = search.options.objective,
          .racing = {.rounds = {sampling.racing_rounds().begin(), sampling.racing_rounds().end()},
                     .standard_errors = sampling.racing_standard_errors()},
          .enabled = sampling.has_racing() ? sampling.racing() : lanes.tallies.front()->RoundsPay(),
          .audit = sampling.racing_audit()};
}

// The lanes' backends after `first`, made on the job's thread: the GPUs a lane may take are
// that thread's (a daemon worker's, ThreadCudaDevices).
absl::StatusOr<Lanes> MakeLanes(const v1::Sampling& sampling, const DcBackend& first) {
  const int count = sampling.candidates_at_once() > 0 ? sampling.candidates_at_once()
                                                      : first.DefaultCandidatesAtOnce();
  Lanes lanes;
  for (int l = 1; l < count; ++l) {
    FENESTRA_ASSIGN_OR_RETURN(backend, MakeLaneBackend(sampling.backend(), first, l));
    lanes.more.push_back(std::move(backend));
  }
  return lanes;
}

// The lanes' design tallies, their indoor records made at once but no annual product yet
// (SetLaneProducts).
absl::Status StartLanes(Lanes& lanes, DcBackend& first, const Scene& scene,
                        const IndoorOptions& options) {
  std::vector<DcBackend*> backends = {&first};
  for (const auto& backend : lanes.more) backends.push_back(backend.get());
  const int count = static_cast<int>(backends.size());
  lanes.tallies.resize(count);
  std::vector<absl::Status> made(count);
  ParallelFor(count, count, [&](uint64_t l) {
    absl::StatusOr<std::unique_ptr<DesignTallies>> tallies =
        backends[l]->StartDesignTallies(scene, options);
    if (tallies.ok()) {
      lanes.tallies[l] = *std::move(tallies);
    } else {
      made[l] = tallies.status();
    }
  });
  for (const absl::Status& status : made) FENESTRA_RETURN_IF_ERROR(status);
  return absl::OkStatus();
}

// Once the outdoor stage and the sky are there: every lane's annual product set with
// `outdoor`'s batches (from the GPU that formed them where a lane is on it) and `sky`.
absl::Status SetLaneProducts(Lanes& lanes, const OutdoorMatrix& outdoor, const Matrix& sky) {
  std::vector<absl::Status> set(lanes.tallies.size());
  ParallelFor(set.size(), set.size(), [&](uint64_t l) {
    set[l] = lanes.tallies[l]->SetProduct(outdoor.batches, sky, outdoor.batches_on_device);
  });
  for (const absl::Status& status : set) FENESTRA_RETURN_IF_ERROR(status);
  return absl::OkStatus();
}

// The job's search from the start or from `so_far`, keeping `checkpoint` (that of `so_far`,
// else new) up to date after each step and handing it out with the progress; `racer`
// evaluates the designs and learns of each new incumbent.
absl::StatusOr<VnsResult> RunJobSearch(const PreparedJob& job, const SearchSettings& search,
                                       Racer& racer, const JobCallbacks& callbacks,
                                       const JobClock& clock, const VnsResult* so_far,
                                       v1::SearchCheckpoint& checkpoint) {
  // When the search started, on the job's clock
  const double search_start = clock.Seconds() - (so_far ? so_far->elapsed_seconds : 0);
  if (so_far != nullptr) {
    for (auto step = so_far->history.rbegin(); step != so_far->history.rend(); ++step) {
      if (!step->improved) continue;
      racer.SetIncumbent(DesignAt(job, step->x));
      break;
    }
  }
  const BatchObjective objective = [&](const std::vector<std::vector<double>>& xs) {
    std::vector<BlindDesign> designs;
    for (const std::vector<double>& x : xs) designs.push_back(DesignAt(job, x));
    return racer.EvaluateBatch(designs);
  };
  VnsCallbacks vns_callbacks;
  vns_callbacks.cancelled = callbacks.cancelled;
  vns_callbacks.checkpoint = [&](const VnsResult& state) {
    const VnsRecord& step = state.history.back();
    v1::Evaluation& e = *checkpoint.add_history() = ToProto(job, step, search_start);
    if (!step.cached) e.set_paths_fraction(racer.PathsFraction(DesignAt(job, step.x)));
    if (step.improved) racer.SetIncumbent(DesignAt(job, step.x));
    if (step.improved) {
      if (const auto* metrics = std::any_cast<AnnualMetricsEstimate>(&step.evaluation.payload)) {
        *checkpoint.mutable_best_metrics() = ToProto(*metrics);
      } else {
        checkpoint.clear_best_metrics();
      }
    }
    checkpoint.set_search_seconds(state.elapsed_seconds);
    if (callbacks.checkpoint) callbacks.checkpoint(checkpoint);
  };
  if (callbacks.progress) {
    vns_callbacks.progress = [&](const VnsProgress& p) {
      JobProgress progress;
      progress.evaluations = p.evaluations;
      progress.max_evaluations = p.max_evaluations;
      progress.current = checkpoint.history(p.current->index);
      progress.best = checkpoint.history(p.best->index);
      progress.elapsed_seconds = clock.Seconds();
      progress.remaining_seconds = p.remaining_seconds;
      callbacks.progress(progress);
    };
  }
  return RunVns(search.variables, objective, search.options, vns_callbacks, so_far);
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
    return InvalidJobField("weather_file",
                           "no weather file (neither the job nor the scene's site)");
  }
  FENESTRA_ASSIGN_OR_RETURN(weather, ReadEpw(prepared.weather_file));
  prepared.weather = std::move(weather);
  return prepared;
}

std::string OutdoorMatrixKey(const Scene& scene, const v1::Sampling& sampling) {
  ContentHash hash;
  hash.String("fenestra outdoor matrix v2");
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
  hash.Value(sampling.batches());
  const WindowParts parts = SamplingWindowParts(sampling, scene.window);
  hash.Value(parts.columns), hash.Value(parts.rows);
  return hash.Hex();
}

double OutdoorMeanRelativeError(const OutdoorMatrix& matrix) {
  const Eigen::Index cells = std::max<Eigen::Index>(0, matrix.coefficients.rows() - kDaylightBins);
  if (cells == 0 || matrix.standard_error.rows() != matrix.coefficients.rows()) return 0;
  return MeanRelativeError(matrix.coefficients.topRows(cells), matrix.standard_error.topRows(cells),
                           0.01, false);
}

WindowParts SamplingWindowParts(const v1::Sampling& sampling, const Window& window) {
  const WindowParts automatic = AutomaticWindowParts(window);
  return {sampling.window_columns() > 0 ? sampling.window_columns() : automatic.columns,
          sampling.window_rows() > 0 ? sampling.window_rows() : automatic.rows};
}

absl::StatusOr<OutdoorMatrix> ComputeOutdoorMatrix(const Scene& scene, const v1::Sampling& sampling,
                                                   const std::function<bool()>& cancelled,
                                                   bool keep_on_device) {
  if (cancelled && cancelled()) return absl::CancelledError("cancelled before the outdoor stage");
  OutdoorOptions options;
  options.paths = sampling.outdoor_paths();
  options.max_bounces = sampling.outdoor_bounces();
  options.seed = sampling.seed();
  options.basis_cells = sampling.basis_cells();
  options.parts = SamplingWindowParts(sampling, scene.window);
  options.batches = sampling.batches();
  FENESTRA_ASSIGN_OR_RETURN(backend, MakeBackend(sampling.backend()));
  FENESTRA_ASSIGN_OR_RETURN(result, ComputeOutdoorStage(scene, options, backend.get()));
  OutdoorMatrix matrix;
  matrix.coefficients = std::move(result.coefficients);
  matrix.standard_error = std::move(result.standard_error);
  matrix.batches = std::move(result.batches);
  if (keep_on_device) matrix.batches_on_device = std::move(result.batches_on_device);
  matrix.basis_cells = result.basis_cells;
  matrix.parts = result.parts;
  matrix.paths = result.paths_per_cell * result.sky_view.size();
  matrix.bounces = sampling.outdoor_bounces();
  matrix.seed = sampling.seed();
  matrix.wall_seconds = result.wall_seconds;
  matrix.backend = result.backend;
  matrix.key = OutdoorMatrixKey(scene, sampling);
  return matrix;
}

SkyMatrixOptions JobSkyOptions(const PreparedJob& job) {
  SkyMatrixOptions options;
  options.ground_reflectance = job.scene.site.ground_reflectance;
  return options;
}

absl::StatusOr<std::shared_ptr<const SkyMatrix>> JobSkyMatrix(const PreparedJob& job) {
  FENESTRA_ASSIGN_OR_RETURN(sky, BuildSkyMatrix(job.weather, JobSkyOptions(job)));
  return std::make_shared<const SkyMatrix>(std::move(sky));
}

std::string JobContentHash(const PreparedJob& job) {
  // The job with its scene inline (a scene_file, or the scene left out, says nothing of the
  // scene's content), serialized deterministically
  v1::Job content = job.job;
  content.clear_scene_file();
  *content.mutable_scene() = SelfContainedSceneProto(job.scene);
  // How many designs are evaluated at once changes the time, not the steps
  content.mutable_sampling()->clear_candidates_at_once();
  std::string bytes;
  {
    google::protobuf::io::StringOutputStream stream(&bytes);
    google::protobuf::io::CodedOutputStream coded(&stream);
    coded.SetSerializationDeterministic(true);
    content.SerializeToCodedStream(&coded);
  }
  ContentHash hash;
  hash.String("fenestra job v1");
  hash.String(bytes);

  // The weather: the site and every record
  const EpwLocation& site = job.weather.location;
  hash.Value(site.latitude_deg), hash.Value(site.longitude_deg);
  hash.Value(site.time_zone_hours), hash.Value(site.elevation_m);
  hash.Value(job.weather.records_per_hour);
  for (const EpwRecord& r : job.weather.records) {
    for (const int v : {r.year, r.month, r.day, r.hour, r.minute}) hash.Value(v);
    hash.Value(r.direct_normal_wm2), hash.Value(r.diffuse_horizontal_wm2);
    for (const std::optional<double>& v :
         {r.dry_bulb_c, r.dew_point_c, r.global_horizontal_wm2, r.global_horizontal_lux,
          r.direct_normal_lux, r.diffuse_horizontal_lux}) {
      hash.Value(v.has_value());
      hash.Value(v.value_or(0.0));
    }
  }
  return hash.Hex();
}

absl::StatusOr<v1::SearchCheckpoint> ParseSearchCheckpoint(std::string_view bytes) {
  v1::SearchCheckpoint checkpoint;
  if (bytes.size() > static_cast<size_t>(INT_MAX) ||
      !checkpoint.ParseFromArray(bytes.data(), static_cast<int>(bytes.size()))) {
    return absl::DataLossError(
        absl::StrCat("search checkpoint: ", bytes.size(),
                     " bytes that are not a serialized fenestra.v1.SearchCheckpoint"));
  }
  FENESTRA_RETURN_IF_ERROR(CheckCheckpointFormat(checkpoint));
  return checkpoint;
}

namespace {

// The job's annual setting (sky matrix, occupied and lit hours, metric settings), made on the
// host while the outdoor stage traces into `computed` where `cached` is null (else `cached`
// is checked against the job); the setting's errors come after the outdoor stage's. Their
// times go to `timings`.
absl::StatusOr<AnnualSetting> SettingAndOutdoor(const PreparedJob& job,
                                                const JobCallbacks& callbacks,
                                                const OutdoorMatrix* cached,
                                                OutdoorMatrix& computed, v1::Timings& timings) {
  if (callbacks.stage) callbacks.stage("sky");
  double sky_seconds = 0;
  std::future<absl::StatusOr<AnnualSetting>> setting = std::async(std::launch::async, [&] {
    const auto start = std::chrono::steady_clock::now();
    absl::StatusOr<AnnualSetting> made = MakeAnnualSetting(job);
    sky_seconds = SecondsSince(start);
    return made;
  });
  absl::Status outdoor_status;
  if (cached != nullptr) {
    if (cached->key != OutdoorMatrixKey(job.scene, job.job.sampling())) {
      outdoor_status =
          absl::InvalidArgumentError("the cached outdoor matrix belongs to another site");
    }
  } else {
    if (callbacks.stage) callbacks.stage("outdoor");
    absl::StatusOr<OutdoorMatrix> matrix = ComputeOutdoorMatrix(
        job.scene, job.job.sampling(), callbacks.cancelled, /*keep_on_device=*/true);
    if (matrix.ok()) {
      computed = *std::move(matrix);
      timings.set_outdoor_seconds(computed.wall_seconds);
    } else {
      outdoor_status = matrix.status();
    }
  }
  absl::StatusOr<AnnualSetting> made = setting.get();
  timings.set_sky_seconds(sky_seconds);
  if (!made.ok()) return made.status();
  FENESTRA_RETURN_IF_ERROR(outdoor_status);
  return made;
}

}  // namespace

absl::StatusOr<v1::JobResult> RunJob(const PreparedJob& job, const OutdoorMatrix* outdoor,
                                     const JobCallbacks& callbacks,
                                     const v1::SearchCheckpoint* resume) {
  const auto start = std::chrono::steady_clock::now();
  const v1::Job& spec = job.job;
  v1::JobResult result;

  // The search, and where it starts: a checkpoint is checked before any work
  SearchSettings search_settings = MakeSearchSettings(spec);
  FENESTRA_ASSIGN_OR_RETURN(from, StartOfSearch(job, search_settings, resume));
  v1::SearchCheckpoint& checkpoint = from.checkpoint;
  const JobClock clock{start, from.resumed_seconds};

  // Per design: the indoor stage, then the metrics from the tallies of E_b = (I_b O_b) S, as
  // the backend does it best (on the CPU the paths recorded once, then replayed per design;
  // on the GPU I and E never leave the device), for the designs within the job's ranges.
  // A design's paths depend on the seed alone, never on the designs before it, so a resumed
  // search evaluates as the uninterrupted one would. The records need neither the sky nor
  // the outdoor stage, so they are made beside them.
  FENESTRA_ASSIGN_OR_RETURN(backend, MakeBackend(spec.sampling().backend()));
  const IndoorOptions indoor_options = JobIndoorOptions(job);
  const Scene ranged = WithJobRanges(job.scene, spec);
  FENESTRA_ASSIGN_OR_RETURN(lanes, MakeLanes(spec.sampling(), *backend));
  std::future<absl::Status> started = std::async(
      std::launch::async, [&] { return StartLanes(lanes, *backend, ranged, indoor_options); });

  // Sky matrix, the occupied hours and the lit analysed ones, the metric settings; the outdoor
  // matrix: the cached one, or traced now
  OutdoorMatrix computed;
  absl::StatusOr<AnnualSetting> made_setting =
      SettingAndOutdoor(job, callbacks, outdoor, computed, *result.mutable_timings());
  if (callbacks.stage) callbacks.stage("indoor paths");
  const absl::Status recorded = started.get();
  FENESTRA_RETURN_IF_ERROR(made_setting.status());
  const AnnualSetting& setting = *made_setting;
  const OutdoorMatrix& matrix = outdoor != nullptr ? *outdoor : computed;
  if (!(matrix.parts == indoor_options.parts)) {
    return absl::InvalidArgumentError("the outdoor matrix has other window parts than the job");
  }
  if (static_cast<int>(matrix.batches.size()) != indoor_options.batches) {
    return absl::InvalidArgumentError("the outdoor matrix has other batches than the job");
  }
  FENESTRA_RETURN_IF_ERROR(recorded);
  FENESTRA_RETURN_IF_ERROR(SetLaneProducts(lanes, matrix, setting.lit_sky));
  computed.batches_on_device = {};  // the lanes hold their own copies
  // The outdoor matrix's mean relative error, for the result: a pass over O and its errors
  // (5-15 ms at the job's end) made beside the search
  std::future<double> outdoor_error =
      std::async(std::launch::async, [&matrix] { return OutdoorMeanRelativeError(matrix); });
  Racer racer(RacerSetting(spec.sampling(), lanes, setting, search_settings));

  // The search
  if (callbacks.stage) callbacks.stage("search");
  // Designs evaluated at once: each lane's, as many as it traces together (without racing)
  const int per_lane = racer.Races() ? 1 : lanes.tallies.front()->DesignsAtOnce();
  search_settings.options.lookahead =
      std::min(kMaxLookahead, static_cast<int>(lanes.tallies.size()) * per_lane);
  FENESTRA_ASSIGN_OR_RETURN(search,
                            RunJobSearch(job, search_settings, racer, callbacks, clock,
                                         from.so_far ? &*from.so_far : nullptr, checkpoint));
  if (racer.Races()) AddRacing(racer, result);
  result.set_candidates_at_once(search_settings.options.lookahead);
  result.set_evaluations_discarded(search.discarded);

  DescribeRun(spec, ranged, job.weather.location, result);

  // The result
  AddSearch(search_settings, search, checkpoint, result);
  result.set_outdoor_mean_relative_standard_error(outdoor_error.get());
  result.set_backend(backend->Name());
  FENESTRA_RETURN_IF_ERROR(
      HourlyAndCheck(job, setting, search, *lanes.tallies.front(), callbacks, clock, result));
  lanes.tallies.clear();  // the search's paths are no longer needed
  result.mutable_timings()->set_total_seconds(clock.Seconds());
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
