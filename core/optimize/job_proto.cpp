// Between a job's protos and the core's types (job_proto.h), and the reading of a job file
// (ReadJobFile, job.h).
#include "core/optimize/job_proto.h"

#include <algorithm>
#include <cstdint>

#include "absl/strings/str_join.h"
#include "core/common/json_proto.h"
#include "core/common/status_macros.h"
#include "core/dc/dc_backend.h"
#include "core/geometry/scene_proto.h"
#include "core/optimize/build_info.h"
#include "core/optimize/design_variables.h"

namespace fenestra {
namespace {

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

// The objective's constraints into the search: its options' bounds and the metrics the
// evaluations return (the job validated: every metric known).
void AddConstraints(const v1::Objective& objective, SearchSettings& search) {
  Constraints& constraints = search.options.constraints;
  for (const v1::Constraint& c : objective.constraints()) {
    search.constraints.push_back(c);
    search.constraint_metrics.push_back(ToSceneMetric(c.metric()).value_or(SceneMetric::kUdiMean));
    constraints.bounds.push_back({c.bound() == v1::Constraint::AT_LEAST ? ConstraintBound::kAtLeast
                                                                        : ConstraintBound::kAtMost,
                                  c.value()});
  }
  if (objective.constraint_standard_errors() > 0) {
    constraints.standard_errors = objective.constraint_standard_errors();
  }
}

// Each constraint at the best design, whether it holds (within the search's standard errors).
void AddBestConstraints(const SearchSettings& settings, const VnsResult& search,
                        v1::JobResult& result) {
  const Constraints& constraints = settings.options.constraints;
  const std::vector<Estimated>& values = search.best.constraints;
  for (size_t c = 0; c < settings.constraints.size() && c < values.size(); ++c) {
    v1::ConstraintResult& out = *result.add_best_constraints();
    *out.mutable_constraint() = settings.constraints[c];
    SetEstimate(out.mutable_estimate(), values[c].value, values[c].standard_error);
    out.set_holds(!ConstraintsBroken({&constraints.bounds[c], 1}, {&values[c], 1},
                                     constraints.standard_errors));
  }
}

}  // namespace

absl::StatusOr<v1::Job> ReadJobFile(const std::string& path) {
  v1::Job job;
  FENESTRA_RETURN_IF_ERROR(ReadJsonProtoFile(path, "job", &job));
  return job;
}

SearchSettings MakeSearchSettings(const v1::Job& spec) {
  SearchSettings search;
  for (const v1::DesignVariable& v : spec.variables()) {
    search.variables.push_back({v.name(), v.lower(), v.upper(), v.start(), v.fixed(), v.step(),
                                v.name() == kFinishVariable});
  }
  VnsOptions& vns = search.options;
  if (spec.neighborhoods_size() > 0) {
    vns.neighborhoods.clear();
    for (const v1::Neighborhood& n : spec.neighborhoods()) {
      vns.neighborhoods.push_back({n.variables(), n.radius()});
    }
  }
  // A Pareto search's evaluations carry its first objective as their value
  const v1::Objective& objective = spec.has_pareto() && spec.pareto().objectives_size() > 0
                                       ? spec.pareto().objectives(0)
                                       : spec.objective();
  switch (objective.goal()) {
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
  AddConstraints(spec.objective(), search);
  vns.max_evaluations = spec.budget().max_evaluations();
  vns.max_seconds = spec.budget().max_seconds();
  vns.failed_cycles_to_stop = std::max(0, spec.budget().failed_cycles_to_stop());
  vns.seed = spec.sampling().seed();
  return search;
}

std::vector<SceneMetric> SearchMetrics(const v1::Job& spec) {
  std::vector<SceneMetric> metrics;
  if (spec.has_pareto()) {
    for (const v1::Objective& o : spec.pareto().objectives()) {
      metrics.push_back(ToSceneMetric(o.metric()).value_or(SceneMetric::kUdiMean));
    }
  } else {
    metrics.push_back(ToSceneMetric(spec.objective().metric()).value_or(SceneMetric::kUdiMean));
  }
  for (const v1::Constraint& c : spec.objective().constraints()) {
    metrics.push_back(ToSceneMetric(c.metric()).value_or(SceneMetric::kUdiMean));
  }
  return metrics;
}

ParetoOptions MakeParetoOptions(const v1::Job& spec, const SearchSettings& search) {
  ParetoOptions options;
  for (const v1::Objective& o : spec.pareto().objectives()) {
    options.objectives.push_back(
        {ToSceneMetric(o.metric()).value_or(SceneMetric::kUdiMean), o.goal() != v1::GOAL_MINIMIZE});
  }
  options.population = spec.pareto().population();
  options.dominance_z = spec.pareto().dominance_standard_errors();
  options.max_evaluations = spec.budget().max_evaluations();
  options.max_seconds = spec.budget().max_seconds();
  options.seed = spec.sampling().seed();
  options.constraints = search.options.constraints;
  return options;
}

Sequence SequenceOf(const v1::Sampling& sampling) {
  return sampling.sequence() == v1::SEQUENCE_SOBOL ? Sequence::kSobol : Sequence::kPseudoRandom;
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
    case v1::METRIC_ASE:
      return SceneMetric::kAse;
    case v1::METRIC_BLIND_IN_PLACE:
      return SceneMetric::kBlindInPlace;
    case v1::METRIC_GLARE_AUTONOMY:
      return SceneMetric::kGlareAutonomy;
    case v1::METRIC_GLARE_HOURS:
      return SceneMetric::kGlareHours;
    case v1::METRIC_SOLAR_GAIN:
      return SceneMetric::kSolarGain;
    case v1::METRIC_COOLING_SOLAR_GAIN:
      return SceneMetric::kCoolingSolarGain;
    default:
      return InvalidJobField("objective.metric", "unknown metric");
  }
}

IndoorOptions JobIndoorOptions(const PreparedJob& job) {
  const v1::Sampling& sampling = job.job.sampling();
  IndoorOptions options;
  options.paths_per_sensor = sampling.indoor_paths_per_sensor();
  options.max_bounces = sampling.indoor_bounces();
  options.seed = sampling.seed();
  options.basis_cells = sampling.basis_cells();
  options.parts = SamplingWindowParts(sampling, job.scene);
  options.batches = sampling.batches();
  options.sequence = SequenceOf(sampling);
  return options;
}

BlindDesign DesignAt(const PreparedJob& job, const std::vector<double>& x) {
  BlindDesign design = DefaultDesign(job.scene);
  for (int i = 0; i < job.job.variables_size(); ++i) {
    if (const DesignVariableInfo* info = FindDesignVariable(job.job.variables(i).name())) {
      design.*(info->field) = x[i];
    } else if (!job.finishes.empty()) {
      design.finish = FinishAt(job.finishes, x[i]);
    }
  }
  return design;
}

v1::Evaluation EvaluationProto(const PreparedJob& job, const VnsRecord& record,
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
  e.set_feasible(record.feasible);
  for (const Estimated& c : record.evaluation.constraints) {
    SetEstimate(e.add_constraints(), c.value, c.standard_error);
  }
  return e;
}

v1::Metrics MetricsProto(const AnnualMetricsEstimate& m) {
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
  SetEstimate(out.mutable_ase(), v.ase_percent, se.ase_percent);
  SetEstimate(out.mutable_blind_in_place(), v.blind_in_place_percent, se.blind_in_place_percent);
  out.set_leed_points(LeedDaylightPoints(v.sda_percent));
  if (m.has_glare) {
    SetEstimate(out.mutable_glare_autonomy(), v.glare_autonomy_percent, se.glare_autonomy_percent);
    SetEstimate(out.mutable_glare_hours(), v.glare_hours_percent, se.glare_hours_percent);
  }
  if (m.has_gains) {
    SetEstimate(out.mutable_solar_gain_kwh(), v.solar_gain_kwh, se.solar_gain_kwh);
    SetEstimate(out.mutable_cooling_solar_gain_kwh(), v.cooling_solar_gain_kwh,
                se.cooling_solar_gain_kwh);
  }
  for (const SensorMetrics& s : m.value.sensors) {
    out.add_sensor_sunlit_hours(static_cast<int32_t>(s.ase_hours));
  }
  for (size_t s = 0; s < m.value.sensors.size(); ++s) {
    SetEstimate(out.add_sensor_udi(), m.value.sensors[s].udi_percent,
                m.standard_error.sensors[s].udi_percent);
    SetEstimate(out.add_sensor_da(), m.value.sensors[s].da_percent,
                m.standard_error.sensors[s].da_percent);
  }
  return out;
}

void SetEstimate(v1::Estimate* out, double value, double standard_error) {
  out->set_value(value);
  out->set_standard_error(standard_error);
}

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

void AddSearch(const SearchSettings& settings, const VnsResult& search,
               v1::SearchCheckpoint& checkpoint, v1::JobResult& result) {
  for (size_t i = 0; i < settings.variables.size(); ++i) {
    (*result.mutable_best_design())[settings.variables[i].name] = search.best_x[i];
  }
  SetEstimate(result.mutable_best_value(), search.best.value, search.best.standard_error);
  if (checkpoint.has_best_metrics()) *result.mutable_best_metrics() = checkpoint.best_metrics();
  result.mutable_history()->Swap(checkpoint.mutable_history());
  AddBestOverTime(result);
  AddBestConstraints(settings, search, result);
  result.set_evaluations(search.evaluations);
  result.set_stop_reason(std::string(StopReasonName(search.stop_reason)));
  result.mutable_timings()->set_evaluation_seconds(search.evaluation_seconds);
}

}  // namespace fenestra
