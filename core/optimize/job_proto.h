#pragma once

// Between a job's protos and the core's types, for the job runner (job.cpp): a job's fields
// as the settings of its search, metric, indoor stage and designs; what its search and racing
// did as the fields of its JobResult.
#include <string>
#include <vector>

#include "absl/status/statusor.h"
#include "core/dc/two_stage.h"
#include "core/geometry/blind.h"
#include "core/geometry/scene.h"
#include "core/metrics/annual_metrics.h"
#include "core/metrics/metric_errors.h"
#include "core/optimize/job.h"
#include "core/optimize/pareto_search.h"
#include "core/optimize/racing.h"
#include "core/optimize/vns.h"
#include "core/sky/epw.h"
#include "fenestra/v1/job.pb.h"

namespace fenestra {

// The search of a job: its variables, in the job's order, and its options.
struct SearchSettings {
  std::vector<DesignVariable> variables;
  VnsOptions options;
  // The objective's constraints as the job gives them, and the scene metric of each (what
  // the evaluations return in Evaluation::constraints), in the job's order.
  std::vector<v1::Constraint> constraints;
  std::vector<SceneMetric> constraint_metrics;
};

// The search `spec` asks for: its variables, neighborhoods, objective with its constraints,
// budget and seed (the job validated, its defaults filled in). The lookahead is left at one.
SearchSettings MakeSearchSettings(const v1::Job& spec);

// The metrics the job's search weighs: the objective's (each Pareto objective's, for a Pareto
// search), then each constraint's (the job validated).
std::vector<SceneMetric> SearchMetrics(const v1::Job& spec);

// The Pareto search `spec` asks for (spec.pareto set, the job validated: defaults filled in).
ParetoOptions MakeParetoOptions(const v1::Job& spec, const SearchSettings& search);

// The scene metric of an objective's (or a constraint's) metric; InvalidArgument "job
// objective.metric" for an unknown one.
absl::StatusOr<SceneMetric> ToSceneMetric(v1::Metric metric);
// The tracer's sequence of a resolved job's Sampling.sequence (ResolveSampling).
Sequence SequenceOf(const v1::Sampling& sampling);

// The indoor stage of the job's designs: its sampling's paths, bounces, seed, basis, window
// parts (resolved) and batches.
IndoorOptions JobIndoorOptions(const PreparedJob& job);

// The design at the search's point `x` (a value per job variable, in the job's order; the
// finish's an index of PreparedJob::finishes), the blind's other parameters and, without a
// finish variable, its finish at the scene's values.
BlindDesign DesignAt(const PreparedJob& job, const std::vector<double>& x);

// A step of the search as a result's Evaluation. `search_start_seconds`: when the search
// started, in the job's time [s].
v1::Evaluation EvaluationProto(const PreparedJob& job, const VnsRecord& record,
                               double search_start_seconds);

// Annual metrics with their standard errors [%], the scene's and each sensor's.
v1::Metrics MetricsProto(const AnnualMetricsEstimate& m);

void SetEstimate(v1::Estimate* out, double value, double standard_error);

// What a result says about how it was made: the job as run (`spec` with `scene` inline, self
// contained, and no file paths), the weather's location and the versions.
void DescribeRun(const v1::Job& spec, const Scene& scene, const EpwLocation& location,
                 v1::JobResult& result);

// What racing did (its rounds, test, candidates, rejections and paths), into `result`.
void AddRacing(const Racer& racer, v1::JobResult& result);

// The search into `result`: the best design and its value, metrics and constraints, every
// step (moved from `checkpoint`, which holds them in the job's terms), the best value against
// time, the counts and why it stopped.
void AddSearch(const SearchSettings& settings, const VnsResult& search,
               v1::SearchCheckpoint& checkpoint, v1::JobResult& result);

}  // namespace fenestra
