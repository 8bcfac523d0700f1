#pragma once

// A job's Pareto search (job.proto, ParetoSearch; core/optimize/pareto_search.h) on the
// lanes of its racer, and its outcome in the job's result.
#include <functional>

#include "absl/status/statusor.h"
#include "core/optimize/job.h"
#include "core/optimize/job_proto.h"
#include "core/optimize/pareto_search.h"
#include "core/optimize/racing.h"
#include "fenestra/v1/job.pb.h"

namespace fenestra {

// The search's objective: the designs at `xs` evaluated by `racer` (on its lanes); both must
// outlive it.
BatchObjective RacerObjective(const PreparedJob& job, Racer& racer);

// The search from the start or from `so_far`, `checkpoint` (that of `so_far`, else new) kept
// up to date after each step and handed out with the progress; `job_seconds` is the job's
// clock.
absl::StatusOr<ParetoOutcome> RunJobPareto(const PreparedJob& job, const SearchSettings& search,
                                           Racer& racer, const JobCallbacks& callbacks,
                                           const std::function<double()>& job_seconds,
                                           const ParetoOutcome* so_far,
                                           v1::SearchCheckpoint& checkpoint);

// `outcome`'s front, hypervolume and generations into result.pareto.
void AddParetoResult(const PreparedJob& job, const ParetoOutcome& outcome, v1::JobResult& result);

// Step `e` of a checkpoint's history as a Pareto step: its objectives and generation.
std::vector<Estimated> ParetoObjectivesOf(const v1::Evaluation& e);

}  // namespace fenestra
