// Variable Neighborhood Search (Mladenovic & Hansen 1997, "Variable neighborhood search",
// Computers & Operations Research 24(11)) over box-constrained design variables
// (core/README.md, "Variable Neighborhood Search"): neighborhood N_k = (v, r) changes v
// randomly chosen free variables at once, each by U(-r, r) x (upper - lower). The search
// starts at N_1; an improvement moves the incumbent and returns to N_1, a failure goes on
// to N_{k+1}; after the last neighborhood a new cycle starts at N_1 from the incumbent. It
// stops at the first of: the evaluation budget, the time budget, `failed_cycles_to_stop`
// consecutive cycles in which every neighborhood failed, the target reached (target mode),
// or cancellation.
//
// With constraints (VnsOptions::constraints: bounds on other metrics, which the objective
// function returns beside its value), a design is infeasible when it breaks one by more than
// Constraints::standard_errors of its standard errors, and the incumbent moves by Deb's
// feasibility rules (`Improves`): a feasible design beats an infeasible one, two infeasible
// ones compare by their total violation, two feasible ones by their scores. Without
// constraints every design is feasible and the search is the unconstrained one.
//
// Moves are clamped to the box by default, so optima on a bound (a blind fully open, a
// tilt of 0) are reached exactly; BoundaryRule::kReflect mirrors them back instead. A
// variable with a `step` is then snapped to lower + k x step (and clamped again). A
// categorical variable (a choice, DesignVariable::categorical) moves to another of its values
// instead, within the neighborhood's radius but at least one step away.
//
// Every evaluated design is cached by its exact coordinates after clamping and snapping;
// proposing it again costs no evaluation and is marked `cached` in the history (`step`
// is how to make nearby designs count as equal). The random stream is std::mt19937_64
// seeded with `seed` and turned into numbers by fixed bit arithmetic (no std::
// distributions), so the sequence of designs is the same for the same seed on every
// platform and standard library, provided the objective is deterministic and no time
// budget or cancellation cuts the run short.
//
// A search may evaluate several designs at once (VnsOptions::lookahead, fewer while it
// improves often; a BatchObjective): it proposes the designs the next steps would propose if
// none of them improved, evaluates them together (on several devices, say), then takes the
// steps one by one as before. At the first improvement the designs evaluated ahead are
// dropped, and the search proposes from the new incumbent. The steps, and so the result, are
// those of the search one design at a time for the same seed; only time is spent on the
// dropped evaluations (VnsResult::discarded).
//
// A search can stop and go on later, in another process: after each step it hands out its
// result so far (VnsCallbacks::checkpoint), and RunVns continues from one (`resume`). All of
// its state follows from its history: replaying it (the same proposals, without calling the
// objective) rebuilds the random stream, the cache, the incumbent and the neighborhood, and
// checks the history against the search that replays it.
#pragma once

#include <any>
#include <cstdint>
#include <functional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "absl/status/statusor.h"
#include "core/trace/philox.h"

namespace fenestra {

struct DesignVariable {
  std::string name;
  double lower = 0;  // inclusive bound, in the variable's units
  double upper = 0;  // inclusive bound; upper == lower behaves as fixed
  double start = 0;  // in [lower, upper]; evaluated first, as given
  bool fixed = false;
  double step = 0;  // grid spacing of proposed values, variable's units; 0 = continuous
  // A choice among the values of its grid (step > 0), e.g. the slats' finish: each move goes
  // to another value of the grid, at most radius x (upper - lower) away and at least one step
  // (CategoryMove), where a grid variable's moves may round back to where they started.
  bool categorical = false;
};

// How many free variables change, and by how much.
struct Neighborhood {
  static constexpr int kAllVariables = 0;
  int variables = 1;              // at most this many (kAllVariables: every free one)
  double radius_fraction = 0.05;  // each moves by U(-r, r) x (upper - lower)
};

// (1, 0.02), (1, 0.1), (2, 0.1), (2, 0.3), (all, 0.5): fine then medium one-variable steps
// to refine; pairs for coupled variables (slat width and spacing act through their ratio,
// tilt and spacing through the cut-off angle); a shake of everything to leave a basin. A
// cycle costs 5 evaluations, so the reference budget of 150 allows 30 cycles.
std::vector<Neighborhood> DefaultNeighborhoods();

enum class BoundaryRule { kClamp, kReflect };

enum class ObjectiveSense {
  kMaximize,  // score = value
  kMinimize,  // score = -value
  kTarget,    // score = -|value - target| (the inverse problem)
};

enum class ConstraintBound { kAtMost, kAtLeast };

// A bound on one of a design's metrics besides the objective's (core/README.md,
// "Constraints"); the objective function returns the metric with its standard error
// (Evaluation::constraints).
struct Constraint {
  ConstraintBound bound = ConstraintBound::kAtMost;
  double value = 0;  // the bound, in the metric's units
};

// A design breaks a constraint when its metric is beyond the bound by more than this many of
// its standard errors (Constraints::standard_errors; job.proto's default).
inline constexpr double kDefaultConstraintStandardErrors = 1;

// The bounds a design must keep to be feasible (Deb's feasibility rules, `Improves`); none:
// every design is feasible and the search is the unconstrained one.
struct Constraints {
  std::vector<Constraint> bounds = {};
  // A design breaks a bound when beyond it by more than this many standard errors; > 0.
  double standard_errors = kDefaultConstraintStandardErrors;
};

struct Objective {
  ObjectiveSense sense = ObjectiveSense::kMaximize;
  double target = 0;            // kTarget only
  double target_tolerance = 0;  // kTarget: stop once |value - target| <= this (feasible)
};

struct VnsOptions {
  std::vector<Neighborhood> neighborhoods = DefaultNeighborhoods();
  BoundaryRule boundary = BoundaryRule::kClamp;
  Objective objective;
  Constraints constraints;    // the objective function returns their metrics
  int max_evaluations = 150;  // objective calls, the start included; >= 1
  double max_seconds = 0;     // wall-clock budget [s]; 0 = none
  // Stop after this many consecutive cycles in which every neighborhood failed; 1 = at the
  // first such cycle, 0 = never (run to the budget). A move in a random direction improves
  // at best about half the time, so a run of 15 failures (3 cycles) happens by chance in
  // about 1 run of 100 far from any optimum; 10 cycles (50 failures) means convergence.
  int failed_cycles_to_stop = 10;
  // A candidate replaces the incumbent when its score exceeds the incumbent's by more than
  // max(min_improvement, min_improvement_standard_errors x sqrt(se_new^2 + se_best^2)).
  // The defaults (0, 0) take any strict improvement, right with common random numbers,
  // whose errors largely cancel between designs.
  double min_improvement = 0;
  double min_improvement_standard_errors = 0;
  uint64_t seed = kDefaultSeed;
  // Stop when this many proposals in a row were already in the cache: the space is used up
  // at the resolution of the variables' steps.
  int max_consecutive_cache_hits = 1000;
  // Designs evaluated at once, ahead of the steps that take them (the file comment); 1 = one
  // at a time. In [1, kMaxLookahead]. At most this many: fewer while the search improves
  // often (kBusyImprovements).
  int lookahead = 1;
};

inline constexpr int kMaxLookahead = 64;

// The designs evaluated ahead of an improvement are dropped, so while the search improves
// often it evaluates fewer at once: two thirds of VnsOptions::lookahead (rounded up) while
// more than kBusyImprovements of its last kRecentEvaluations evaluations improved
// (bench/README.md, "Fewer designs at once while the search improves").
inline constexpr int kRecentEvaluations = 20;
inline constexpr int kBusyImprovements = 2;

// A value with its Monte Carlo standard error, in the value's units.
struct Estimated {
  double value = 0;
  double standard_error = 0;
  bool operator==(const Estimated&) const = default;
};

// What the objective returns for one design.
struct Evaluation {
  double value = 0;           // the metric, e.g. UDI [%]
  double standard_error = 0;  // its Monte Carlo standard error, same units
  // Evaluated only far enough to know the design is worse than the incumbent (racing,
  // core/optimize/racing.h): such an evaluation never becomes the incumbent.
  bool partial = false;
  std::any payload;  // anything the caller wants back (e.g. all metrics)
  // The metric of each of VnsOptions::constraints' bounds, in their order (empty without).
  std::vector<Estimated> constraints = {};
};

// Evaluates one design (one coordinate per variable, fixed ones included). An error status
// stops the search and is returned.
using ObjectiveFunction = std::function<absl::StatusOr<Evaluation>(const std::vector<double>& x)>;

// Evaluates several designs, each as ObjectiveFunction would, and returns one result per
// design in their order. An error stops the search only when the search takes that design's
// step; the evaluations of the designs it drops are never looked at.
using BatchObjective = std::function<std::vector<absl::StatusOr<Evaluation>>(
    const std::vector<std::vector<double>>& designs)>;

// One step of the search.
struct VnsRecord {
  int index = 0;  // position in the history
  std::vector<double> x;
  Evaluation evaluation;
  double score = 0;               // what the search maximizes (see ObjectiveSense)
  double evaluation_seconds = 0;  // time in the objective; 0 when cached
  double elapsed_seconds = 0;     // search clock after this step (VnsResult::elapsed_seconds)
  bool cached = false;            // served from the cache, not evaluated
  bool improved = false;          // became the incumbent (the start does)
  int neighborhood = -1;          // index into VnsOptions::neighborhoods; -1 = start
  bool feasible = true;           // keeps every constraint (ConstraintsBroken)
  double violation = 0;           // ConstraintViolation: 0 within every bound
};

struct VnsProgress {
  int evaluations = 0;  // objective calls so far
  int max_evaluations = 0;
  const VnsRecord* current = nullptr;  // the step just done
  const VnsRecord* best = nullptr;     // the incumbent
  double elapsed_seconds = 0;
  // Seconds left at the current rate until the evaluation or time budget, whichever comes
  // first; the search may stop earlier.
  double remaining_seconds = 0;
};

enum class StopReason {
  kEvaluationBudget,
  kTimeBudget,
  kAllNeighborhoodsFailed,
  kTargetReached,
  kCancelled,
  kNoFreeVariables,
  kSpaceExhausted,
};

// What the search maximizes for `value`: value, -value or -|value - target|.
double Score(const Objective& objective, double value);

// How far `value` lies beyond the bound of `constraint` (0 within it), in its units.
double ConstraintExcess(const Constraint& constraint, double value);

// Whether some constraint's value (`values`, one per constraint) is beyond its bound by
// more than `standard_errors` times its standard error: the design is then infeasible.
bool ConstraintsBroken(std::span<const Constraint> constraints, std::span<const Estimated> values,
                       double standard_errors);

// The sum of the constraints' excesses beyond their bounds (ConstraintExcess), in the
// metrics' units: what two infeasible designs compare by.
double ConstraintViolation(std::span<const Constraint> constraints,
                           std::span<const Estimated> values);

// Whether `evaluation` keeps `constraints` (none broken beyond their standard_errors).
bool Feasible(const Constraints& constraints, const Evaluation& evaluation);

// Whether step `candidate` moves the incumbent `incumbent` (Deb 2000, "An efficient
// constraint handling method for genetic algorithms"): never when partial; a feasible design
// beats an infeasible one; of two infeasible ones the smaller violation wins; of two feasible
// ones the score, by more than max(min_improvement, min_improvement_standard_errors x
// sqrt(se_new^2 + se_best^2)). Reads the records' score, feasible and violation.
bool Improves(const VnsOptions& options, const VnsRecord& candidate, const VnsRecord& incumbent);

// Stable snake_case names: "evaluation_budget", "time_budget", "all_neighborhoods_failed",
// "target_reached", "cancelled", "no_free_variables", "space_exhausted".
std::string_view StopReasonName(StopReason reason);

struct VnsResult {
  std::vector<double> best_x;  // the incumbent
  Evaluation best;
  double best_score = 0;
  int best_index = 0;  // into history: its last step that improved
  std::vector<VnsRecord> history;
  int evaluations = 0;
  int cache_hits = 0;
  int improvements = 0;  // moves of the incumbent, the start excluded
  StopReason stop_reason = StopReason::kEvaluationBudget;
  // The search's clock [s]: since it started, the time between a checkpoint and its resume
  // left out.
  double elapsed_seconds = 0;
  double evaluation_seconds = 0;  // total time in the objective, dropped evaluations included
  // Designs evaluated ahead and dropped because an earlier one improved (lookahead > 1)
  int discarded = 0;
};

struct VnsCallbacks {
  std::function<void(const VnsProgress&)> progress;  // after each step; may be empty
  std::function<bool()> cancelled;  // polled before each step; true stops; may be empty
  // After each step (an evaluation or a cache hit), before `progress`: the result so far,
  // from which RunVns's `resume` goes on. Its stop_reason means nothing yet, its
  // elapsed_seconds is the step's. May be empty.
  std::function<void(const VnsResult& so_far)> checkpoint;
};

// Runs the search from the variables' start values. InvalidArgument for bad variables or
// options, or a non-finite value from the objective; the objective's own error status as
// returned (with the design prepended); Cancelled when cancelled before the start was
// evaluated. A cancellation after that returns the result so far with kCancelled.
//
// With `resume`, a result so far of the same search (same variables and options;
// VnsCallbacks::checkpoint), the search goes on after its last step as if it had never
// stopped: its history is replayed without calling the objective, and
// the clock continues from its elapsed_seconds. Only its history and elapsed_seconds are
// read; the rest is rebuilt. InvalidArgument when the history is not one this search makes
// (a step's design, neighborhood, cache hit or improvement differs from the replay's).
absl::StatusOr<VnsResult> RunVns(std::span<const DesignVariable> variables,
                                 const ObjectiveFunction& objective, const VnsOptions& options = {},
                                 const VnsCallbacks& callbacks = {},
                                 const VnsResult* resume = nullptr);

// The same with designs evaluated options.lookahead at a time: the same steps and result.
// A step's evaluation_seconds is its share of its batch's time.
absl::StatusOr<VnsResult> RunVns(std::span<const DesignVariable> variables,
                                 const BatchObjective& objective, const VnsOptions& options = {},
                                 const VnsCallbacks& callbacks = {},
                                 const VnsResult* resume = nullptr);

// What RunVns checks of its inputs and of `resume` (the replay of its history), without
// running the search: a resumed job refuses a bad checkpoint before its costly stages.
absl::Status CheckVnsResume(std::span<const DesignVariable> variables, const VnsOptions& options,
                            const VnsResult& resume);

}  // namespace fenestra
