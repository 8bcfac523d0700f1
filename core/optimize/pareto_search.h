#pragma once

// A Pareto search (core/README.md, "Pareto search"): NSGA-II (nsga2.h) over a job's design
// variables with the job's evaluations, generation by generation, each generation's designs
// evaluated at once (the lanes trace them together). Designs are snapped to the variables'
// steps and cached by their coordinates, as the Variable Neighborhood Search does. Every
// objective is a metric with its standard error: a design dominates another only when no
// worse in each and better in one by more than `dominance_z` combined standard errors, and
// with constraints Deb's rule (the smaller violation first) decides before the objectives.
// The front is the archive of evaluated designs no other dominates; its hypervolume after
// each generation is taken below the initial population's worst values.
//
// Its history (VnsRecord per proposed design, cached ones included) is its whole state: a
// search resumed from a history replays the generations, taking the values the history
// holds, and goes on as the uninterrupted one, mid-generation included.
#include <functional>
#include <span>
#include <vector>

#include "absl/status/statusor.h"
#include "core/metrics/annual_metrics.h"
#include "core/optimize/vns.h"

namespace fenestra {

struct ParetoObjective {
  SceneMetric metric = SceneMetric::kUdiMean;
  bool maximize = true;
};

// job.proto's defaults (ParetoSearch)
inline constexpr int kDefaultParetoPopulation = 40;
inline constexpr int kMaxParetoPopulation = 1000;
inline constexpr double kDefaultDominanceStandardErrors = 1;

struct ParetoOptions {
  std::vector<ParetoObjective> objectives;  // two or three
  int population = kDefaultParetoPopulation;
  double dominance_z = kDefaultDominanceStandardErrors;
  int max_evaluations = 150;  // designs proposed, cached ones included
  double max_seconds = 0;     // 0 = none
  uint64_t seed = kDefaultSeed;
  Constraints constraints;
};

// A search so far, or done.
struct ParetoOutcome {
  // Every proposed design (VnsRecord::neighborhood -1; `improved`: became the best in the
  // first objective, feasible first) and the best so (best_x, best, best_index)
  VnsResult search;
  std::vector<std::vector<Estimated>> objectives;  // per step, as the options' objectives
  std::vector<int> generation;                     // per step
  std::vector<int> front;           // steps no evaluated design dominates, by first objective
  std::vector<double> hypervolume;  // per generation done
  std::vector<double> reference;    // in the objectives' own units
  int generations = 0;              // done
};

struct ParetoCallbacks {
  std::function<bool()> cancelled;  // polled before each generation
  // After each step, the search so far (its last step the new one).
  std::function<void(const ParetoOutcome&)> step;
};

// The value of each of `objectives` in an evaluation's payload (AnnualMetricsEstimate).
std::vector<Estimated> ObjectiveValues(const Evaluation& evaluation,
                                       std::span<const ParetoObjective> objectives);

// Runs the search; with `resume` (a search so far of the same variables and options: its
// history's designs, evaluations, cached flags and objectives), from there. An empty
// `objective` replays `resume` and stops at its end (checking it). InvalidArgument for bad
// options or a history this search does not make; the objective's errors as returned.
absl::StatusOr<ParetoOutcome> RunPareto(std::span<const DesignVariable> variables,
                                        const BatchObjective& objective,
                                        const ParetoOptions& options,
                                        const ParetoCallbacks& callbacks = {},
                                        const ParetoOutcome* resume = nullptr);

}  // namespace fenestra
