#include "core/optimize/vns.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <map>
#include <random>
#include <utility>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_join.h"

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

}  // namespace

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
                                 const VnsCallbacks& callbacks) {
  if (absl::Status ok = CheckInputs(variables, options); !ok.ok()) return ok;
  const Clock::time_point start_time = Clock::now();
  std::mt19937_64 rng(options.seed);
  std::vector<size_t> free;
  for (size_t i = 0; i < variables.size(); ++i) {
    if (IsFree(variables[i])) free.push_back(i);
  }

  VnsResult result;
  std::map<std::vector<double>, int> cache;  // design -> history index of its evaluation
  auto cancelled = [&] { return callbacks.cancelled && callbacks.cancelled(); };

  // Evaluates (or looks up) one design and appends it to the history
  auto step = [&](std::vector<double> x, int neighborhood) -> absl::StatusOr<VnsRecord*> {
    VnsRecord record;
    record.index = static_cast<int>(result.history.size());
    record.neighborhood = neighborhood;
    if (auto hit = cache.find(x); hit != cache.end()) {
      const VnsRecord& earlier = result.history[hit->second];
      record.evaluation = earlier.evaluation;
      record.score = earlier.score;
      record.cached = true;
      ++result.cache_hits;
    } else {
      const Clock::time_point t0 = Clock::now();
      absl::StatusOr<Evaluation> evaluation = objective(x);
      record.evaluation_seconds = SecondsSince(t0);
      result.evaluation_seconds += record.evaluation_seconds;
      ++result.evaluations;
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
      record.score = Score(options.objective, record.evaluation.value);
      cache.emplace(x, record.index);
    }
    record.x = std::move(x);
    result.history.push_back(std::move(record));
    return &result.history.back();
  };

  auto report = [&] {
    if (!callbacks.progress) return;
    VnsProgress progress;
    progress.evaluations = result.evaluations;
    progress.max_evaluations = options.max_evaluations;
    progress.current = &result.history.back();
    progress.best = &result.history[result.best_index];
    progress.elapsed_seconds = result.history.back().elapsed_seconds;
    const double per_evaluation = progress.elapsed_seconds / std::max(result.evaluations, 1);
    progress.remaining_seconds = per_evaluation * (options.max_evaluations - result.evaluations);
    if (options.max_seconds > 0) {
      progress.remaining_seconds = std::clamp(options.max_seconds - progress.elapsed_seconds, 0.0,
                                              progress.remaining_seconds);
    }
    callbacks.progress(progress);
  };

  auto target_reached = [&] {
    return options.objective.sense == ObjectiveSense::kTarget &&
           -result.history[result.best_index].score <= options.objective.target_tolerance;
  };

  // Evaluate the start
  if (cancelled()) return absl::CancelledError("cancelled before the first evaluation");
  std::vector<double> start;
  for (const DesignVariable& v : variables) start.push_back(v.start);
  {
    auto first = step(start, -1);
    if (!first.ok()) return first.status();
    (*first)->improved = true;
    (*first)->elapsed_seconds = SecondsSince(start_time);
  }
  result.best_index = 0;
  report();

  // Search the neighborhoods of the incumbent
  const int neighborhoods = static_cast<int>(options.neighborhoods.size());
  int k = 0;
  int failed_cycles = 0;
  int consecutive_hits = 0;
  StopReason stop;
  while (true) {
    if (free.empty()) {
      stop = StopReason::kNoFreeVariables;
      break;
    }
    if (target_reached()) {
      stop = StopReason::kTargetReached;
      break;
    }
    if (result.evaluations >= options.max_evaluations) {
      stop = StopReason::kEvaluationBudget;
      break;
    }
    if (options.max_seconds > 0 && SecondsSince(start_time) >= options.max_seconds) {
      stop = StopReason::kTimeBudget;
      break;
    }
    if (cancelled()) {
      stop = StopReason::kCancelled;
      break;
    }

    // Move v randomly chosen free variables of the incumbent
    const Neighborhood& n = options.neighborhoods[k];
    const size_t count = n.variables == Neighborhood::kAllVariables
                             ? free.size()
                             : std::min(free.size(), static_cast<size_t>(n.variables));
    std::vector<size_t> order = free;
    std::vector<double> x = result.history[result.best_index].x;
    for (size_t c = 0; c < count; ++c) {
      std::swap(order[c], order[c + UniformIndex(rng, order.size() - c)]);
      const DesignVariable& v = variables[order[c]];
      const double delta = (2 * Uniform01(rng) - 1) * n.radius_fraction * (v.upper - v.lower);
      x[order[c]] = Constrain(v, x[order[c]] + delta, options.boundary);
    }

    auto current = step(std::move(x), k);
    if (!current.ok()) return current.status();
    VnsRecord& record = **current;
    const VnsRecord& best = result.history[result.best_index];
    const double margin =
        std::max(options.min_improvement,
                 options.min_improvement_standard_errors *
                     std::hypot(record.evaluation.standard_error, best.evaluation.standard_error));
    record.improved = record.score > best.score + margin;
    record.elapsed_seconds = SecondsSince(start_time);
    consecutive_hits = record.cached ? consecutive_hits + 1 : 0;
    if (record.improved) {
      result.best_index = record.index;
      ++result.improvements;
      k = 0;
      failed_cycles = 0;
    } else if (++k == neighborhoods) {
      k = 0;
      ++failed_cycles;
    }
    report();
    if (options.failed_cycles_to_stop > 0 && failed_cycles >= options.failed_cycles_to_stop) {
      stop = StopReason::kAllNeighborhoodsFailed;
      break;
    }
    if (consecutive_hits >= options.max_consecutive_cache_hits) {
      stop = StopReason::kSpaceExhausted;
      break;
    }
  }

  const VnsRecord& best = result.history[result.best_index];
  result.best_x = best.x;
  result.best = best.evaluation;
  result.best_score = best.score;
  result.stop_reason = stop;
  result.elapsed_seconds = SecondsSince(start_time);
  return result;
}

}  // namespace fenestra
