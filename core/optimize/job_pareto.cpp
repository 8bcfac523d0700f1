#include "core/optimize/job_pareto.h"

#include <algorithm>

namespace fenestra {

BatchObjective RacerObjective(const PreparedJob& job, Racer& racer) {
  return [&job, &racer](const std::vector<std::vector<double>>& xs) {
    std::vector<BlindDesign> designs;
    for (const std::vector<double>& x : xs) designs.push_back(DesignAt(job, x));
    return racer.EvaluateBatch(designs);
  };
}

absl::StatusOr<ParetoOutcome> RunJobPareto(const PreparedJob& job, const SearchSettings& search,
                                           Racer& racer, const JobCallbacks& callbacks,
                                           const std::function<double()>& job_seconds,
                                           const ParetoOutcome* so_far,
                                           v1::SearchCheckpoint& checkpoint) {
  // When the search started, on the job's clock
  const double search_start = job_seconds() - (so_far ? so_far->search.elapsed_seconds : 0);
  const ParetoOptions options = MakeParetoOptions(job.job, search);
  const BatchObjective objective = RacerObjective(job, racer);
  ParetoCallbacks pareto_callbacks;
  pareto_callbacks.cancelled = callbacks.cancelled;
  pareto_callbacks.step = [&](const ParetoOutcome& state) {
    const size_t s = state.search.history.size() - 1;
    const VnsRecord& step = state.search.history[s];
    v1::Evaluation& e = *checkpoint.add_history() = EvaluationProto(job, step, search_start);
    for (const Estimated& o : state.objectives[s]) {
      SetEstimate(e.add_objectives(), o.value, o.standard_error);
    }
    e.set_generation(state.generation[s]);
    if (!step.cached) e.set_paths_fraction(1);
    if (step.improved) {
      if (const auto* metrics = std::any_cast<AnnualMetricsEstimate>(&step.evaluation.payload)) {
        *checkpoint.mutable_best_metrics() = MetricsProto(*metrics);
      } else {
        checkpoint.clear_best_metrics();
      }
    }
    checkpoint.set_search_seconds(state.search.elapsed_seconds);
    if (callbacks.checkpoint) callbacks.checkpoint(checkpoint);
    if (callbacks.progress) {
      JobProgress progress;
      progress.evaluations = static_cast<int>(s + 1);
      progress.max_evaluations = job.job.budget().max_evaluations();
      progress.current = checkpoint.history(static_cast<int>(s));
      progress.best = checkpoint.history(state.search.best_index);
      progress.elapsed_seconds = job_seconds();
      const double per_step = state.search.elapsed_seconds / static_cast<double>(s + 1);
      progress.remaining_seconds =
          per_step * std::max(0, progress.max_evaluations - static_cast<int>(s + 1));
      callbacks.progress(progress);
    }
  };
  return RunPareto(search.variables, objective, options, pareto_callbacks, so_far);
}

void AddParetoResult(const PreparedJob& job, const ParetoOutcome& outcome, v1::JobResult& result) {
  v1::ParetoResult& out = *result.mutable_pareto();
  for (const int s : outcome.front) {
    const VnsRecord& step = outcome.search.history[s];
    v1::FrontMember& m = *out.add_front();
    m.set_evaluation(s);
    for (int i = 0; i < job.job.variables_size(); ++i) {
      (*m.mutable_design())[job.job.variables(i).name()] = step.x[i];
    }
    for (const Estimated& o : outcome.objectives[s]) {
      SetEstimate(m.add_objectives(), o.value, o.standard_error);
    }
    if (const auto* metrics = std::any_cast<AnnualMetricsEstimate>(&step.evaluation.payload)) {
      *m.mutable_metrics() = MetricsProto(*metrics);
    }
  }
  for (const double v : outcome.hypervolume) out.add_hypervolume(v);
  for (const double v : outcome.reference) out.add_reference(v);
  out.set_generations(outcome.generations);
}

std::vector<Estimated> ParetoObjectivesOf(const v1::Evaluation& e) {
  std::vector<Estimated> out;
  for (const v1::Estimate& o : e.objectives()) out.push_back({o.value(), o.standard_error()});
  return out;
}

}  // namespace fenestra
