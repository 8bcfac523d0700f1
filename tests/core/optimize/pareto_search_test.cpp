// The Pareto search (core/optimize/pareto_search.h) on ZDT1, whose front is known (f2 = 1 -
// sqrt(f1), hypervolume 2/3 below (1, 1)): the archive's hypervolume within 1% of it, a
// resume mid-generation giving the same search, a replay that checks a history, and errors
// in the objectives the search does not hide. Seeds are fixed.
#include "core/optimize/pareto_search.h"

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "core/metrics/metric_errors.h"
#include "core/optimize/nsga2.h"

namespace fenestra {
namespace {

// ZDT1 as metrics: f1 the mean UDI, f2 the sDA, both minimized, exact (no error).
const BatchObjective kZdt1 = [](const std::vector<std::vector<double>>& xs) {
  std::vector<absl::StatusOr<Evaluation>> out;
  for (const std::vector<double>& x : xs) {
    double sum = 0;
    for (size_t i = 1; i < x.size(); ++i) sum += x[i];
    const double g = 1 + 9 * sum / static_cast<double>(x.size() - 1);
    AnnualMetricsEstimate m;
    m.value.scene.udi_mean_percent = x[0];
    m.value.scene.sda_percent = g * (1 - std::sqrt(x[0] / g));
    Evaluation e;
    e.value = x[0];
    e.payload = m;
    out.push_back(std::move(e));
  }
  return out;
};

std::vector<DesignVariable> Box(int n) {
  std::vector<DesignVariable> v;
  for (int i = 0; i < n; ++i) v.push_back({"x" + std::to_string(i), 0, 1, 0.5});
  return v;
}

ParetoOptions Zdt1Options(int population, int generations) {
  ParetoOptions o;
  o.objectives = {{SceneMetric::kUdiMean, false}, {SceneMetric::kSda, false}};
  o.population = population;
  o.max_evaluations = population * generations;
  o.dominance_z = 0;
  o.seed = 11;
  return o;
}

double FrontHypervolume(const ParetoOutcome& out) {
  std::vector<Nsga2Member> front;
  for (const int s : out.front) {
    front.push_back({{}, {out.objectives[s][0].value, out.objectives[s][1].value}, {}});
  }
  return Hypervolume2d(front, 1, 1);
}

TEST(ParetoSearchTest, RecoversTheFrontOfZdt1) {
  const std::vector<DesignVariable> vars = Box(10);
  absl::StatusOr<ParetoOutcome> out = RunPareto(vars, kZdt1, Zdt1Options(100, 200));
  ASSERT_TRUE(out.ok()) << out.status();
  EXPECT_EQ(out->generations, 200);
  EXPECT_EQ(out->search.history.size(), 20000u);
  EXPECT_NEAR(FrontHypervolume(*out), 2.0 / 3.0, 0.01 * 2.0 / 3.0);
  for (size_t g = 1; g < out->hypervolume.size(); ++g) {
    EXPECT_GE(out->hypervolume[g], out->hypervolume[g - 1]);
  }
  EXPECT_GE(out->front.size(), 50u);
}

TEST(ParetoSearchTest, ResumeMidGenerationIsTheSameSearch) {
  const std::vector<DesignVariable> vars = Box(5);
  const ParetoOptions options = Zdt1Options(20, 6);
  ParetoOutcome at_50;
  ParetoCallbacks callbacks;
  callbacks.step = [&](const ParetoOutcome& so_far) {
    if (so_far.search.history.size() == 50) at_50 = so_far;
  };
  absl::StatusOr<ParetoOutcome> whole = RunPareto(vars, kZdt1, options, callbacks);
  ASSERT_TRUE(whole.ok()) << whole.status();
  ASSERT_EQ(at_50.search.history.size(), 50u);
  // The history alone, as a checkpoint holds it: designs, values, objectives
  for (VnsRecord& r : at_50.search.history) r.evaluation.payload.reset();
  absl::StatusOr<ParetoOutcome> replay = RunPareto(vars, {}, options, {}, &at_50);
  ASSERT_TRUE(replay.ok()) << replay.status();
  absl::StatusOr<ParetoOutcome> resumed = RunPareto(vars, kZdt1, options, {}, &at_50);
  ASSERT_TRUE(resumed.ok()) << resumed.status();
  ASSERT_EQ(resumed->search.history.size(), whole->search.history.size());
  for (size_t s = 0; s < whole->search.history.size(); ++s) {
    EXPECT_EQ(resumed->search.history[s].x, whole->search.history[s].x) << "step " << s;
    EXPECT_EQ(resumed->objectives[s][1].value, whole->objectives[s][1].value);
  }
  EXPECT_EQ(resumed->front, whole->front);
  EXPECT_EQ(resumed->hypervolume, whole->hypervolume);
  // A history this search does not make
  at_50.search.history[30].x[2] += 0.01;
  EXPECT_EQ(RunPareto(vars, {}, options, {}, &at_50).status().code(),
            absl::StatusCode::kInvalidArgument);
}

TEST(ParetoSearchTest, AnObjectiveErrorStopsTheSearch) {
  const BatchObjective failing = [](const std::vector<std::vector<double>>& xs) {
    std::vector<absl::StatusOr<Evaluation>> out(xs.size(), absl::InternalError("no light"));
    return out;
  };
  absl::StatusOr<ParetoOutcome> out = RunPareto(Box(2), failing, Zdt1Options(4, 2));
  EXPECT_EQ(out.status().code(), absl::StatusCode::kInternal);
  EXPECT_EQ(RunPareto(Box(2), kZdt1, Zdt1Options(5, 2)).status().code(),
            absl::StatusCode::kInvalidArgument);  // odd population
}

}  // namespace
}  // namespace fenestra
