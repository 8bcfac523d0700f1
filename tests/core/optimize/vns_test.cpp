#include "core/optimize/vns.h"

#include <gtest/gtest.h>

#include <any>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstring>
#include <numbers>
#include <set>
#include <string>
#include <thread>
#include <vector>

#include "absl/strings/str_cat.h"
#include "tests/core/optimize/same_search.h"

namespace fenestra {
namespace {

Evaluation Value(double value, double standard_error = 0) {
  Evaluation e;
  e.value = value;
  e.standard_error = standard_error;
  return e;
}

// A bowl with its top (100) at (0.3, 0.7).
absl::StatusOr<Evaluation> Bowl(const std::vector<double>& x) {
  const double dx = x[0] - 0.3, dy = x[1] - 0.7;
  return Value(100 - 1000 * (dx * dx + dy * dy));
}

TEST(VnsTest, FindsTheTopOfASmoothBowl) {
  const std::vector<DesignVariable> vars = {BoxVariable("x", 0, 1, 0), BoxVariable("y", 0, 1, 0)};
  VnsOptions options;
  options.max_evaluations = 200;
  absl::StatusOr<VnsResult> r = RunVns(vars, Bowl, options);
  ASSERT_TRUE(r.ok()) << r.status();
  EXPECT_NEAR(r->best_x[0], 0.3, 0.03);
  EXPECT_NEAR(r->best_x[1], 0.7, 0.03);
  EXPECT_GT(r->best.value, 99.5);
  EXPECT_LE(r->evaluations, 200);
  EXPECT_EQ(r->history[r->best_index].x, r->best_x);
  EXPECT_TRUE(r->history[r->best_index].improved);
  EXPECT_EQ(r->history.front().neighborhood, -1);
  EXPECT_EQ(r->history.front().x, (std::vector<double>{0, 0}));
}

// A partial evaluation (a candidate racing stopped) never becomes the incumbent, however
// high its value, and a resume replays that.
TEST(VnsTest, PartialEvaluationsNeverBecomeTheIncumbent) {
  const std::vector<DesignVariable> vars = {BoxVariable("x", 0, 1, 0.5)};
  VnsOptions options;
  options.max_evaluations = 30;
  options.failed_cycles_to_stop = 0;
  const ObjectiveFunction objective = [](const std::vector<double>& x) {
    // Right of the start: partial and high; left: full, with its top at 0.45
    Evaluation e = Value(x[0] > 0.5 ? 100 + x[0] : 50 - std::abs(x[0] - 0.45));
    e.partial = x[0] > 0.5;
    return absl::StatusOr<Evaluation>(e);
  };
  absl::StatusOr<VnsResult> r = RunVns(vars, objective, options);
  ASSERT_TRUE(r.ok()) << r.status();
  EXPECT_NEAR(r->best_x[0], 0.45, 0.05);
  EXPECT_LT(r->best.value, 51);
  EXPECT_FALSE(r->best.partial);
  int partial = 0;
  for (const VnsRecord& step : r->history) {
    partial += step.evaluation.partial ? 1 : 0;
    if (step.evaluation.partial) {
      EXPECT_FALSE(step.improved);
    }
  }
  EXPECT_GT(partial, 3);
  VnsResult so_far = *r;
  so_far.history.resize(20);
  options.max_evaluations = 40;
  absl::StatusOr<VnsResult> resumed = RunVns(vars, objective, options, {}, &so_far);
  ASSERT_TRUE(resumed.ok()) << resumed.status();
  // A history whose partial step is called full is not this search's
  for (VnsRecord& step : so_far.history) {
    if (step.evaluation.partial && !step.cached) {
      step.evaluation.partial = false;
      break;
    }
  }
  EXPECT_FALSE(RunVns(vars, objective, options, {}, &so_far).ok());
}

// 50 +- 1 on [0.2, 0.8]^2, falling steeply outside.
absl::StatusOr<Evaluation> Plateau(const std::vector<double>& x) {
  double outside = 0;
  for (double v : x) outside += std::max({0.0, 0.2 - v, v - 0.8});
  return Value(50 - 500 * outside + DesignNoise(x), 1.0);
}

TEST(VnsTest, NoisyPlateauStaysOnThePlateauAndReportsTheNoise) {
  const std::vector<DesignVariable> vars = {BoxVariable("x", 0, 1, 0.5),
                                            BoxVariable("y", 0, 1, 0.5)};
  VnsOptions options;
  options.max_evaluations = 100;
  absl::StatusOr<VnsResult> r = RunVns(vars, Plateau, options);
  ASSERT_TRUE(r.ok());
  for (double v : r->best_x) {
    EXPECT_GE(v, 0.2);
    EXPECT_LE(v, 0.8);
  }
  // The best of ~100 noisy draws sits a few errors above the truth, and says so
  EXPECT_LT(r->best.value, 50 + 4.5);
  EXPECT_EQ(r->best.standard_error, 1.0);

  // Asking for a 2-sigma gain keeps the incumbent from chasing the noise
  options.min_improvement_standard_errors = 2;
  absl::StatusOr<VnsResult> strict = RunVns(vars, Plateau, options);
  ASSERT_TRUE(strict.ok());
  EXPECT_LE(strict->improvements, r->improvements);
  EXPECT_LE(strict->improvements, 2);
  EXPECT_LT(strict->best.value, 50 + 4.5);
}

TEST(VnsTest, FixedVariableNeverChanges) {
  std::vector<DesignVariable> vars = {BoxVariable("a", 0, 1, 0), BoxVariable("b", 0, 1, 0.4),
                                      BoxVariable("c", 0, 1, 1)};
  vars[1].fixed = true;
  auto f = [](const std::vector<double>& x) -> absl::StatusOr<Evaluation> {
    return Value(-std::abs(x[0] - 0.5) - std::abs(x[1] - 0.9) - std::abs(x[2] - 0.5));
  };
  VnsOptions options;
  options.max_evaluations = 60;
  absl::StatusOr<VnsResult> r = RunVns(vars, f, options);
  ASSERT_TRUE(r.ok());
  for (const VnsRecord& record : r->history) EXPECT_EQ(record.x[1], 0.4);
  EXPECT_GT(r->improvements, 0);
}

TEST(VnsTest, ZeroWidthRangeBehavesAsFixed) {
  const std::vector<DesignVariable> vars = {BoxVariable("a", 0, 1, 0.5), BoxVariable("w", 2, 2, 2)};
  int calls = 0;
  auto f = [&](const std::vector<double>& x) -> absl::StatusOr<Evaluation> {
    ++calls;
    return Value(x[0]);
  };
  VnsOptions options;
  options.max_evaluations = 30;
  absl::StatusOr<VnsResult> r = RunVns(vars, f, options);
  ASSERT_TRUE(r.ok());
  for (const VnsRecord& record : r->history) EXPECT_EQ(record.x[1], 2);
  EXPECT_EQ(calls, r->evaluations);

  // Nothing free at all: only the start is evaluated
  const std::vector<DesignVariable> none = {BoxVariable("w", 2, 2, 2)};
  absl::StatusOr<VnsResult> only = RunVns(none, f, options);
  ASSERT_TRUE(only.ok());
  EXPECT_EQ(only->evaluations, 1);
  EXPECT_EQ(only->stop_reason, StopReason::kNoFreeVariables);
}

TEST(VnsTest, BudgetOfOneEvaluatesOnlyTheStart) {
  const std::vector<DesignVariable> vars = {BoxVariable("x", 0, 1, 0.1),
                                            BoxVariable("y", 0, 1, 0.9)};
  VnsOptions options;
  options.max_evaluations = 1;
  absl::StatusOr<VnsResult> r = RunVns(vars, Bowl, options);
  ASSERT_TRUE(r.ok());
  ASSERT_EQ(r->history.size(), 1u);
  EXPECT_EQ(r->evaluations, 1);
  EXPECT_EQ(r->best_x, (std::vector<double>{0.1, 0.9}));
  EXPECT_EQ(r->stop_reason, StopReason::kEvaluationBudget);
  EXPECT_EQ(r->improvements, 0);
}

TEST(VnsTest, TargetModeReachesTheTarget) {
  // UDI-like response rising to 40% at x = 0.6 and falling after: 32% has two solutions
  auto f = [](const std::vector<double>& x) -> absl::StatusOr<Evaluation> {
    return Value(40 - 100 * std::abs(x[0] - 0.6), 0.1);
  };
  const std::vector<DesignVariable> vars = {BoxVariable("alpha", 0, 1, 0)};
  VnsOptions options;
  options.objective.sense = ObjectiveSense::kTarget;
  options.objective.target = 32;
  options.max_evaluations = 150;
  absl::StatusOr<VnsResult> r = RunVns(vars, f, options);
  ASSERT_TRUE(r.ok());
  EXPECT_NEAR(r->best.value, 32, 0.5);
  EXPECT_NEAR(std::abs(r->best_x[0] - 0.6), 0.08, 0.005);
  EXPECT_NEAR(r->best_score, -std::abs(r->best.value - 32), 1e-12);

  options.objective.target_tolerance = 0.5;
  absl::StatusOr<VnsResult> tolerant = RunVns(vars, f, options);
  ASSERT_TRUE(tolerant.ok());
  EXPECT_EQ(tolerant->stop_reason, StopReason::kTargetReached);
  EXPECT_LE(std::abs(tolerant->best.value - 32), 0.5);
  EXPECT_LT(tolerant->evaluations, r->evaluations);
}

TEST(VnsTest, MinimizeMode) {
  auto f = [](const std::vector<double>& x) -> absl::StatusOr<Evaluation> {
    return Value((x[0] - 0.25) * (x[0] - 0.25));
  };
  const std::vector<DesignVariable> vars = {BoxVariable("x", 0, 1, 1)};
  VnsOptions options;
  options.objective.sense = ObjectiveSense::kMinimize;
  absl::StatusOr<VnsResult> r = RunVns(vars, f, options);
  ASSERT_TRUE(r.ok());
  EXPECT_NEAR(r->best_x[0], 0.25, 0.02);
}

TEST(VnsTest, SameSeedSameRunOtherSeedOtherRun) {
  const std::vector<DesignVariable> vars = {BoxVariable("x", 0, 1, 0), BoxVariable("y", 0, 1, 0),
                                            BoxVariable("z", -1, 1, 0)};
  VnsOptions options;
  options.max_evaluations = 50;
  options.seed = 42;
  absl::StatusOr<VnsResult> a = RunVns(vars, Plateau, options);
  absl::StatusOr<VnsResult> b = RunVns(vars, Plateau, options);
  options.seed = 43;
  absl::StatusOr<VnsResult> c = RunVns(vars, Plateau, options);
  ASSERT_TRUE(a.ok() && b.ok() && c.ok());
  ASSERT_EQ(a->history.size(), b->history.size());
  for (size_t i = 0; i < a->history.size(); ++i) {
    EXPECT_EQ(a->history[i].x, b->history[i].x);
    EXPECT_EQ(a->history[i].neighborhood, b->history[i].neighborhood);
    EXPECT_EQ(a->history[i].improved, b->history[i].improved);
  }
  EXPECT_NE(a->history[1].x, c->history[1].x);
}

TEST(VnsTest, RepeatedDesignIsServedFromTheCache) {
  // A grid of 5 x 5 designs: the search soon proposes designs it has seen
  std::vector<DesignVariable> vars = {BoxVariable("x", 0, 1, 0), BoxVariable("y", 0, 1, 0)};
  for (DesignVariable& v : vars) v.step = 0.25;
  std::set<std::vector<double>> seen;
  int calls = 0;
  auto f = [&](const std::vector<double>& x) -> absl::StatusOr<Evaluation> {
    ++calls;
    EXPECT_TRUE(seen.insert(x).second) << "evaluated twice";
    return Bowl(x);
  };
  VnsOptions options;
  options.max_evaluations = 100;
  options.failed_cycles_to_stop = 0;
  options.max_consecutive_cache_hits = 50;
  absl::StatusOr<VnsResult> r = RunVns(vars, f, options);
  ASSERT_TRUE(r.ok());
  EXPECT_EQ(calls, r->evaluations);
  EXPECT_LE(calls, 25);
  EXPECT_GT(r->cache_hits, 0);
  EXPECT_EQ(static_cast<int>(r->history.size()), r->evaluations + r->cache_hits);
  for (const VnsRecord& record : r->history) {
    for (double v : record.x) EXPECT_EQ(std::fmod(v, 0.25), 0.0);
    if (record.cached) {
      EXPECT_EQ(record.evaluation_seconds, 0);
    }
  }
  EXPECT_EQ(r->best_x, (std::vector<double>{0.25, 0.75}));
  EXPECT_EQ(r->stop_reason, StopReason::kSpaceExhausted);
  EXPECT_EQ(StopReasonName(r->stop_reason), "space_exhausted");
}

TEST(VnsTest, CancellationStopsAtACheckpoint) {
  const std::vector<DesignVariable> vars = {BoxVariable("x", 0, 1, 0), BoxVariable("y", 0, 1, 0)};
  std::atomic<bool> cancel = false;
  int reports = 0;
  VnsCallbacks callbacks;
  callbacks.progress = [&](const VnsProgress& p) {
    ++reports;
    EXPECT_NE(p.current, nullptr);
    EXPECT_GE(p.best->score, p.current->score - (p.current->improved ? 0 : 1e300));
    EXPECT_GE(p.remaining_seconds, 0);
    if (p.evaluations == 5) cancel = true;
  };
  callbacks.cancelled = [&] { return cancel.load(); };
  absl::StatusOr<VnsResult> r = RunVns(vars, Bowl, {}, callbacks);
  ASSERT_TRUE(r.ok());
  EXPECT_EQ(r->stop_reason, StopReason::kCancelled);
  EXPECT_EQ(r->evaluations, 5);
  EXPECT_EQ(reports, static_cast<int>(r->history.size()));

  // Cancelled before anything was evaluated
  absl::StatusOr<VnsResult> none = RunVns(vars, Bowl, {}, callbacks);
  EXPECT_EQ(none.status().code(), absl::StatusCode::kCancelled);
}

TEST(VnsTest, ProgressReportsTheIncumbent) {
  const std::vector<DesignVariable> vars = {BoxVariable("x", 0, 1, 0), BoxVariable("y", 0, 1, 0)};
  double best_so_far = -1e300;
  int last_evaluations = 0;
  VnsCallbacks callbacks;
  callbacks.progress = [&](const VnsProgress& p) {
    EXPECT_GE(p.best->score, best_so_far);
    EXPECT_GE(p.best->score, p.current->score);
    best_so_far = p.best->score;
    EXPECT_GE(p.evaluations, last_evaluations);
    last_evaluations = p.evaluations;
    EXPECT_EQ(p.max_evaluations, 40);
    EXPECT_GE(p.elapsed_seconds, 0);
  };
  VnsOptions options;
  options.max_evaluations = 40;
  absl::StatusOr<VnsResult> r = RunVns(vars, Bowl, options, callbacks);
  ASSERT_TRUE(r.ok());
  EXPECT_EQ(best_so_far, r->best_score);
}

TEST(VnsTest, StopsWhenAllNeighborhoodsFail) {
  const std::vector<DesignVariable> vars = {BoxVariable("x", 0, 1, 0.5)};
  auto flat = [](const std::vector<double>&) -> absl::StatusOr<Evaluation> { return Value(1); };
  VnsOptions options;
  options.failed_cycles_to_stop = 1;
  absl::StatusOr<VnsResult> r = RunVns(vars, flat, options);
  ASSERT_TRUE(r.ok());
  EXPECT_EQ(r->stop_reason, StopReason::kAllNeighborhoodsFailed);
  EXPECT_EQ(r->evaluations, 1 + static_cast<int>(options.neighborhoods.size()));

  options.failed_cycles_to_stop = 0;  // run to the budget
  options.max_evaluations = 40;
  absl::StatusOr<VnsResult> budget = RunVns(vars, flat, options);
  ASSERT_TRUE(budget.ok());
  EXPECT_EQ(budget->stop_reason, StopReason::kEvaluationBudget);
  EXPECT_EQ(budget->evaluations, 40);
}

TEST(VnsTest, TimeBudget) {
  const std::vector<DesignVariable> vars = {BoxVariable("x", 0, 1, 0)};
  auto slow = [](const std::vector<double>& x) -> absl::StatusOr<Evaluation> {
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
    return Value(x[0]);
  };
  VnsOptions options;
  options.max_seconds = 0.05;
  options.failed_cycles_to_stop = 0;
  absl::StatusOr<VnsResult> r = RunVns(vars, slow, options);
  ASSERT_TRUE(r.ok());
  EXPECT_EQ(r->stop_reason, StopReason::kTimeBudget);
  EXPECT_LT(r->evaluations, 20);
  EXPECT_GE(r->elapsed_seconds, 0.05);
  EXPECT_GE(r->evaluation_seconds, 0.005 * r->evaluations);
}

TEST(VnsTest, ReflectKeepsMovesInsideTheBox) {
  const std::vector<DesignVariable> vars = {BoxVariable("x", -1, 1, 1),
                                            BoxVariable("y", 0, 0.5, 0)};
  VnsOptions options;
  options.boundary = BoundaryRule::kReflect;
  options.neighborhoods = {{2, 3.0}};
  options.failed_cycles_to_stop = 0;
  options.max_evaluations = 100;
  auto f = [](const std::vector<double>& x) -> absl::StatusOr<Evaluation> {
    EXPECT_GE(x[0], -1);
    EXPECT_LE(x[0], 1);
    EXPECT_GE(x[1], 0);
    EXPECT_LE(x[1], 0.5);
    return Value(x[0] + x[1]);
  };
  absl::StatusOr<VnsResult> r = RunVns(vars, f, options);
  ASSERT_TRUE(r.ok());
  EXPECT_EQ(r->evaluations, 100);
}

TEST(VnsTest, ObjectiveErrorAbortsTheRun) {
  const std::vector<DesignVariable> vars = {BoxVariable("x", 0, 1, 0)};
  int calls = 0;
  auto f = [&](const std::vector<double>& x) -> absl::StatusOr<Evaluation> {
    if (++calls == 3) return absl::ResourceExhaustedError("out of device memory");
    return Value(x[0]);
  };
  absl::StatusOr<VnsResult> r = RunVns(vars, f);
  EXPECT_EQ(r.status().code(), absl::StatusCode::kResourceExhausted);
  EXPECT_NE(r.status().message().find("out of device memory"), std::string::npos);
  EXPECT_EQ(calls, 3);

  auto nan = [](const std::vector<double>&) -> absl::StatusOr<Evaluation> {
    return Value(std::nan(""));
  };
  EXPECT_EQ(RunVns(vars, nan).status().code(), absl::StatusCode::kInvalidArgument);
}

TEST(VnsTest, RejectsBadVariablesAndOptions) {
  EXPECT_FALSE(RunVns({}, Bowl).ok());
  const std::vector<DesignVariable> outside = {BoxVariable("x", 0, 1, 2)};
  EXPECT_EQ(RunVns(outside, Bowl).status().code(), absl::StatusCode::kInvalidArgument);
  const std::vector<DesignVariable> inverted = {BoxVariable("x", 1, 0, 0.5)};
  EXPECT_FALSE(RunVns(inverted, Bowl).ok());
  const std::vector<DesignVariable> ok = {BoxVariable("x", 0, 1, 0), BoxVariable("y", 0, 1, 0)};
  VnsOptions no_budget;
  no_budget.max_evaluations = 0;
  EXPECT_FALSE(RunVns(ok, Bowl, no_budget).ok());
  VnsOptions bad_neighborhood;
  bad_neighborhood.neighborhoods = {{1, 0}};
  EXPECT_FALSE(RunVns(ok, Bowl, bad_neighborhood).ok());
  for (const int lookahead : {0, -1, kMaxLookahead + 1}) {
    VnsOptions bad_lookahead;
    bad_lookahead.lookahead = lookahead;
    EXPECT_EQ(RunVns(ok, Bowl, bad_lookahead).status().code(), absl::StatusCode::kInvalidArgument);
  }
}

// A choice among `count` values 0, 1, ..., count - 1 (a categorical variable, as a finish).
DesignVariable ChoiceVariable(std::string name, int count, int start) {
  DesignVariable v = BoxVariable(std::move(name), 0, count - 1, start);
  v.step = 1;
  v.categorical = true;
  return v;
}

// A categorical variable moves to another of its values at every move, at most the
// neighborhood's radius of its range away (one value at least), and stays on its values; a
// grid variable of the same values mostly rounds back to where it was.
TEST(VnsTest, ChoiceMovesToAnotherValueWithinTheRadius) {
  const std::vector<DesignVariable> vars = {BoxVariable("x", 0, 1, 0.5), ChoiceVariable("c", 6, 0)};
  VnsOptions options;
  options.max_evaluations = 200;
  options.failed_cycles_to_stop = 0;
  options.max_consecutive_cache_hits = 100'000;
  const ObjectiveFunction objective = [](const std::vector<double>& x) {
    return Value(-std::abs(x[1] - 3) + 0.1 * x[0]);  // best: value 3, x at 1
  };
  absl::StatusOr<VnsResult> r = RunVns(vars, objective, options);
  ASSERT_TRUE(r.ok()) << r.status();
  EXPECT_EQ(r->best_x[1], 3);
  std::vector<double> incumbent = r->history.front().x;
  int moves = 0;
  for (const VnsRecord& step : r->history) {
    const double c = step.x[1];
    EXPECT_EQ(c, std::round(c));
    EXPECT_GE(c, 0);
    EXPECT_LE(c, 5);
    if (step.neighborhood >= 0 && c != incumbent[1]) {
      ++moves;
      const double radius = options.neighborhoods[step.neighborhood].radius_fraction;
      EXPECT_LE(std::abs(c - incumbent[1]), std::max(1.0, std::round(radius * 5)));
    }
    if (step.improved) incumbent = step.x;
  }
  EXPECT_GT(moves, 20);

  // Two values: each move is to the other one, so the search evaluates both at once
  const std::vector<DesignVariable> two = {ChoiceVariable("c", 2, 0)};
  options.failed_cycles_to_stop = 1;
  absl::StatusOr<VnsResult> both = RunVns(
      two, [](const std::vector<double>& x) { return Value(x[0]); }, options);
  ASSERT_TRUE(both.ok()) << both.status();
  EXPECT_EQ(both->evaluations, 2);
  EXPECT_EQ(both->best_x, (std::vector<double>{1}));
  EXPECT_EQ(both->history[1].x, (std::vector<double>{1}));
  for (size_t i = 2; i < both->history.size(); ++i) {
    EXPECT_EQ(both->history[i].x, (std::vector<double>{0}));
    EXPECT_TRUE(both->history[i].cached);
  }
  // The same two values as a plain grid: the fine neighborhoods round back to the start
  std::vector<DesignVariable> grid = two;
  grid[0].categorical = false;
  absl::StatusOr<VnsResult> rounded = RunVns(
      grid, [](const std::vector<double>& x) { return Value(x[0]); }, options);
  ASSERT_TRUE(rounded.ok()) << rounded.status();
  EXPECT_TRUE(rounded->history[1].cached);
  // A choice needs a grid
  std::vector<DesignVariable> no_step = two;
  no_step[0].step = 0;
  EXPECT_EQ(RunVns(no_step, Bowl, options).status().code(), absl::StatusCode::kInvalidArgument);
}

// Resuming: a noisy bowl over a continuous variable starting on its bound, a gridded one
// (cache hits) and a fixed one; the payload is the design's first coordinate.
absl::StatusOr<Evaluation> NoisyBowl(const std::vector<double>& x) {
  Evaluation e = Value(
      10 - 30 * (std::pow(x[0] - 0.7, 2) + std::pow(x[1] - 0.35, 2)) + 0.2 * DesignNoise(x), 0.2);
  e.payload = x[0];
  return e;
}

std::vector<DesignVariable> ResumeVariables() {
  std::vector<DesignVariable> vars = {BoxVariable("a", 0, 1, 0), BoxVariable("b", 0, 1, 0.5),
                                      BoxVariable("c", 2, 3, 2.5)};
  vars[1].step = 0.05;
  vars[2].fixed = true;
  return vars;
}

struct ResumeCase {
  std::string name;
  VnsOptions options;
  StopReason stop;  // how the uninterrupted search ends
  std::vector<DesignVariable> variables = ResumeVariables();
};

// Every stopping rule a resumed search must meet where the uninterrupted one did.
std::vector<ResumeCase> ResumeCases() {
  std::vector<ResumeCase> cases;
  VnsOptions budget;
  budget.max_evaluations = 60;
  budget.failed_cycles_to_stop = 0;
  budget.min_improvement_standard_errors = 0.5;
  budget.seed = 5;
  cases.push_back({"budget", budget, StopReason::kEvaluationBudget});
  VnsOptions failed;
  failed.failed_cycles_to_stop = 2;
  cases.push_back({"failed cycles", failed, StopReason::kAllNeighborhoodsFailed});
  VnsOptions target;
  target.objective = {ObjectiveSense::kTarget, 7, 0.05};
  target.boundary = BoundaryRule::kReflect;
  cases.push_back({"target", target, StopReason::kTargetReached});
  VnsOptions exhausted;
  exhausted.failed_cycles_to_stop = 0;
  exhausted.max_consecutive_cache_hits = 6;
  std::vector<DesignVariable> gridded = ResumeVariables();
  gridded[0].step = 0.1;
  cases.push_back({"space exhausted", exhausted, StopReason::kSpaceExhausted, gridded});
  std::vector<DesignVariable> chosen = ResumeVariables();
  chosen[2] = ChoiceVariable("c", 5, 0);
  cases.push_back({"a choice", budget, StopReason::kEvaluationBudget, chosen});
  return cases;
}

// Resumed from the checkpoint of every step, the search ends as the uninterrupted one: the
// same steps, incumbent, counts and stopping rule, and no design evaluated twice.
TEST(VnsTest, ResumedFromAnyStepTheSearchEndsAsTheUninterruptedOne) {
  for (const ResumeCase& c : ResumeCases()) {
    SCOPED_TRACE(c.name);
    const std::vector<DesignVariable>& vars = c.variables;
    std::vector<VnsResult> checkpoints;
    VnsCallbacks callbacks;
    callbacks.checkpoint = [&](const VnsResult& so_far) { checkpoints.push_back(so_far); };
    absl::StatusOr<VnsResult> full = RunVns(vars, NoisyBowl, c.options, callbacks);
    ASSERT_TRUE(full.ok()) << full.status();
    ASSERT_EQ(full->stop_reason, c.stop) << StopReasonName(full->stop_reason);
    ASSERT_EQ(checkpoints.size(), full->history.size());
    EXPECT_GT(full->cache_hits, 0);
    EXPECT_GT(full->improvements, 1);

    for (const VnsResult& checkpoint : checkpoints) {
      const size_t done = checkpoint.history.size();
      SCOPED_TRACE(done);
      EXPECT_EQ(checkpoint.best_x, checkpoint.history[checkpoint.best_index].x);
      std::set<std::vector<double>> evaluated;
      for (const VnsRecord& record : checkpoint.history) evaluated.insert(record.x);
      int calls = 0;
      auto counted = [&](const std::vector<double>& x) {
        ++calls;
        EXPECT_TRUE(evaluated.insert(x).second) << "evaluated again";
        return NoisyBowl(x);
      };
      size_t handed_out = done;
      VnsCallbacks resumed_callbacks;
      resumed_callbacks.checkpoint = [&](const VnsResult& so_far) {
        EXPECT_EQ(so_far.history.size(), ++handed_out);
      };
      absl::StatusOr<VnsResult> resumed =
          RunVns(vars, counted, c.options, resumed_callbacks, &checkpoint);
      ASSERT_TRUE(resumed.ok()) << resumed.status();
      ExpectSameSearch(*resumed, *full);
      EXPECT_EQ(calls, full->evaluations - checkpoint.evaluations);
      EXPECT_EQ(std::any_cast<double>(resumed->best.payload), resumed->best_x[0]);
    }
  }
}

// Cancelled right after a checkpoint, resumed, cancelled and resumed again: the search of
// an uninterrupted run.
TEST(VnsTest, CancelledSearchGoesOnFromItsLastCheckpoint) {
  const std::vector<DesignVariable> vars = ResumeVariables();
  const VnsOptions options = ResumeCases()[0].options;
  absl::StatusOr<VnsResult> full = RunVns(vars, NoisyBowl, options);
  ASSERT_TRUE(full.ok()) << full.status();

  // Stopped once the search has made `stop_at` steps
  VnsResult last;
  size_t stop_at = 7;
  VnsCallbacks callbacks;
  callbacks.checkpoint = [&](const VnsResult& so_far) { last = so_far; };
  callbacks.cancelled = [&] { return last.history.size() >= stop_at; };
  absl::StatusOr<VnsResult> first = RunVns(vars, NoisyBowl, options, callbacks);
  ASSERT_TRUE(first.ok()) << first.status();
  EXPECT_EQ(first->stop_reason, StopReason::kCancelled);
  ASSERT_EQ(last.history.size(), 7u);
  EXPECT_EQ(first->history.size(), 7u);

  const VnsResult after_first = last;
  stop_at = 30;
  absl::StatusOr<VnsResult> second = RunVns(vars, NoisyBowl, options, callbacks, &after_first);
  ASSERT_TRUE(second.ok()) << second.status();
  EXPECT_EQ(second->stop_reason, StopReason::kCancelled);
  ASSERT_EQ(last.history.size(), 30u);

  const VnsResult after_second = last;
  stop_at = full->history.size() + 1;
  absl::StatusOr<VnsResult> third = RunVns(vars, NoisyBowl, options, callbacks, &after_second);
  ASSERT_TRUE(third.ok()) << third.status();
  ExpectSameSearch(*third, *full);
}

// The clock goes on from the checkpoint's, and so does the time budget.
TEST(VnsTest, ResumedClockGoesOnFromTheCheckpoint) {
  const std::vector<DesignVariable> vars = ResumeVariables();
  VnsOptions options = ResumeCases()[0].options;
  VnsResult so_far;
  VnsCallbacks callbacks;
  callbacks.checkpoint = [&](const VnsResult& s) { so_far = s; };
  callbacks.cancelled = [&] { return so_far.history.size() >= 5; };
  ASSERT_TRUE(RunVns(vars, NoisyBowl, options, callbacks).ok());
  so_far.elapsed_seconds = 1000;

  absl::StatusOr<VnsResult> resumed = RunVns(vars, NoisyBowl, options, {}, &so_far);
  ASSERT_TRUE(resumed.ok()) << resumed.status();
  EXPECT_EQ(resumed->stop_reason, StopReason::kEvaluationBudget);
  for (size_t i = 5; i < resumed->history.size(); ++i) {
    EXPECT_GE(resumed->history[i].elapsed_seconds, 1000);
  }
  EXPECT_GE(resumed->elapsed_seconds, 1000);

  // Spent at the checkpoint: nothing more is evaluated
  options.max_seconds = 1000;
  int calls = 0;
  auto counted = [&](const std::vector<double>& x) {
    ++calls;
    return NoisyBowl(x);
  };
  absl::StatusOr<VnsResult> spent = RunVns(vars, counted, options, {}, &so_far);
  ASSERT_TRUE(spent.ok()) << spent.status();
  EXPECT_EQ(spent->stop_reason, StopReason::kTimeBudget);
  EXPECT_EQ(calls, 0);
  EXPECT_EQ(spent->history.size(), 5u);
}

// A history that the search does not make is refused, naming the step and what differs.
TEST(VnsTest, ResumeRefusesAHistoryOfAnotherSearch) {
  const std::vector<DesignVariable> vars = ResumeVariables();
  const VnsOptions options = ResumeCases()[0].options;
  VnsResult so_far;
  VnsCallbacks callbacks;
  callbacks.checkpoint = [&](const VnsResult& s) { so_far = s; };
  absl::StatusOr<VnsResult> full = RunVns(vars, NoisyBowl, options, callbacks);
  ASSERT_TRUE(full.ok()) << full.status();
  int first_hit = -1, first_failure = -1;
  for (const VnsRecord& r : so_far.history) {
    if (r.cached && first_hit < 0) first_hit = r.index;
    if (!r.improved && !r.cached && first_failure < 0) first_failure = r.index;
  }
  ASSERT_GT(first_hit, 0);
  ASSERT_GT(first_failure, 0);

  auto refused = [&](const VnsResult& bad, const VnsOptions& o, const std::string& says) {
    int calls = 0;
    auto counted = [&](const std::vector<double>& x) {
      ++calls;
      return NoisyBowl(x);
    };
    absl::StatusOr<VnsResult> r = RunVns(vars, counted, o, {}, &bad);
    EXPECT_EQ(r.status().code(), absl::StatusCode::kInvalidArgument) << says;
    EXPECT_NE(r.status().message().find(says), std::string::npos) << r.status();
    EXPECT_EQ(CheckVnsResume(vars, o, bad).message(), r.status().message());
    EXPECT_EQ(calls, 0);
  };
  EXPECT_TRUE(CheckVnsResume(vars, options, so_far).ok());

  VnsOptions other_seed = options;
  other_seed.seed = 6;
  refused(so_far, other_seed, "step 1 differs from this search's (design (");
  VnsOptions other_neighborhoods = options;
  other_neighborhoods.neighborhoods.pop_back();
  refused(so_far, other_neighborhoods, "differs from this search's");
  VnsOptions minimizing = options;
  minimizing.objective.sense = ObjectiveSense::kMinimize;
  refused(so_far, minimizing, "(improvement)");

  VnsResult bad = so_far;
  bad.history[first_failure].improved = true;
  refused(bad, options, absl::StrCat("step ", first_failure, " differs"));
  bad = so_far;
  bad.history[first_hit].evaluation.value += 1;
  refused(bad, options, "a cache hit with another value");
  bad = so_far;
  bad.history[first_hit].cached = false;
  refused(bad, options,
          absl::StrCat("step ", first_hit, " differs from this search's (cache hit)"));
  bad = so_far;
  bad.history[3].neighborhood = (bad.history[3].neighborhood + 1) % 5;
  refused(bad, options, "step 3 differs from this search's (neighborhood");
  bad = so_far;
  bad.history[0].x[1] = 0.55;
  refused(bad, options, "step 0 differs from this search's (design (0, 0.55, 2.5))");
  bad = so_far;
  bad.history[2].x.pop_back();
  refused(bad, options, "step 2 differs");
  bad = so_far;
  bad.history[4].evaluation.standard_error = std::nan("");
  refused(bad, options, "not finite");
  bad = so_far;
  bad.history[4].index = 5;
  refused(bad, options, "step 4 differs from this search's (index 5)");
  bad = so_far;
  bad.elapsed_seconds = -1;
  refused(bad, options, "elapsed_seconds -1 is not a time");
  refused(VnsResult(), options, "no steps");
}
// The steps of a search that evaluates designs ahead, in batches, against one design at a
// time: a noisy bowl over a continuous and a gridded variable (cache hits), with partial
// evaluations on one side (as racing makes them).
class LookaheadTest : public ::testing::Test {
 protected:
  static absl::StatusOr<Evaluation> Objective(const std::vector<double>& x) {
    absl::StatusOr<Evaluation> e = NoisyBowl(x);
    e->partial = x[0] < 0.2;
    return e;
  }
  // The batch objective, keeping every batch it was given
  BatchObjective Batches() {
    return [this](const std::vector<std::vector<double>>& designs) {
      batches_.push_back(designs);
      std::vector<absl::StatusOr<Evaluation>> out;
      for (const std::vector<double>& x : designs) {
        out.push_back(failing_.contains(x) ? absl::InternalError("out of memory") : Objective(x));
      }
      return out;
    };
  }
  static VnsOptions Options(int lookahead) {
    VnsOptions options;
    options.max_evaluations = 120;
    options.failed_cycles_to_stop = 0;
    options.seed = 7;
    options.lookahead = lookahead;
    return options;
  }
  static void ExpectSameSteps(const VnsResult& a, const VnsResult& b) {
    ASSERT_EQ(a.history.size(), b.history.size());
    for (size_t i = 0; i < a.history.size(); ++i) {
      SCOPED_TRACE(absl::StrCat("step ", i));
      EXPECT_EQ(a.history[i].x, b.history[i].x);
      EXPECT_EQ(a.history[i].evaluation.value, b.history[i].evaluation.value);
      EXPECT_EQ(a.history[i].evaluation.partial, b.history[i].evaluation.partial);
      EXPECT_EQ(a.history[i].cached, b.history[i].cached);
      EXPECT_EQ(a.history[i].improved, b.history[i].improved);
      EXPECT_EQ(a.history[i].neighborhood, b.history[i].neighborhood);
    }
    EXPECT_EQ(a.best_x, b.best_x);
    EXPECT_EQ(a.evaluations, b.evaluations);
    EXPECT_EQ(a.improvements, b.improvements);
  }

  std::vector<DesignVariable> vars_ = {BoxVariable("x", 0, 1, 0.1), GridVar("y", 0, 1, 0.5, 0.05)};
  std::vector<std::vector<std::vector<double>>> batches_;
  std::set<std::vector<double>> failing_;

 private:
  static DesignVariable GridVar(std::string name, double lower, double upper, double start,
                                double step) {
    DesignVariable v = BoxVariable(std::move(name), lower, upper, start);
    v.step = step;
    return v;
  }
};

TEST_F(LookaheadTest, TakesTheStepsOfTheSearchOneDesignAtATime) {
  const absl::StatusOr<VnsResult> one = RunVns(vars_, Objective, Options(1));
  ASSERT_TRUE(one.ok()) << one.status();
  ASSERT_GT(one->improvements, 5);
  ASSERT_GT(one->cache_hits, 0);
  for (const int lookahead : {2, 5, 16}) {
    SCOPED_TRACE(absl::StrCat("lookahead ", lookahead));
    batches_.clear();
    const absl::StatusOr<VnsResult> ahead = RunVns(vars_, Batches(), Options(lookahead));
    ASSERT_TRUE(ahead.ok()) << ahead.status();
    ExpectSameSteps(*one, *ahead);
    size_t evaluated = 0, largest = 0;
    for (const auto& batch : batches_) {
      evaluated += batch.size();
      largest = std::max(largest, batch.size());
      EXPECT_LE(batch.size(), static_cast<size_t>(lookahead));
      EXPECT_EQ(std::set<std::vector<double>>(batch.begin(), batch.end()).size(), batch.size());
    }
    EXPECT_EQ(largest, static_cast<size_t>(lookahead));
    EXPECT_LT(batches_.size(), static_cast<size_t>(one->evaluations));
    EXPECT_GT(ahead->discarded, 0);
    EXPECT_EQ(evaluated, static_cast<size_t>(ahead->evaluations + ahead->discarded));
  }
}

// While more than kBusyImprovements of the last kRecentEvaluations evaluations improved, a
// batch holds two thirds of the lookahead (rounded up), else all of it.
TEST_F(LookaheadTest, EvaluatesFewerAtOnceWhileTheSearchImproves) {
  const absl::StatusOr<VnsResult> ahead = RunVns(vars_, Batches(), Options(3));
  ASSERT_TRUE(ahead.ok()) << ahead.status();
  std::set<size_t> sizes;
  for (const auto& batch : batches_) {
    // The step that took the batch's first design, and the evaluations before it
    const auto taken =
        std::find_if(ahead->history.begin(), ahead->history.end(),
                     [&](const VnsRecord& r) { return r.x == batch[0] && !r.cached; });
    ASSERT_NE(taken, ahead->history.end());
    int evaluated = 0, improved = 0;
    for (auto r = std::make_reverse_iterator(taken);
         r != ahead->history.rend() && evaluated < kRecentEvaluations; ++r) {
      if (r->cached) continue;
      ++evaluated;
      improved += r->improved ? 1 : 0;
    }
    const size_t expected = improved > kBusyImprovements ? 2 : 3;
    SCOPED_TRACE(absl::StrCat("step ", taken - ahead->history.begin()));
    // Fewer where the proposals were cached or the budget ends; the start alone
    EXPECT_LE(batch.size(), taken == ahead->history.begin() ? 1 : expected);
    sizes.insert(batch.size());
  }
  EXPECT_TRUE(sizes.contains(2));
  EXPECT_TRUE(sizes.contains(3));
}

// An error in a design evaluated ahead and dropped never reaches the search; one in a design
// a step takes stops it.
TEST_F(LookaheadTest, AnErrorMattersOnlyWhereAStepTakesItsDesign) {
  const absl::StatusOr<VnsResult> ahead = RunVns(vars_, Batches(), Options(4));
  ASSERT_TRUE(ahead.ok()) << ahead.status();
  std::set<std::vector<double>> taken;
  for (const VnsRecord& step : ahead->history) taken.insert(step.x);
  for (const auto& batch : batches_) {
    for (const std::vector<double>& x : batch) {
      if (!taken.contains(x)) failing_.insert(x);
    }
  }
  ASSERT_FALSE(failing_.empty());
  batches_.clear();
  const absl::StatusOr<VnsResult> again = RunVns(vars_, Batches(), Options(4));
  ASSERT_TRUE(again.ok()) << again.status();
  ExpectSameSteps(*ahead, *again);

  failing_ = {ahead->history[40].x};
  ASSERT_FALSE(ahead->history[40].cached);
  const absl::StatusOr<VnsResult> stopped = RunVns(vars_, Batches(), Options(4));
  EXPECT_EQ(stopped.status().code(), absl::StatusCode::kInternal);
  EXPECT_NE(stopped.status().message().find("out of memory"), std::string::npos);
}

// A search with lookahead resumes from a checkpoint of one without, and the other way round.
TEST_F(LookaheadTest, ResumesAcrossLookaheads) {
  const absl::StatusOr<VnsResult> one = RunVns(vars_, Objective, Options(1));
  ASSERT_TRUE(one.ok()) << one.status();
  VnsResult so_far = *one;
  so_far.history.resize(50);
  const absl::StatusOr<VnsResult> resumed = RunVns(vars_, Batches(), Options(6), {}, &so_far);
  ASSERT_TRUE(resumed.ok()) << resumed.status();
  ExpectSameSteps(*one, *resumed);
}

}  // namespace
}  // namespace fenestra
