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
#include "core/common/status_macros.h"

namespace fenestra {
namespace {

using Clock = std::chrono::steady_clock;

double SecondsSince(Clock::time_point start) {
  return std::chrono::duration<double>(Clock::now() - start).count();
}

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
  if (!(o.max_seconds >= 0) || o.failed_cycles_to_stop < 0 || !(o.min_improvement >= 0) ||
      !(o.min_improvement_standard_errors >= 0) || o.max_consecutive_cache_hits < 1 ||
      !(o.objective.target_tolerance >= 0) || !std::isfinite(o.objective.target)) {
    return absl::InvalidArgumentError(
        "max_seconds, failed_cycles_to_stop, min_improvement, "
        "min_improvement_standard_errors and target_tolerance must not be negative, "
        "max_consecutive_cache_hits must be positive and the target finite");
  }
  return absl::OkStatus();
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

// One run of the search: its state between steps (the result so far and where it goes on),
// and the steps.
class Search {
 public:
  Search(std::span<const DesignVariable> variables, const ObjectiveFunction& objective,
         const VnsOptions& options, const VnsCallbacks& callbacks)
      : variables_(variables),
        objective_(objective),
        options_(options),
        callbacks_(callbacks),
        start_time_(Clock::now()),
        rng_(options.seed) {
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
  std::vector<double> Propose();
  absl::StatusOr<VnsRecord> Evaluate(std::vector<double> x, int neighborhood);
  void Record(VnsRecord record);
  void Publish();
  std::optional<StopReason> StopBeforeStep();

  std::span<const DesignVariable> variables_;
  const ObjectiveFunction& objective_;
  const VnsOptions& options_;
  const VnsCallbacks& callbacks_;
  const Clock::time_point start_time_;
  double resumed_seconds_ = 0;  // the clock at the checkpoint resumed from
  std::vector<size_t> free_;    // indices of the free variables
  std::mt19937_64 rng_;
  VnsResult state_;
  std::map<std::vector<double>, int> cache_;  // design -> history index of its evaluation
  int neighborhood_ = 0;                      // of the next step
  int failed_cycles_ = 0;
  int consecutive_hits_ = 0;
};

std::vector<double> Search::StartDesign() const {
  std::vector<double> start;
  for (const DesignVariable& v : variables_) start.push_back(v.start);
  return start;
}

// Moves v randomly chosen free variables of the incumbent (v and the radius of the current
// neighborhood).
std::vector<double> Search::Propose() {
  const Neighborhood& n = options_.neighborhoods[neighborhood_];
  const size_t count = n.variables == Neighborhood::kAllVariables
                           ? free_.size()
                           : std::min(free_.size(), static_cast<size_t>(n.variables));
  std::vector<size_t> order = free_;
  std::vector<double> x = state_.best_x;
  for (size_t c = 0; c < count; ++c) {
    std::swap(order[c], order[c + UniformIndex(rng_, order.size() - c)]);
    const DesignVariable& v = variables_[order[c]];
    const double delta = (2 * Uniform01(rng_) - 1) * n.radius_fraction * (v.upper - v.lower);
    x[order[c]] = Constrain(v, x[order[c]] + delta, options_.boundary);
  }
  return x;
}

// The step at design `x`: looked up in the cache, else evaluated.
absl::StatusOr<VnsRecord> Search::Evaluate(std::vector<double> x, int neighborhood) {
  VnsRecord record;
  record.index = static_cast<int>(state_.history.size());
  record.neighborhood = neighborhood;
  if (auto hit = cache_.find(x); hit != cache_.end()) {
    const VnsRecord& earlier = state_.history[hit->second];
    record.evaluation = earlier.evaluation;
    record.score = earlier.score;
    record.cached = true;
  } else {
    const Clock::time_point t0 = Clock::now();
    absl::StatusOr<Evaluation> evaluation = objective_(x);
    record.evaluation_seconds = SecondsSince(t0);
    if (!evaluation.ok()) {
      return absl::Status(evaluation.status().code(),
                          absl::StrCat("evaluating x = (", absl::StrJoin(x, ", "),
                                       "): ", evaluation.status().message()));
    }
    if (!std::isfinite(evaluation->value) || !std::isfinite(evaluation->standard_error)) {
      return absl::InvalidArgumentError(absl::StrCat("the objective returned ", evaluation->value,
                                                     " +- ", evaluation->standard_error,
                                                     " at x = (", absl::StrJoin(x, ", "), ")"));
    }
    record.evaluation = *std::move(evaluation);
    record.score = Score(options_.objective, record.evaluation.value);
  }
  record.x = std::move(x);
  return record;
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
    const VnsRecord& best = state_.history[state_.best_index];
    const double margin =
        std::max(options_.min_improvement,
                 options_.min_improvement_standard_errors *
                     std::hypot(record.evaluation.standard_error, best.evaluation.standard_error));
    record.improved = !record.evaluation.partial && record.score > best.score + margin;
    consecutive_hits_ = record.cached ? consecutive_hits_ + 1 : 0;
    if (record.improved) {
      ++state_.improvements;
      neighborhood_ = 0;
      failed_cycles_ = 0;
    } else if (++neighborhood_ == static_cast<int>(options_.neighborhoods.size())) {
      neighborhood_ = 0;
      ++failed_cycles_;
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
    if (done.neighborhood != (i == 0 ? -1 : neighborhood_)) {
      return differs(absl::StrCat("neighborhood ", done.neighborhood));
    }
    if (done.x != (i == 0 ? StartDesign() : Propose())) {
      return differs(absl::StrCat("design (", absl::StrJoin(done.x, ", "), ")"));
    }
    if (!std::isfinite(done.evaluation.value) || !std::isfinite(done.evaluation.standard_error) ||
        !std::isfinite(done.evaluation_seconds) || !std::isfinite(done.elapsed_seconds)) {
      return differs("a value or time that is not finite");
    }
    const auto hit = cache_.find(done.x);
    if (done.cached != (hit != cache_.end())) return differs("cache hit");
    if (done.cached) {
      const Evaluation& earlier = state_.history[hit->second].evaluation;
      if (done.evaluation.value != earlier.value ||
          done.evaluation.standard_error != earlier.standard_error ||
          done.evaluation.partial != earlier.partial) {
        return differs("a cache hit with another value than its design's evaluation");
      }
    }
    VnsRecord step = done;
    step.score = Score(options_.objective, step.evaluation.value);
    Record(std::move(step));
    if (state_.history.back().improved != done.improved) return differs("improvement");
  }
  resumed_seconds_ = so_far.elapsed_seconds;
  state_.elapsed_seconds = so_far.elapsed_seconds;
  return absl::OkStatus();
}

// The stopping rules, checked before each step but the start.
std::optional<StopReason> Search::StopBeforeStep() {
  if (options_.failed_cycles_to_stop > 0 && failed_cycles_ >= options_.failed_cycles_to_stop) {
    return StopReason::kAllNeighborhoodsFailed;
  }
  if (consecutive_hits_ >= options_.max_consecutive_cache_hits) return StopReason::kSpaceExhausted;
  if (free_.empty()) return StopReason::kNoFreeVariables;
  if (options_.objective.sense == ObjectiveSense::kTarget &&
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
      state_.stop_reason = *stop;
      state_.elapsed_seconds = Elapsed();
      return std::move(state_);
    }
    FENESTRA_ASSIGN_OR_RETURN(step, Evaluate(Propose(), neighborhood_));
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
  const ObjectiveFunction unused;  // a replay never evaluates
  return Search(variables, unused, options, {}).Replay(resume);
}

}  // namespace fenestra
