#include "core/optimize/vns.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <map>
#include <optional>
#include <random>
#include <utility>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_join.h"
#include "core/common/seconds.h"
#include "core/common/status_macros.h"

namespace fenestra {
namespace {

using Clock = std::chrono::steady_clock;

// Uniform in [0, 1) from the top 53 bits.
double Uniform01(std::mt19937_64& rng) { return static_cast<double>(rng() >> 11) * 0x1.0p-53; }

// Uniform in [0, n) by rejection, free of modulo bias.
uint64_t UniformIndex(std::mt19937_64& rng, uint64_t n) {
  const uint64_t limit = UINT64_MAX - UINT64_MAX % n;
  uint64_t r;
  do {
    r = rng();
  } while (r >= limit);
  return r % n;
}

bool IsFree(const DesignVariable& v) { return !v.fixed && v.upper > v.lower; }

absl::Status CheckInputs(std::span<const DesignVariable> variables, const VnsOptions& o) {
  if (variables.empty()) return absl::InvalidArgumentError("no design variables");
  for (const DesignVariable& v : variables) {
    const std::string which = absl::StrCat("variable '", v.name, "'");
    if (!std::isfinite(v.lower) || !std::isfinite(v.upper) || v.lower > v.upper) {
      return absl::InvalidArgumentError(
          absl::StrCat(which, ": bounds [", v.lower, ", ", v.upper, "] are not a finite range"));
    }
    if (!(v.start >= v.lower && v.start <= v.upper)) {
      return absl::InvalidArgumentError(
          absl::StrCat(which, ": start ", v.start, " outside [", v.lower, ", ", v.upper, "]"));
    }
    if (!(v.step >= 0) || !std::isfinite(v.step)) {
      return absl::InvalidArgumentError(absl::StrCat(which, ": step ", v.step, " is negative"));
    }
    if (v.categorical && !(v.step > 0)) {
      return absl::InvalidArgumentError(absl::StrCat(which, ": a choice needs a step > 0"));
    }
  }
  if (o.neighborhoods.empty()) return absl::InvalidArgumentError("no neighborhoods");
  for (size_t k = 0; k < o.neighborhoods.size(); ++k) {
    const Neighborhood& n = o.neighborhoods[k];
    if (n.variables < 0 || !(n.radius_fraction > 0) || !std::isfinite(n.radius_fraction)) {
      return absl::InvalidArgumentError(
          absl::StrCat("neighborhood ", k + 1, " (", n.variables, ", ", n.radius_fraction,
                       "): need variables >= 0 (0 = all) and a positive radius"));
    }
  }
  if (o.max_evaluations < 1) {
    return absl::InvalidArgumentError(
        absl::StrCat("max_evaluations ", o.max_evaluations, ": must be at least 1"));
  }
  if (o.lookahead < 1 || o.lookahead > kMaxLookahead) {
    return absl::InvalidArgumentError(
        absl::StrCat("lookahead ", o.lookahead, ": must be in [1, ", kMaxLookahead, "]"));
  }
  if (!(o.max_seconds >= 0) || o.failed_cycles_to_stop < 0 || !(o.min_improvement >= 0) ||
      !(o.min_improvement_standard_errors >= 0) || o.max_consecutive_cache_hits < 1 ||
      !(o.objective.target_tolerance >= 0) || !std::isfinite(o.objective.target)) {
    return absl::InvalidArgumentError(
        "max_seconds, failed_cycles_to_stop, min_improvement, "
        "min_improvement_standard_errors and target_tolerance must not be negative, "
        "max_consecutive_cache_hits must be positive and the target finite");
  }
  for (size_t c = 0; c < o.constraints.bounds.size(); ++c) {
    if (!std::isfinite(o.constraints.bounds[c].value)) {
      return absl::InvalidArgumentError(absl::StrCat(
          "constraint ", c + 1, ": bound ", o.constraints.bounds[c].value, " is not finite"));
    }
  }
  if (!(o.constraints.standard_errors > 0) || !std::isfinite(o.constraints.standard_errors)) {
    return absl::InvalidArgumentError(absl::StrCat("constraints' standard_errors ",
                                                   o.constraints.standard_errors,
                                                   ": must be positive and finite"));
  }
  return absl::OkStatus();
}

// Whether every value and standard error of an evaluation is finite.
bool AllFinite(const Evaluation& e) {
  if (!std::isfinite(e.value) || !std::isfinite(e.standard_error)) return false;
  return std::all_of(e.constraints.begin(), e.constraints.end(), [](const Estimated& c) {
    return std::isfinite(c.value) && std::isfinite(c.standard_error);
  });
}

// Brings a moved coordinate back into the box, then onto the variable's grid.
double Constrain(const DesignVariable& v, double x, BoundaryRule rule) {
  const double width = v.upper - v.lower;
  if (rule == BoundaryRule::kReflect) {
    double t = std::fmod(x - v.lower, 2 * width);
    if (t < 0) t += 2 * width;
    if (t > width) t = 2 * width - t;
    x = v.lower + t;
  }
  x = std::clamp(x, v.lower, v.upper);
  if (v.step > 0) {
    x = v.lower + std::round((x - v.lower) / v.step) * v.step;
    x = std::clamp(x, v.lower, v.upper);
  }
  return x;
}

// A move of categorical `v` from `x`: to one of the other grid values at most
// max(1, round(radius x (count - 1))) steps away, each as likely (one draw of `rng`).
double CategoryMove(const DesignVariable& v, double x, double radius_fraction,
                    std::mt19937_64& rng) {
  const int64_t last = std::llround((v.upper - v.lower) / v.step);
  const int64_t at = std::clamp<int64_t>(std::llround((x - v.lower) / v.step), 0, last);
  const int64_t reach =
      std::max<int64_t>(1, std::llround(radius_fraction * static_cast<double>(last)));
  const int64_t low = std::max<int64_t>(0, at - reach), high = std::min(last, at + reach);
  if (high == low) return x;
  int64_t to = low + static_cast<int64_t>(UniformIndex(rng, static_cast<uint64_t>(high - low)));
  if (to >= at) ++to;  // every value but the one it is at
  return std::min(v.upper, v.lower + static_cast<double>(to) * v.step);
}

// Where the search goes next: the random stream and the counts the steps move on.
struct Walk {
  explicit Walk(uint64_t seed) : rng(seed) {}

  // A step (not the start) is done: an improvement returns to the first neighborhood, a
  // failure goes on to the next, and after the last to a new cycle.
  void Advance(bool improved, bool cached, int neighborhoods) {
    consecutive_hits = cached ? consecutive_hits + 1 : 0;
    if (improved) {
      neighborhood = 0;
      failed_cycles = 0;
    } else if (++neighborhood == neighborhoods) {
      neighborhood = 0;
      ++failed_cycles;
    }
  }

  std::mt19937_64 rng;
  int neighborhood = 0;  // of the next step
  int failed_cycles = 0;
  int consecutive_hits = 0;
};

// A design evaluated ahead of its step.
struct Ahead {
  std::vector<double> x;
  absl::StatusOr<Evaluation> evaluation;
  double seconds = 0;  // its share of its batch's time
};

// One run of the search: its state between steps (the result so far and where it goes on),
// and the steps.
class Search {
 public:
  Search(std::span<const DesignVariable> variables, const BatchObjective& objective,
         const VnsOptions& options, const VnsCallbacks& callbacks)
      : variables_(variables),
        objective_(objective),
        options_(options),
        callbacks_(callbacks),
        start_time_(Clock::now()),
        walk_(options.seed) {
    for (size_t i = 0; i < variables.size(); ++i) {
      if (IsFree(variables[i])) free_.push_back(i);
    }
  }

  // Evaluates the start design.
  absl::Status Start();
  // Takes `so_far`'s history as done by this search, checking each step against the replay.
  absl::Status Replay(const VnsResult& so_far);
  // Steps until a stopping rule holds; the result.
  absl::StatusOr<VnsResult> Run();

 private:
  double Elapsed() const { return resumed_seconds_ + SecondsSince(start_time_); }
  std::vector<double> StartDesign() const;
  std::vector<double> Propose(Walk& walk) const;
  absl::StatusOr<VnsRecord> Evaluate(std::vector<double> x, int neighborhood);
  void Assess(VnsRecord& record) const;
  int Lookahead() const;
  void EvaluateAhead(const std::vector<double>& x, bool start);
  void DropAhead();
  void Record(VnsRecord record);
  void Publish();
  bool WalkEnds(const Walk& walk, int evaluations) const;
  std::optional<StopReason> StopBeforeStep();

  std::span<const DesignVariable> variables_;
  const BatchObjective& objective_;
  const VnsOptions& options_;
  const VnsCallbacks& callbacks_;
  const Clock::time_point start_time_;
  double resumed_seconds_ = 0;  // the clock at the checkpoint resumed from
  std::vector<size_t> free_;    // indices of the free variables
  Walk walk_;
  VnsResult state_;
  std::map<std::vector<double>, int> cache_;  // design -> history index of its evaluation
  std::vector<Ahead> ahead_;  // evaluated ahead against the current incumbent, not yet taken
};

std::vector<double> Search::StartDesign() const {
  std::vector<double> start;
  for (const DesignVariable& v : variables_) start.push_back(v.start);
  return start;
}

// Moves v randomly chosen free variables of the incumbent (v and the radius of the current
// neighborhood).
std::vector<double> Search::Propose(Walk& walk) const {
  const Neighborhood& n = options_.neighborhoods[walk.neighborhood];
  const size_t count = n.variables == Neighborhood::kAllVariables
                           ? free_.size()
                           : std::min(free_.size(), static_cast<size_t>(n.variables));
  std::vector<size_t> order = free_;
  std::vector<double> x = state_.best_x;
  for (size_t c = 0; c < count; ++c) {
    std::swap(order[c], order[c + UniformIndex(walk.rng, order.size() - c)]);
    const DesignVariable& v = variables_[order[c]];
    if (v.categorical) {
      x[order[c]] = CategoryMove(v, x[order[c]], n.radius_fraction, walk.rng);
      continue;
    }
    const double delta = (2 * Uniform01(walk.rng) - 1) * n.radius_fraction * (v.upper - v.lower);
    x[order[c]] = Constrain(v, x[order[c]] + delta, options_.boundary);
  }
  return x;
}

// Designs evaluated at once now: options_.lookahead, or two thirds of it (rounded up) while
// more than kBusyImprovements of the last kRecentEvaluations evaluations improved.
int Search::Lookahead() const {
  int evaluated = 0, improved = 0;
  for (auto r = state_.history.rbegin();
       r != state_.history.rend() && evaluated < kRecentEvaluations; ++r) {
    if (r->cached) continue;
    ++evaluated;
    improved += r->improved ? 1 : 0;
  }
  return improved > kBusyImprovements ? (2 * options_.lookahead + 2) / 3 : options_.lookahead;
}

// Evaluates `x`, the design of the next step, with the designs the steps after it propose
// if none of them improves (Lookahead() in all, new ones only, within the budget); the start
// alone (there is no incumbent to propose from yet).
void Search::EvaluateAhead(const std::vector<double>& x, bool start) {
  std::vector<std::vector<double>> designs = {x};
  const auto known = [&](const std::vector<double>& y) {
    return cache_.contains(y) || std::find(designs.begin(), designs.end(), y) != designs.end();
  };
  const int neighborhoods = static_cast<int>(options_.neighborhoods.size());
  Walk walk = walk_;  // past x's proposal
  walk.Advance(false, false, neighborhoods);
  const int lookahead = Lookahead();
  const int max_steps = 16 * lookahead;
  for (int step = 0; !start && step < max_steps && static_cast<int>(designs.size()) < lookahead &&
                     !WalkEnds(walk, state_.evaluations + static_cast<int>(designs.size()));
       ++step) {
    std::vector<double> y = Propose(walk);
    const bool cached = known(y);
    if (!cached) designs.push_back(std::move(y));
    walk.Advance(false, cached, neighborhoods);
  }
  const Clock::time_point t0 = Clock::now();
  std::vector<absl::StatusOr<Evaluation>> evaluations = objective_(designs);
  const double share = SecondsSince(t0) / static_cast<double>(designs.size());
  for (size_t i = 0; i < designs.size(); ++i) {
    absl::StatusOr<Evaluation> e =
        i < evaluations.size() ? std::move(evaluations[i])
                               : absl::InternalError("the objective returned too few results");
    ahead_.push_back({std::move(designs[i]), std::move(e), share});
  }
}

// Drops the designs evaluated ahead that no step took (the incumbent changed, or the search
// stops), keeping their time.
void Search::DropAhead() {
  for (const Ahead& a : ahead_) state_.evaluation_seconds += a.seconds;
  state_.discarded += static_cast<int>(ahead_.size());
  ahead_.clear();
}

// The step at design `x`: looked up in the cache, else evaluated (ahead, or now with the
// designs after it).
absl::StatusOr<VnsRecord> Search::Evaluate(std::vector<double> x, int neighborhood) {
  VnsRecord record;
  record.index = static_cast<int>(state_.history.size());
  record.neighborhood = neighborhood;
  if (auto hit = cache_.find(x); hit != cache_.end()) {
    const VnsRecord& earlier = state_.history[hit->second];
    record.evaluation = earlier.evaluation;
    record.score = earlier.score;
    record.feasible = earlier.feasible;
    record.violation = earlier.violation;
    record.cached = true;
  } else {
    auto ahead =
        std::find_if(ahead_.begin(), ahead_.end(), [&](const Ahead& a) { return a.x == x; });
    if (ahead == ahead_.end()) {
      EvaluateAhead(x, neighborhood < 0);
      ahead = ahead_.end() - 1;
      while (ahead->x != x) --ahead;
    }
    absl::StatusOr<Evaluation> evaluation = std::move(ahead->evaluation);
    record.evaluation_seconds = ahead->seconds;
    ahead_.erase(ahead);
    if (!evaluation.ok()) {
      return absl::Status(evaluation.status().code(),
                          absl::StrCat("evaluating x = (", absl::StrJoin(x, ", "),
                                       "): ", evaluation.status().message()));
    }
    if (!AllFinite(*evaluation)) {
      return absl::InvalidArgumentError(absl::StrCat(
          "the objective returned ", evaluation->value, " +- ", evaluation->standard_error,
          " at x = (", absl::StrJoin(x, ", "), "), or a constraint's value that is not finite"));
    }
    if (evaluation->constraints.size() != options_.constraints.bounds.size()) {
      return absl::InvalidArgumentError(
          absl::StrCat("the objective returned ", evaluation->constraints.size(),
                       " constraint values for ", options_.constraints.bounds.size(),
                       " constraints at x = (", absl::StrJoin(x, ", "), ")"));
    }
    record.evaluation = *std::move(evaluation);
    Assess(record);
  }
  record.x = std::move(x);
  return record;
}

// The record's score and standing against the constraints, from its evaluation.
void Search::Assess(VnsRecord& record) const {
  record.score = Score(options_.objective, record.evaluation.value);
  record.feasible = Feasible(options_.constraints, record.evaluation);
  record.violation =
      ConstraintViolation(options_.constraints.bounds, record.evaluation.constraints);
}

// Appends a step to the history: whether it moves the incumbent (the start does), and where
// the search goes on (next neighborhood, failed cycles, run of cache hits).
void Search::Record(VnsRecord record) {
  if (record.cached) {
    ++state_.cache_hits;
  } else {
    ++state_.evaluations;
    state_.evaluation_seconds += record.evaluation_seconds;
    cache_.emplace(record.x, record.index);
  }
  if (record.neighborhood < 0) {
    record.improved = true;
  } else {
    record.improved = Improves(options_, record, state_.history[state_.best_index]);
    walk_.Advance(record.improved, record.cached, static_cast<int>(options_.neighborhoods.size()));
    if (record.improved) {
      ++state_.improvements;
      DropAhead();  // evaluated against the incumbent before
    }
  }
  state_.elapsed_seconds = record.elapsed_seconds;
  state_.history.push_back(std::move(record));
  const VnsRecord& step = state_.history.back();
  if (step.improved) {
    state_.best_index = step.index;
    state_.best_x = step.x;
    state_.best = step.evaluation;
    state_.best_score = step.score;
  }
}

// Hands out the step just recorded: the checkpoint, then the progress.
void Search::Publish() {
  if (callbacks_.checkpoint) callbacks_.checkpoint(state_);
  if (!callbacks_.progress) return;
  VnsProgress progress;
  progress.evaluations = state_.evaluations;
  progress.max_evaluations = options_.max_evaluations;
  progress.current = &state_.history.back();
  progress.best = &state_.history[state_.best_index];
  progress.elapsed_seconds = state_.history.back().elapsed_seconds;
  const double per_evaluation = progress.elapsed_seconds / std::max(state_.evaluations, 1);
  progress.remaining_seconds = per_evaluation * (options_.max_evaluations - state_.evaluations);
  if (options_.max_seconds > 0) {
    progress.remaining_seconds = std::clamp(options_.max_seconds - progress.elapsed_seconds, 0.0,
                                            progress.remaining_seconds);
  }
  callbacks_.progress(progress);
}

absl::Status Search::Start() {
  FENESTRA_ASSIGN_OR_RETURN(first, Evaluate(StartDesign(), -1));
  first.elapsed_seconds = Elapsed();
  Record(std::move(first));
  Publish();
  return absl::OkStatus();
}

absl::Status Search::Replay(const VnsResult& so_far) {
  if (so_far.history.empty()) {
    return absl::InvalidArgumentError("resume: the search so far has no steps");
  }
  if (!(so_far.elapsed_seconds >= 0) || !std::isfinite(so_far.elapsed_seconds)) {
    return absl::InvalidArgumentError(
        absl::StrCat("resume: elapsed_seconds ", so_far.elapsed_seconds, " is not a time"));
  }
  for (const VnsRecord& done : so_far.history) {
    const int i = static_cast<int>(state_.history.size());
    auto differs = [&](const std::string& what) {
      return absl::InvalidArgumentError(
          absl::StrCat("resume: step ", i, " differs from this search's (", what,
                       "): the history belongs to another search (variables, options or seed)"));
    };
    if (done.index != i) return differs(absl::StrCat("index ", done.index));
    if (done.neighborhood != (i == 0 ? -1 : walk_.neighborhood)) {
      return differs(absl::StrCat("neighborhood ", done.neighborhood));
    }
    if (done.x != (i == 0 ? StartDesign() : Propose(walk_))) {
      return differs(absl::StrCat("design (", absl::StrJoin(done.x, ", "), ")"));
    }
    if (!AllFinite(done.evaluation) || !std::isfinite(done.evaluation_seconds) ||
        !std::isfinite(done.elapsed_seconds)) {
      return differs("a value or time that is not finite");
    }
    if (done.evaluation.constraints.size() != options_.constraints.bounds.size()) {
      return differs(absl::StrCat(done.evaluation.constraints.size(), " constraint values"));
    }
    const auto hit = cache_.find(done.x);
    if (done.cached != (hit != cache_.end())) return differs("cache hit");
    if (done.cached) {
      const Evaluation& earlier = state_.history[hit->second].evaluation;
      if (done.evaluation.value != earlier.value ||
          done.evaluation.standard_error != earlier.standard_error ||
          done.evaluation.partial != earlier.partial ||
          done.evaluation.constraints != earlier.constraints) {
        return differs("a cache hit with another value than its design's evaluation");
      }
    }
    VnsRecord step = done;
    Assess(step);
    Record(std::move(step));
    if (state_.history.back().improved != done.improved) return differs("improvement");
  }
  resumed_seconds_ = so_far.elapsed_seconds;
  state_.elapsed_seconds = so_far.elapsed_seconds;
  return absl::OkStatus();
}

// Whether a search at `walk`, with `evaluations` done, stops before its next step by the
// rules that follow from the steps alone (not the incumbent, the clock or a cancellation).
bool Search::WalkEnds(const Walk& walk, int evaluations) const {
  return (options_.failed_cycles_to_stop > 0 &&
          walk.failed_cycles >= options_.failed_cycles_to_stop) ||
         walk.consecutive_hits >= options_.max_consecutive_cache_hits ||
         evaluations >= options_.max_evaluations;
}

// The stopping rules, checked before each step but the start.
std::optional<StopReason> Search::StopBeforeStep() {
  if (options_.failed_cycles_to_stop > 0 && walk_.failed_cycles >= options_.failed_cycles_to_stop) {
    return StopReason::kAllNeighborhoodsFailed;
  }
  if (walk_.consecutive_hits >= options_.max_consecutive_cache_hits) {
    return StopReason::kSpaceExhausted;
  }
  if (free_.empty()) return StopReason::kNoFreeVariables;
  if (options_.objective.sense == ObjectiveSense::kTarget &&
      state_.history[state_.best_index].feasible &&
      -state_.best_score <= options_.objective.target_tolerance) {
    return StopReason::kTargetReached;
  }
  if (state_.evaluations >= options_.max_evaluations) return StopReason::kEvaluationBudget;
  if (options_.max_seconds > 0 && Elapsed() >= options_.max_seconds) return StopReason::kTimeBudget;
  if (callbacks_.cancelled && callbacks_.cancelled()) return StopReason::kCancelled;
  return std::nullopt;
}

absl::StatusOr<VnsResult> Search::Run() {
  while (true) {
    if (const std::optional<StopReason> stop = StopBeforeStep()) {
      DropAhead();
      state_.stop_reason = *stop;
      state_.elapsed_seconds = Elapsed();
      return std::move(state_);
    }
    const int neighborhood = walk_.neighborhood;
    FENESTRA_ASSIGN_OR_RETURN(step, Evaluate(Propose(walk_), neighborhood));
    step.elapsed_seconds = Elapsed();
    Record(std::move(step));
    Publish();
  }
}

}  // namespace

double Score(const Objective& objective, double value) {
  switch (objective.sense) {
    case ObjectiveSense::kMaximize:
      return value;
    case ObjectiveSense::kMinimize:
      return -value;
    case ObjectiveSense::kTarget:
      return -std::abs(value - objective.target);
  }
  return value;
}

double ConstraintExcess(const Constraint& constraint, double value) {
  const double excess = constraint.bound == ConstraintBound::kAtMost ? value - constraint.value
                                                                     : constraint.value - value;
  return std::max(0.0, excess);
}

bool ConstraintsBroken(std::span<const Constraint> constraints, std::span<const Estimated> values,
                       double standard_errors) {
  for (size_t c = 0; c < constraints.size() && c < values.size(); ++c) {
    if (ConstraintExcess(constraints[c], values[c].value) >
        standard_errors * values[c].standard_error) {
      return true;
    }
  }
  return false;
}

double ConstraintViolation(std::span<const Constraint> constraints,
                           std::span<const Estimated> values) {
  double violation = 0;
  for (size_t c = 0; c < constraints.size() && c < values.size(); ++c) {
    violation += ConstraintExcess(constraints[c], values[c].value);
  }
  return violation;
}

bool Feasible(const Constraints& constraints, const Evaluation& evaluation) {
  return !ConstraintsBroken(constraints.bounds, evaluation.constraints,
                            constraints.standard_errors);
}

bool Improves(const VnsOptions& options, const VnsRecord& candidate, const VnsRecord& incumbent) {
  if (candidate.evaluation.partial) return false;
  if (candidate.feasible != incumbent.feasible) return candidate.feasible;
  if (!candidate.feasible) return candidate.violation < incumbent.violation;
  const double margin = std::max(
      options.min_improvement,
      options.min_improvement_standard_errors *
          std::hypot(candidate.evaluation.standard_error, incumbent.evaluation.standard_error));
  return candidate.score > incumbent.score + margin;
}

std::vector<Neighborhood> DefaultNeighborhoods() {
  return {{1, 0.02}, {1, 0.1}, {2, 0.1}, {2, 0.3}, {Neighborhood::kAllVariables, 0.5}};
}

std::string_view StopReasonName(StopReason reason) {
  switch (reason) {
    case StopReason::kEvaluationBudget:
      return "evaluation_budget";
    case StopReason::kTimeBudget:
      return "time_budget";
    case StopReason::kAllNeighborhoodsFailed:
      return "all_neighborhoods_failed";
    case StopReason::kTargetReached:
      return "target_reached";
    case StopReason::kCancelled:
      return "cancelled";
    case StopReason::kNoFreeVariables:
      return "no_free_variables";
    case StopReason::kSpaceExhausted:
      return "space_exhausted";
  }
  return "";
}

absl::StatusOr<VnsResult> RunVns(std::span<const DesignVariable> variables,
                                 const ObjectiveFunction& objective, const VnsOptions& options,
                                 const VnsCallbacks& callbacks, const VnsResult* resume) {
  const BatchObjective each = [&](const std::vector<std::vector<double>>& designs) {
    std::vector<absl::StatusOr<Evaluation>> evaluations;
    for (const std::vector<double>& x : designs) evaluations.push_back(objective(x));
    return evaluations;
  };
  return RunVns(variables, each, options, callbacks, resume);
}

absl::StatusOr<VnsResult> RunVns(std::span<const DesignVariable> variables,
                                 const BatchObjective& objective, const VnsOptions& options,
                                 const VnsCallbacks& callbacks, const VnsResult* resume) {
  FENESTRA_RETURN_IF_ERROR(CheckInputs(variables, options));
  Search search(variables, objective, options, callbacks);
  if (resume != nullptr) {
    FENESTRA_RETURN_IF_ERROR(search.Replay(*resume));
  } else {
    if (callbacks.cancelled && callbacks.cancelled()) {
      return absl::CancelledError("cancelled before the first evaluation");
    }
    FENESTRA_RETURN_IF_ERROR(search.Start());
  }
  return search.Run();
}

absl::Status CheckVnsResume(std::span<const DesignVariable> variables, const VnsOptions& options,
                            const VnsResult& resume) {
  FENESTRA_RETURN_IF_ERROR(CheckInputs(variables, options));
  const BatchObjective unused;  // a replay never evaluates
  return Search(variables, unused, options, {}).Replay(resume);
}

}  // namespace fenestra
