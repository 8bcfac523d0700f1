// The run of a job (job.h): the annual setting (sky matrix, occupied and lit hours) made
// beside the outdoor stage, the lanes that evaluate the designs (indoor stage, annual product,
// racing), the search with its checkpoints and progress, then the best design's hourly
// illuminance and its final check by the one-stage method. A job's fields are read and its
// result written by job_proto.cpp, its hashes made by job_hash.cpp, a checkpoint it resumes
// read by job_checkpoint.cpp; the door is job_validation.cpp.
#include "core/optimize/job.h"

#include <algorithm>
#include <chrono>
#include <filesystem>
#include <future>
#include <span>

#include "absl/strings/str_cat.h"
#include "core/common/seconds.h"
#include "core/common/status_macros.h"
#include "core/common/thread_pool.h"
#include "core/dc/direct_sun.h"
#include "core/dc/two_stage.h"
#include "core/metrics/annual_metrics.h"
#include "core/metrics/illuminance.h"
#include "core/metrics/metric_errors.h"
#include "core/metrics/occupancy.h"
#include "core/optimize/comfort.h"
#include "core/optimize/final_check.h"
#include "core/optimize/hourly_illuminance.h"
#include "core/optimize/job_checkpoint.h"
#include "core/optimize/job_pareto.h"
#include "core/optimize/job_proto.h"
#include "core/optimize/metric_objective.h"
#include "core/optimize/operated_blind.h"
#include "core/optimize/pareto_search.h"
#include "core/optimize/racing.h"
#include "core/optimize/view_glare.h"
#include "core/optimize/vns.h"
#include "core/sky/epw.h"
#include "core/sky/sky_matrix.h"

namespace fenestra {
namespace {

namespace fs = std::filesystem;

// What the annual metrics of a job's designs need: the sky matrix, the occupied steps and
// the lit analysed ones (the rest are dark or not counted), the metric settings and the
// objective's metric.
struct AnnualSetting {
  std::shared_ptr<const SkyMatrix> sky;
  std::vector<bool> occupied;
  std::vector<int> columns;  // lit analysed steps, ascending
  // S over those steps, in lux, split (kSplitSkyRows x columns; core/README.md, "Direct sun"):
  // the coefficients' direct component leaves the sun to the direct sun
  Matrix lit_sky;
  std::vector<SunColumn> suns;  // the sun of each of those columns that has one
  // The direct sun of those columns through the scene within the job's ranges
  std::shared_ptr<const DirectSun> sun;
  int analysed_hours = 0;
  MetricOptions options;
  SceneMetric metric = SceneMetric::kUdiMean;  // a Pareto search's: its first objective's
  // The skies of the comfort metrics the search weighs (comfort.h); null: none
  std::shared_ptr<const ComfortSky> comfort;
};

// The comfort part of `setting` where the job's search weighs a comfort metric: the solar sky
// matrix of the same weather beside the visible one.
absl::Status AddComfortSky(const PreparedJob& job, AnnualSetting& setting) {
  if (!NeedsOf(SearchMetrics(job.job)).Any()) return absl::OkStatus();
  SkyMatrixOptions options = JobSkyOptions(job);
  options.quantity = SkyQuantity::kSolar;
  FENESTRA_ASSIGN_OR_RETURN(solar, BuildSkyMatrix(job.weather, options));
  const v1::MetricSettings& m = job.job.metrics();
  FENESTRA_ASSIGN_OR_RETURN(
      sky, MakeComfortSky(*setting.sky, solar, setting.columns, setting.occupied,
                          m.glare_threshold(), {m.cooling_start_month(), m.cooling_end_month()}));
  setting.comfort = std::make_shared<const ComfortSky>(std::move(sky));
  return absl::OkStatus();
}

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
  FENESTRA_ASSIGN_OR_RETURN(split, SplitSkyColumnsInLux(*setting.sky, setting.columns));
  setting.lit_sky = std::move(split);
  setting.suns = SunColumnsOf(*setting.sky, setting.columns);
  FENESTRA_ASSIGN_OR_RETURN(sun, DirectSun::Trace(WithJobRanges(job.scene, job.job), setting.suns,
                                                  static_cast<int>(setting.columns.size())));
  setting.sun = std::move(sun);
  setting.options.udi_lower_lux = m.udi_lower_lux();
  setting.options.udi_upper_lux = m.udi_upper_lux();
  setting.options.da_threshold_lux = m.da_threshold_lux();
  setting.options.sda_min_da_percent = m.sda_time_fraction_percent();
  setting.options.ase_threshold_lux = m.ase_threshold_lux();
  setting.options.ase_min_hours = m.ase_min_hours();
  setting.options.hours = hour_basis;
  FENESTRA_ASSIGN_OR_RETURN(
      metric, ToSceneMetric(job.job.has_pareto() ? job.job.pareto().objectives(0).metric()
                                                 : job.job.objective().metric()));
  setting.metric = metric;
  FENESTRA_RETURN_IF_ERROR(AddComfortSky(job, setting));
  return setting;
}

// The final check (final_check.h) of design `x` against `two_stage`, the one-stage metrics
// taken as the search takes the two-stage ones. Cancelled as RunFinalCheck.
// With an operated blind (`operation`), over its closed hours, the bare window's open ones
// added as their mean (WithOpenMean): the same light in both estimates, so the difference is
// the closed hours', and its error, which counts the two-stage estimate's open hours too, is
// on the safe side.
absl::StatusOr<v1::FinalCheck> CheckDesign(const PreparedJob& job, const AnnualSetting& setting,
                                           const BlindOperation* operation,
                                           const std::vector<double>& x,
                                           const v1::Estimate& two_stage, DcBackend* backend,
                                           const std::function<bool()>& cancelled) {
  // E_b = D_b S and its tallies by the backend, as the search's designs: a one-stage D_b
  // already holds the sky bins' light, so the product is the sky's alone (on a GPU the
  // check's 32 pilot batches take a product there instead of one on the host), made once
  // for the pilot and the check
  std::unique_ptr<AnnualProduct> product;
  const DirectSun& sun = operation != nullptr ? *operation->closed_sun : *setting.sun;
  const Matrix& sky = operation != nullptr ? operation->closed_sky : setting.lit_sky;
  const std::vector<SunEntry> direct = sun.Entries(DesignAt(job, x));
  const std::vector<int64_t> sunlit =
      SunlitHours(sun.Illuminance(DesignAt(job, x)), setting.options);
  const DaylightMetric metric =
      [&](std::span<const Matrix> dc_batches) -> absl::StatusOr<Evaluation> {
    if (product == nullptr) {
      FENESTRA_ASSIGN_OR_RETURN(made, backend->MakeSkyProduct(sky));
      product = std::move(made);
    }
    absl::StatusOr<std::vector<HourTally>> tallied =
        product->Tally({dc_batches.begin(), dc_batches.end()}, setting.options, direct);
    if (tallied.ok()) {
      for (HourTally& v : *tallied) v.sunlit = sunlit;
    }
    FENESTRA_ASSIGN_OR_RETURN(versions, operation != nullptr
                                            ? WithOpenMean(std::move(tallied), *operation)
                                            : std::move(tallied));
    FENESTRA_ASSIGN_OR_RETURN(
        metrics, AnnualMetricsFromTallies(versions, setting.analysed_hours, setting.options));
    return MetricEvaluation(std::move(metrics), setting.metric);
  };
  FinalCheckOptions options;
  options.batches = job.job.sampling().batches();
  options.seed = job.job.sampling().seed();
  options.sequence = SequenceOf(job.job.sampling());
  options.cancelled = cancelled;
  options.with_direct_part = true;  // [D_b | D_0,b] for the split sky
  absl::StatusOr<FinalCheckOutcome> outcome =
      RunFinalCheck(job.scene, DesignAt(job, x), two_stage, metric, options, backend);
  if (absl::IsCancelled(outcome.status())) return outcome.status();
  if (!outcome.ok()) {
    return absl::Status(outcome.status().code(),
                        absl::StrCat("final check: ", outcome.status().message()));
  }
  if (const auto* metrics = std::any_cast<AnnualMetricsEstimate>(&outcome->one_stage.payload)) {
    *outcome->check.mutable_one_stage_metrics() = MetricsProto(*metrics);
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
// An operated blind never in place leaves every design the bare window: nothing to check.
absl::Status CheckBestDesign(const PreparedJob& job, const AnnualSetting& setting,
                             const BlindOperation* operation, const VnsResult& search,
                             DcBackend* backend, const JobCallbacks& callbacks,
                             const JobClock& clock, v1::JobResult& result) {
  if (operation != nullptr && operation->closed.empty()) return absl::OkStatus();
  if (callbacks.stage) callbacks.stage("check");
  absl::StatusOr<v1::FinalCheck> check = CheckDesign(
      job, setting, operation, search.best_x, result.best_value(), backend, callbacks.cancelled);
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

// Mixed into the job's seed so that the views trace streams of their own (as the final
// check's, final_check.cpp).
constexpr uint64_t kGlareSeedKey = 0x94D049BB133111EB;

// The glare at the scene's view points at the best design (job.proto, JobResult.best_glare),
// on a backend of its own; nothing for a scene without views, a cancelled search or one
// without an evaluation.
absl::Status GlareOfBestDesign(const PreparedJob& job, const AnnualSetting& setting,
                               const VnsResult& search, const JobCallbacks& callbacks,
                               v1::JobResult& result) {
  if (job.scene.views.empty() || search.evaluations == 0) return absl::OkStatus();
  // The hourly figures of every view are held as the best design's hourly illuminance is
  if (static_cast<int64_t>(job.scene.views.size() * setting.sky->steps.size()) >
      kMaxHourlyIlluminanceValues) {
    return absl::OkStatus();
  }
  if (callbacks.cancelled && callbacks.cancelled()) return absl::OkStatus();
  FENESTRA_ASSIGN_OR_RETURN(backend, MakeBackend(job.job.sampling().backend()));
  ViewGlareOptions options;
  options.tracing.paths_per_sensor = job.job.sampling().indoor_paths_per_sensor();
  options.tracing.batches = job.job.sampling().batches();
  options.tracing.seed = job.job.sampling().seed() ^ kGlareSeedKey;
  FENESTRA_ASSIGN_OR_RETURN(
      glare, ComputeViewGlare(WithJobRanges(job.scene, job.job), DesignAt(job, search.best_x),
                              *setting.sky, setting.occupied, options, backend.get()));
  std::vector<v1::ViewGlare> views = ViewGlareProtos(job.scene, glare);
  for (size_t v = 0; v < views.size(); ++v) {
    // Every step, for the report's map of the year
    const Eigen::Index row = static_cast<Eigen::Index>(v);
    for (Eigen::Index s = 0; s < glare.dgp.cols(); ++s) {
      views[v].add_dgp(static_cast<float>(glare.dgp(row, s)));
    }
    *result.add_best_glare() = std::move(views[v]);
  }
  result.mutable_timings()->set_glare_seconds(glare.seconds);
  return absl::OkStatus();
}

// The best design's hourly illuminance, for reports and other tools, by the search's replay
// and annual product (`tallies`, its O_b already on the device), on a thread of its own; beside
// it, on a backend of its own, the final check of the best design by the one-stage method.
// With an operated blind, each step is the design's where the rule puts the blind in place and
// the bare window's elsewhere.
absl::Status HourlyAndCheck(const PreparedJob& job, const AnnualSetting& setting,
                            const BlindOperation* operation, const VnsResult& search,
                            DesignTallies& tallies, const JobCallbacks& callbacks,
                            const JobClock& clock, v1::JobResult& result) {
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
          // The direct sun of every step (the search's covers only the analysed ones)
          std::vector<int> steps(setting.sky->steps.size());
          for (size_t t = 0; t < steps.size(); ++t) steps[t] = static_cast<int>(t);
          FENESTRA_ASSIGN_OR_RETURN(sun, DirectSun::Trace(WithJobRanges(job.scene, job.job),
                                                          SunColumnsOf(*setting.sky, steps),
                                                          static_cast<int>(steps.size())));
          FENESTRA_ASSIGN_OR_RETURN(
              values, DesignHourlyIlluminance(
                          job.scene, *setting.sky,
                          [&](const Matrix& sky) { return tallies.DesignIlluminance(design, sky); },
                          sun->Entries(design)));
          if (operation != nullptr) {
            FENESTRA_ASSIGN_OR_RETURN(bare, DesignHourlyIlluminance(
                                                job.scene, *setting.sky,
                                                [&](const Matrix& sky) {
                                                  return tallies.Product()->ApplyToSky(
                                                      operation->bare_indoor, sky);
                                                },
                                                sun->Entries(design, /*blind=*/false)));
            MixOperatedHours(BlindInPlace(sun->Illuminance(design, false), setting.options), bare,
                             values);
          }
          hourly_seconds = SecondsSince(hourly_start);
          return values;
        });
  }
  // The one-stage check takes the daylight metrics alone
  if (job.job.sampling().final_check() && !IsComfortMetric(setting.metric)) {
    FENESTRA_ASSIGN_OR_RETURN(backend, MakeBackend(job.job.sampling().backend()));
    FENESTRA_RETURN_IF_ERROR(
        CheckBestDesign(job, setting, operation, search, backend.get(), callbacks, clock, result));
  }
  if (hourly.valid()) {
    FENESTRA_ASSIGN_OR_RETURN(values, hourly.get());
    *result.mutable_best_hourly() = std::move(values);
    result.mutable_timings()->set_best_hourly_seconds(hourly_seconds);
  }
  return GlareOfBestDesign(job, setting, search, callbacks, result);
}

// The lanes a job's designs are evaluated on at once (Sampling.candidates_at_once): the
// job's backend and as many more as asked (on CUDA each on the next GPU in use after the one
// before, MakeLaneBackend), each with the indoor stage's design tallies.
struct Lanes {
  std::vector<std::unique_ptr<DcBackend>> more;  // the backends after the job's
  std::vector<std::unique_ptr<DesignTallies>> tallies;
  // Per lane, the comfort metrics where the search weighs one; else empty
  std::vector<std::unique_ptr<DesignComfort>> comfort;
  bool on_gpu = false;

  std::vector<DesignTallies*> Tallies() const {
    std::vector<DesignTallies*> out;
    for (const auto& t : tallies) out.push_back(t.get());
    return out;
  }
  std::vector<DesignComfort*> Comfort() const {
    std::vector<DesignComfort*> out;
    for (const auto& c : comfort) out.push_back(c.get());
    return out;
  }
};

// How the search's designs are evaluated: on the lanes, in rounds where the job asks for racing
// (by default where the backend races, DesignTallies::RacesByDefault), never for a Pareto
// search or comfort metrics (its rounds race against one incumbent by the daylight tallies).
Racer::Setting RacerSetting(const v1::Job& job, const Lanes& lanes, const AnnualSetting& setting,
                            const SearchSettings& search) {
  const v1::Sampling& sampling = job.sampling();
  const bool may_race = !job.has_pareto() && lanes.comfort.empty();
  return {.lanes = lanes.Tallies(),
          .options = setting.options,
          .analysed_hours = setting.analysed_hours,
          .metric = setting.metric,
          .objective = search.options.objective,
          .constraints = search.options.constraints,
          .constraint_metrics = search.constraint_metrics,
          .racing = {.rounds = {sampling.racing_rounds().begin(), sampling.racing_rounds().end()},
                     .standard_errors = sampling.racing_standard_errors()},
          .enabled = may_race && (sampling.has_racing() ? sampling.racing()
                                                        : lanes.tallies.front()->RacesByDefault()),
          .audit = sampling.racing_audit(),
          .comfort = lanes.Comfort(),
          .comfort_beside = lanes.on_gpu};
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
                        const IndoorOptions& options, ComfortNeeds needs) {
  std::vector<DcBackend*> backends = {&first};
  for (const auto& backend : lanes.more) backends.push_back(backend.get());
  const int count = static_cast<int>(backends.size());
  lanes.tallies.resize(count);
  if (needs.Any()) lanes.comfort.resize(count);
  lanes.on_gpu = first.Gpu() >= 0;
  std::vector<absl::Status> made(count);
  ParallelFor(count, count, [&](uint64_t l) {
    absl::StatusOr<std::unique_ptr<DesignTallies>> tallies =
        backends[l]->StartDesignTallies(scene, options);
    if (tallies.ok()) {
      lanes.tallies[l] = *std::move(tallies);
    } else {
      made[l] = tallies.status();
      return;
    }
    if (!needs.Any()) return;
    absl::StatusOr<std::unique_ptr<DesignComfort>> comfort =
        DesignComfort::Start(scene, options, *backends[l], needs);
    if (comfort.ok()) {
      lanes.comfort[l] = *std::move(comfort);
    } else {
      made[l] = comfort.status();
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

// Once the outdoor stage and the sky are there: every lane's annual product and direct sun;
// for an operated blind (core/optimize/operated_blind.h) over its closed hours, the lanes'
// tallies then adding the bare window's open ones. Null: a static blind.
absl::StatusOr<std::shared_ptr<const BlindOperation>> SetLaneEvaluation(
    const PreparedJob& job, const AnnualSetting& setting, const OutdoorMatrix& matrix,
    const Scene& ranged, const IndoorOptions& indoor, DcBackend& backend, Lanes& lanes) {
  if (!job.scene.blind() || !job.scene.blind()->automated_sun) {
    FENESTRA_RETURN_IF_ERROR(SetLaneProducts(lanes, matrix, setting.lit_sky));
    for (const auto& tallies : lanes.tallies) tallies->SetDirectSun(setting.sun);
    for (const auto& comfort : lanes.comfort) {
      FENESTRA_RETURN_IF_ERROR(comfort->SetSky(matrix.batches, setting.comfort));
    }
    return std::shared_ptr<const BlindOperation>();
  }
  FENESTRA_ASSIGN_OR_RETURN(made, OperateBlind(ranged, setting.lit_sky, setting.suns, *setting.sun,
                                               matrix.batches, indoor, setting.options, backend));
  auto operation = std::make_shared<const BlindOperation>(std::move(made));
  // A blind never in place leaves the tallies nothing to trace; its product still serves the
  // hourly illuminance
  const bool never = operation->closed.empty();
  FENESTRA_RETURN_IF_ERROR(
      SetLaneProducts(lanes, matrix, never ? setting.lit_sky : operation->closed_sky));
  for (auto& tallies : lanes.tallies) {
    tallies->SetDirectSun(never ? setting.sun : operation->closed_sun);
    tallies = std::make_unique<OperatedDesignTallies>(std::move(tallies), operation);
  }
  return operation;
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
      racer.SetIncumbent(DesignAt(job, step->x),
                         Feasible(search.options.constraints, step->evaluation));
      break;
    }
  }
  const BatchObjective objective = RacerObjective(job, racer);
  VnsCallbacks vns_callbacks;
  vns_callbacks.cancelled = callbacks.cancelled;
  vns_callbacks.checkpoint = [&](const VnsResult& state) {
    const VnsRecord& step = state.history.back();
    v1::Evaluation& e = *checkpoint.add_history() = EvaluationProto(job, step, search_start);
    if (!step.cached) e.set_paths_fraction(racer.PathsFraction(DesignAt(job, step.x)));
    if (step.improved) racer.SetIncumbent(DesignAt(job, step.x), step.feasible);
    if (step.improved) {
      if (const auto* metrics = std::any_cast<AnnualMetricsEstimate>(&step.evaluation.payload)) {
        *checkpoint.mutable_best_metrics() = MetricsProto(*metrics);
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

double OutdoorMeanRelativeError(const OutdoorMatrix& matrix) {
  const Eigen::Index cells =
      std::max<Eigen::Index>(0, matrix.coefficients.rows() - kIndoorDirectColumns);
  if (cells == 0 || matrix.standard_error.rows() != matrix.coefficients.rows()) return 0;
  return MeanRelativeError(matrix.coefficients.topRows(cells), matrix.standard_error.topRows(cells),
                           0.01, false);
}

WindowParts SamplingWindowParts(const v1::Sampling& sampling, const Window& window) {
  const WindowParts automatic = AutomaticWindowParts(window);
  return {sampling.window_columns() > 0 ? sampling.window_columns() : automatic.columns,
          sampling.window_rows() > 0 ? sampling.window_rows() : automatic.rows};
}

WindowParts SamplingWindowParts(const v1::Sampling& sampling, const Scene& scene) {
  if (scene.windows.size() == 1) return SamplingWindowParts(sampling, scene.window());
  return {sampling.window_columns(), sampling.window_rows()};
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
  options.parts = SamplingWindowParts(sampling, scene);
  options.batches = sampling.batches();
  options.sequence = SequenceOf(sampling);
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

// Whether `matrix` has the window parts and batches of the job's indoor stage.
absl::Status CheckOutdoorMatchesIndoor(const OutdoorMatrix& matrix, const IndoorOptions& indoor) {
  if (!(matrix.parts == indoor.parts)) {
    return absl::InvalidArgumentError("the outdoor matrix has other window parts than the job");
  }
  if (static_cast<int>(matrix.batches.size()) != indoor.batches) {
    return absl::InvalidArgumentError("the outdoor matrix has other batches than the job");
  }
  return absl::OkStatus();
}

// The designs the search evaluates at once (VnsOptions::lookahead): each lane's, as many as it
// traces together (one where it races).
int SearchLookahead(const Racer& racer, const Lanes& lanes) {
  const int per_lane = racer.Races() ? 1 : lanes.tallies.front()->DesignsAtOnce();
  return std::min(kMaxLookahead, static_cast<int>(lanes.tallies.size()) * per_lane);
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
  std::future<absl::Status> started = std::async(std::launch::async, [&] {
    return StartLanes(lanes, *backend, ranged, indoor_options, NeedsOf(SearchMetrics(job.job)));
  });

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
  FENESTRA_RETURN_IF_ERROR(CheckOutdoorMatchesIndoor(matrix, indoor_options));
  FENESTRA_RETURN_IF_ERROR(recorded);
  FENESTRA_ASSIGN_OR_RETURN(
      operation, SetLaneEvaluation(job, setting, matrix, ranged, indoor_options, *backend, lanes));
  computed.batches_on_device = {};  // the lanes hold their own copies
  // The outdoor matrix's mean relative error, for the result: a pass over O and its errors
  // (5-15 ms at the job's end) made beside the search
  std::future<double> outdoor_error =
      std::async(std::launch::async, [&matrix] { return OutdoorMeanRelativeError(matrix); });
  Racer racer(RacerSetting(spec, lanes, setting, search_settings));

  // The search
  if (callbacks.stage) callbacks.stage("search");
  result.mutable_timings()->set_start_seconds(SecondsSince(start));
  VnsResult search;
  if (spec.has_pareto()) {
    // A generation's designs at once, as many as the lanes trace together
    FENESTRA_ASSIGN_OR_RETURN(
        outcome, RunJobPareto(
                     job, search_settings, racer, callbacks, [&clock] { return clock.Seconds(); },
                     from.pareto_so_far ? &*from.pareto_so_far : nullptr, checkpoint));
    AddParetoResult(job, outcome, result);
    result.set_candidates_at_once(
        std::min(spec.pareto().population(),
                 static_cast<int>(lanes.tallies.size()) * lanes.tallies.front()->DesignsAtOnce()));
    search = std::move(outcome.search);
  } else {
    search_settings.options.lookahead = SearchLookahead(racer, lanes);
    FENESTRA_ASSIGN_OR_RETURN(made,
                              RunJobSearch(job, search_settings, racer, callbacks, clock,
                                           from.so_far ? &*from.so_far : nullptr, checkpoint));
    search = std::move(made);
    if (racer.Races()) AddRacing(racer, result);
    result.set_candidates_at_once(search_settings.options.lookahead);
    result.set_evaluations_discarded(search.discarded);
  }

  DescribeRun(spec, ranged, job.weather.location, result);

  // The result
  AddSearch(search_settings, search, checkpoint, result);
  result.set_outdoor_mean_relative_standard_error(outdoor_error.get());
  result.set_backend(backend->Name());
  FENESTRA_RETURN_IF_ERROR(HourlyAndCheck(job, setting, operation.get(), search,
                                          *lanes.tallies.front(), callbacks, clock, result));
  for (const auto& comfort : lanes.comfort) {
    result.mutable_timings()->set_comfort_seconds(result.timings().comfort_seconds() +
                                                  comfort->Seconds());
  }
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
  return CheckDesign(job, setting, nullptr, x, two_stage, backend.get(), {});
}

}  // namespace fenestra
