// The search with constraints (vns.h, "Constraints" in core/README.md): Deb's feasibility
// rules, the constrained optimum on an analytic objective, lookahead and resume.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <numbers>
#include <set>
#include <string>
#include <vector>

#include "absl/strings/str_cat.h"
#include "core/optimize/vns.h"
#include "tests/core/optimize/same_search.h"

namespace fenestra {
namespace {

// A step with `score` (maximized), standing against the constraints as given.
VnsRecord Step(double score, bool feasible, double violation, double standard_error = 0) {
  VnsRecord r;
  r.score = score;
  r.evaluation.value = score;
  r.evaluation.standard_error = standard_error;
  r.feasible = feasible;
  r.violation = violation;
  return r;
}

// A bowl with its top (100) at (0.3, 0.7) and, as its one constraint's metric, g = 100 (x + y)
// with standard error kConstraintError (noise of that size on g). With g at most 80 the top
// is infeasible and the constrained optimum is the top's projection onto x + y = 0.8,
// (0.2, 0.6), where the bowl is 80.
constexpr double kConstraintError = 0.2;
absl::StatusOr<Evaluation> ConstrainedBowl(const std::vector<double>& x) {
  const double dx = x[0] - 0.3, dy = x[1] - 0.7;
  Evaluation e;
  e.value = 100 - 1000 * (dx * dx + dy * dy);
  e.constraints = {{100 * (x[0] + x[1]) + kConstraintError * DesignNoise(x, 1), kConstraintError}};
  return e;
}

VnsOptions AtMost80(int evaluations) {
  VnsOptions options;
  options.max_evaluations = evaluations;
  options.failed_cycles_to_stop = 0;
  options.constraints.bounds = {{ConstraintBound::kAtMost, 80}};
  return options;
}

TEST(ConstraintsTest, ExcessAndBreaking) {
  const Constraint at_most{ConstraintBound::kAtMost, 10}, at_least{ConstraintBound::kAtLeast, 50};
  EXPECT_EQ(ConstraintExcess(at_most, 12.5), 2.5);
  EXPECT_EQ(ConstraintExcess(at_most, 9), 0);
  EXPECT_EQ(ConstraintExcess(at_least, 47), 3);
  EXPECT_EQ(ConstraintExcess(at_least, 51), 0);
  const std::vector<Constraint> both = {at_most, at_least};
  // Beyond a bound by at most k standard errors: not broken
  EXPECT_FALSE(ConstraintsBroken(both, std::vector<Estimated>{{11, 1}, {60, 1}}, 1));
  EXPECT_TRUE(ConstraintsBroken(both, std::vector<Estimated>{{11.5, 1}, {60, 1}}, 1));
  EXPECT_FALSE(ConstraintsBroken(both, std::vector<Estimated>{{11.5, 1}, {60, 1}}, 2));
  EXPECT_TRUE(ConstraintsBroken(both, std::vector<Estimated>{{10, 1}, {47, 1}}, 2));
  // An exact metric (ASE: standard error 0) breaks its bound by any excess
  EXPECT_TRUE(ConstraintsBroken(both, std::vector<Estimated>{{10.001, 0}, {60, 0}}, 100));
  EXPECT_FALSE(ConstraintsBroken(both, std::vector<Estimated>{{10, 0}, {50, 0}}, 1));
  EXPECT_EQ(ConstraintViolation(both, std::vector<Estimated>{{12, 1}, {47, 1}}), 5);
  EXPECT_EQ(ConstraintViolation(both, std::vector<Estimated>{{9, 1}, {51, 1}}), 0);
  // No constraints: every design is feasible
  EXPECT_TRUE(Feasible(Constraints(), Evaluation()));
}

// Deb's rules: feasible beats infeasible whatever the scores; two infeasible designs by their
// violation; two feasible ones by their scores with the min_improvement margin; a partial
// evaluation never.
TEST(ConstraintsTest, ComparisonFollowsDebsRules) {
  const VnsOptions options;
  EXPECT_TRUE(Improves(options, Step(10, true, 0), Step(90, false, 3)));
  EXPECT_FALSE(Improves(options, Step(90, false, 3), Step(10, true, 0)));
  EXPECT_TRUE(Improves(options, Step(10, false, 2), Step(90, false, 3)));
  EXPECT_FALSE(Improves(options, Step(90, false, 3), Step(10, false, 2)));
  EXPECT_FALSE(Improves(options, Step(90, false, 3), Step(10, false, 3)));  // a tie
  EXPECT_TRUE(Improves(options, Step(51, true, 0), Step(50, true, 0)));
  EXPECT_FALSE(Improves(options, Step(50, true, 0), Step(50, true, 0)));
  // A feasible design within k standard errors of a bound has a violation, which feasible
  // designs do not compare by
  EXPECT_TRUE(Improves(options, Step(51, true, 0.5), Step(50, true, 0)));
  VnsOptions margin;
  margin.min_improvement = 2;
  EXPECT_FALSE(Improves(margin, Step(51, true, 0), Step(50, true, 0)));
  EXPECT_TRUE(Improves(margin, Step(51, true, 0), Step(50, false, 1)));  // no margin needed
  margin.min_improvement = 0;
  margin.min_improvement_standard_errors = 1;
  EXPECT_FALSE(Improves(margin, Step(51, true, 0, 1), Step(50, true, 0, 1)));
  EXPECT_TRUE(Improves(margin, Step(52, true, 0, 1), Step(50, true, 0, 1)));
  VnsRecord partial = Step(10, true, 0);
  partial.evaluation.partial = true;
  EXPECT_FALSE(Improves(options, partial, Step(5, false, 9)));
}

// The unconstrained top breaks the constraint; the search ends on the boundary of the
// feasible region at the constrained optimum, and every move of the incumbent followed the
// rules.
TEST(ConstraintsTest, FindsTheConstrainedOptimumOnTheBoundary) {
  const std::vector<DesignVariable> vars = {BoxVariable("x", 0, 1, 0), BoxVariable("y", 0, 1, 0)};
  VnsOptions free = AtMost80(300);
  free.constraints = {};
  const ObjectiveFunction bowl = [](const std::vector<double>& x) {
    absl::StatusOr<Evaluation> e = ConstrainedBowl(x);
    e->constraints.clear();
    return e;
  };
  absl::StatusOr<VnsResult> unconstrained = RunVns(vars, bowl, free);
  ASSERT_TRUE(unconstrained.ok()) << unconstrained.status();
  EXPECT_NEAR(unconstrained->best_x[0] + unconstrained->best_x[1], 1.0, 0.03);

  for (const double start : {0.0, 1.0}) {  // feasible, and infeasible (g = 200)
    SCOPED_TRACE(absl::StrCat("start ", start));
    std::vector<DesignVariable> from = vars;
    from[0].start = from[1].start = start;
    absl::StatusOr<VnsResult> r = RunVns(from, ConstrainedBowl, AtMost80(300));
    ASSERT_TRUE(r.ok()) << r.status();
    EXPECT_EQ(r->history.front().feasible, start == 0);
    const VnsRecord& best = r->history[r->best_index];
    EXPECT_TRUE(best.feasible);
    // Within the k = 1 standard error the rule allows (and the bound's noise), on the boundary
    ASSERT_EQ(r->best.constraints.size(), 1u);
    EXPECT_LE(r->best.constraints[0].value, 80 + kConstraintError);
    EXPECT_GT(r->best.constraints[0].value, 79);
    EXPECT_NEAR(r->best_x[0], 0.2, 0.03);
    EXPECT_NEAR(r->best_x[1], 0.6, 0.03);
    EXPECT_NEAR(r->best.value, 80, 1.5);
    // The incumbent's standing never got worse
    const VnsRecord* incumbent = nullptr;
    for (const VnsRecord& step : r->history) {
      if (!step.improved) continue;
      if (incumbent != nullptr) {
        EXPECT_TRUE(step.feasible >= incumbent->feasible);
        if (!step.feasible) {
          EXPECT_LT(step.violation, incumbent->violation);
        }
        if (step.feasible && incumbent->feasible) {
          EXPECT_GT(step.score, incumbent->score);
        }
      }
      incumbent = &step;
    }
  }
}

// Target mode stops at the target only with a feasible incumbent.
TEST(ConstraintsTest, TargetIsReachedOnlyByAFeasibleDesign) {
  const std::vector<DesignVariable> vars = {BoxVariable("x", 0, 1, 0), BoxVariable("y", 0, 1, 0)};
  VnsOptions options = AtMost80(300);
  options.failed_cycles_to_stop = 10;
  options.objective = {ObjectiveSense::kTarget, 99, 0.5};  // reached only near the top
  absl::StatusOr<VnsResult> r = RunVns(vars, ConstrainedBowl, options);
  ASSERT_TRUE(r.ok()) << r.status();
  EXPECT_NE(r->stop_reason, StopReason::kTargetReached);
  EXPECT_TRUE(r->history[r->best_index].feasible);
  options.objective.target = 75;  // feasible designs reach it
  r = RunVns(vars, ConstrainedBowl, options);
  ASSERT_TRUE(r.ok()) << r.status();
  EXPECT_EQ(r->stop_reason, StopReason::kTargetReached);
  EXPECT_TRUE(r->history[r->best_index].feasible);
  EXPECT_LE(std::abs(r->best.value - 75), 0.5);
}

// The objective must return one value per constraint, each finite.
TEST(ConstraintsTest, RefusesMissingOrBadConstraintValues) {
  const std::vector<DesignVariable> vars = {BoxVariable("x", 0, 1, 0), BoxVariable("y", 0, 1, 0)};
  const ObjectiveFunction none = [](const std::vector<double>&) {
    return absl::StatusOr<Evaluation>(Evaluation());
  };
  absl::StatusOr<VnsResult> r = RunVns(vars, none, AtMost80(10));
  EXPECT_EQ(r.status().code(), absl::StatusCode::kInvalidArgument);
  const ObjectiveFunction nan = [](const std::vector<double>&) {
    Evaluation e;
    e.constraints = {{std::nan(""), 1}};
    return absl::StatusOr<Evaluation>(e);
  };
  EXPECT_EQ(RunVns(vars, nan, AtMost80(10)).status().code(), absl::StatusCode::kInvalidArgument);
  VnsOptions bad = AtMost80(10);
  bad.constraints.standard_errors = 0;
  EXPECT_EQ(RunVns(vars, ConstrainedBowl, bad).status().code(), absl::StatusCode::kInvalidArgument);
  bad = AtMost80(10);
  bad.constraints.bounds[0].value = INFINITY;
  EXPECT_EQ(RunVns(vars, ConstrainedBowl, bad).status().code(), absl::StatusCode::kInvalidArgument);
}

// Partial (raced-out) evaluations on one side, as in vns_test.cpp's lookahead tests, and a
// gridded variable for cache hits.
absl::StatusOr<Evaluation> PartlyRaced(const std::vector<double>& x) {
  absl::StatusOr<Evaluation> e = ConstrainedBowl(x);
  e->value += DesignNoise(x, 2);
  e->standard_error = 1;
  e->partial = x[0] > 0.9;
  return e;
}

std::vector<DesignVariable> GriddedVariables() {
  std::vector<DesignVariable> vars = {BoxVariable("x", 0, 1, 0.9), BoxVariable("y", 0, 1, 0.9)};
  vars[1].step = 0.05;
  return vars;
}

// Designs evaluated ahead, several at a time: the steps of the search one design at a time,
// infeasible incumbents (the start) and moves by violation included.
TEST(ConstraintsTest, LookaheadTakesTheStepsOfOneAtATime) {
  const std::vector<DesignVariable> vars = GriddedVariables();
  VnsOptions options = AtMost80(120);
  options.seed = 7;
  absl::StatusOr<VnsResult> one = RunVns(vars, PartlyRaced, options);
  ASSERT_TRUE(one.ok()) << one.status();
  int infeasible_moves = 0, infeasible = 0;
  for (const VnsRecord& step : one->history) {
    infeasible += step.feasible ? 0 : 1;
    infeasible_moves += step.improved && !step.feasible ? 1 : 0;
  }
  ASSERT_GT(infeasible_moves, 1);  // the start and moves by violation
  ASSERT_GT(infeasible, infeasible_moves);
  ASSERT_GT(one->cache_hits, 0);
  ASSERT_TRUE(one->history[one->best_index].feasible);
  for (const int lookahead : {2, 5, 16}) {
    SCOPED_TRACE(absl::StrCat("lookahead ", lookahead));
    options.lookahead = lookahead;
    const BatchObjective batch = [](const std::vector<std::vector<double>>& designs) {
      std::vector<absl::StatusOr<Evaluation>> out;
      for (const std::vector<double>& x : designs) out.push_back(PartlyRaced(x));
      return out;
    };
    absl::StatusOr<VnsResult> ahead = RunVns(vars, batch, options);
    ASSERT_TRUE(ahead.ok()) << ahead.status();
    ExpectSameSearch(*one, *ahead);
    EXPECT_GT(ahead->discarded, 0);
  }
}

// Resumed from the checkpoint of every step, a constrained search ends as the uninterrupted
// one; feasibility is taken again from the constraints' values the history holds, and a
// history with other values is not this search's.
TEST(ConstraintsTest, ResumedFromAnyStepTheSearchEndsAsTheUninterruptedOne) {
  const std::vector<DesignVariable> vars = GriddedVariables();
  const VnsOptions options = AtMost80(60);
  std::vector<VnsResult> checkpoints;
  VnsCallbacks callbacks;
  callbacks.checkpoint = [&](const VnsResult& so_far) { checkpoints.push_back(so_far); };
  absl::StatusOr<VnsResult> full = RunVns(vars, PartlyRaced, options, callbacks);
  ASSERT_TRUE(full.ok()) << full.status();
  for (VnsResult checkpoint : checkpoints) {
    SCOPED_TRACE(checkpoint.history.size());
    // Only the values are read back: the standing is recomputed
    for (VnsRecord& step : checkpoint.history) {
      step.feasible = true;
      step.violation = 0;
    }
    std::set<std::vector<double>> evaluated;
    for (const VnsRecord& step : checkpoint.history) evaluated.insert(step.x);
    const ObjectiveFunction counted = [&](const std::vector<double>& x) {
      EXPECT_TRUE(evaluated.insert(x).second) << "evaluated again";
      return PartlyRaced(x);
    };
    absl::StatusOr<VnsResult> resumed = RunVns(vars, counted, options, {}, &checkpoint);
    ASSERT_TRUE(resumed.ok()) << resumed.status();
    ExpectSameSearch(*resumed, *full);
  }

  VnsResult other = checkpoints.back();
  for (VnsRecord& step : other.history) step.evaluation.constraints.clear();
  absl::StatusOr<VnsResult> refused = RunVns(vars, PartlyRaced, options, {}, &other);
  EXPECT_EQ(refused.status().code(), absl::StatusCode::kInvalidArgument);
  EXPECT_NE(refused.status().message().find("step 0 differs from this search's (0 constraint"),
            std::string::npos)
      << refused.status();
  // Without the constraint the same history moves the incumbent elsewhere
  VnsOptions unconstrained = options;
  unconstrained.constraints = {};
  EXPECT_FALSE(CheckVnsResume(vars, unconstrained, other).ok());
}

}  // namespace
}  // namespace fenestra
