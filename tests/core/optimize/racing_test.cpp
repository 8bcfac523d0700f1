#include "core/optimize/racing.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <vector>

#include "core/metrics/metric_errors.h"
#include "core/optimize/job.h"

namespace fenestra {
namespace {

// Design tallies without tracing: one sensor over kHours analysed hours, E_b(h) = tilt x 20 (h
// + 1) lx x (1 + 5% of noise that batch b and hour h share across designs), the noise larger
// where fewer parts are traced. So the tilt scales the light: UDI [100, 3000] lx is 95.5% at
// 0.5, 73% at 1, 36.5% at 2, 18% at 4; UDI exceeded 0%, 25%, 62.5%, 81%; DA 300 lx 70.5% at
// 0.25, 98.5% at 4.
class ScaledTallies : public DesignTallies {
 public:
  static constexpr int kHours = 200;
  using DesignTallies::SetProduct;

  absl::StatusOr<std::vector<HourTally>> Tally(const BlindDesign& design,
                                               const MetricOptions& options, int parts) override {
    rays_ += parts;
    std::vector<Matrix> batches;
    for (int b = 0; b < 8; ++b) {
      Matrix e(1, kHours);
      for (int h = 0; h < kHours; ++h) {
        const uint64_t k =
            (uint64_t(b) * 7919 + h) * 6364136223846793005ull + 1442695040888963407ull;
        const double jitter = static_cast<double>(k >> 11) * 0x1.0p-53 * 2 - 1;  // in [-1, 1)
        const double amplitude = 0.05 * std::sqrt(static_cast<double>(kDesignParts) / parts);
        e(0, h) = design.tilt_rad * 20 * (h + 1) * (1 + amplitude * jitter);
      }
      batches.push_back(std::move(e));
    }
    return TallyBatchVersions(batches, options);
  }
  absl::StatusOr<std::vector<Matrix>> IndoorBatches(const BlindDesign&) override {
    return absl::UnimplementedError("no indoor stage");
  }
  absl::Status SetProduct(const std::vector<Matrix>&, const Matrix&,
                          const DeviceMatrices&) override {
    return absl::OkStatus();
  }
  AnnualProduct* Product() override { return nullptr; }
  bool TracesInParts() const override { return true; }
  uint64_t RaysTraced() const override { return rays_; }

 private:
  uint64_t rays_ = 0;
};

BlindDesign Scaled(double tilt) {
  BlindDesign design;
  design.has_blind = true;
  design.tilt_rad = tilt;
  return design;
}

// A racer maximizing `metric` over ScaledTallies, with UDI exceeded at most 10% where
// `constrained`.
Racer::Setting ScaledSetting(ScaledTallies& tallies, SceneMetric metric, bool constrained) {
  Racer::Setting setting;
  setting.lanes = {&tallies};
  setting.analysed_hours = ScaledTallies::kHours;
  setting.metric = metric;
  if (constrained) {
    setting.constraints.bounds = {{ConstraintBound::kAtMost, 10}};
    setting.constraint_metrics = {SceneMetric::kUdiMeanExceeded};
  }
  return setting;
}

// The racer's evaluation of `tilt` against the incumbent `incumbent_tilt`, evaluated before
// and set with its feasibility as the search takes it.
absl::StatusOr<Evaluation> AgainstIncumbent(Racer& racer, double incumbent_tilt, double tilt,
                                            const Constraints& constraints) {
  absl::StatusOr<Evaluation> incumbent = racer.Evaluate(Scaled(incumbent_tilt));
  if (!incumbent.ok()) return incumbent.status();
  EXPECT_FALSE(incumbent->partial);
  racer.SetIncumbent(Scaled(incumbent_tilt), Feasible(constraints, *incumbent));
  return racer.Evaluate(Scaled(tilt));
}

// Against an infeasible incumbent a round rejects nobody, not even a candidate clearly worse
// by the objective; against a feasible one the same candidate is rejected.
TEST(RacingTest, NoRejectionByObjectiveWhileTheIncumbentIsInfeasible) {
  ScaledTallies tallies;
  Racer racer(ScaledSetting(tallies, SceneMetric::kUdiMean, true));
  ASSERT_TRUE(racer.Races());
  const Constraints constraints{.bounds = {{ConstraintBound::kAtMost, 10}}};
  // Tilt 2: UDI 36.5%, exceeded 62.5% (infeasible); tilt 4: UDI 18%
  absl::StatusOr<Evaluation> worse = AgainstIncumbent(racer, 2, 4, constraints);
  ASSERT_TRUE(worse.ok()) << worse.status();
  EXPECT_FALSE(worse->partial);
  EXPECT_EQ(racer.PathsFraction(Scaled(4)), 1.0);
  ASSERT_EQ(worse->constraints.size(), 1u);
  EXPECT_NEAR(worse->constraints[0].value, 81, 1);
  EXPECT_EQ(racer.stats().rejected, (std::vector<int>{0, 0}));
  // Tilt 0.5: UDI 95.5%, exceeded 0% (feasible)
  worse = AgainstIncumbent(racer, 0.5, 4, constraints);
  ASSERT_TRUE(worse.ok()) << worse.status();
  EXPECT_TRUE(worse->partial);
  EXPECT_LT(racer.PathsFraction(Scaled(4)), 1.0);
  EXPECT_EQ(racer.stats().rejected[0], 1);
}

// Against a feasible incumbent a candidate better by the objective is rejected where a
// round shows it breaking a constraint beyond racing's standard errors; unconstrained it is
// traced in full.
TEST(RacingTest, RejectsACandidateThatBreaksAConstraint) {
  const Constraints constraints{.bounds = {{ConstraintBound::kAtMost, 10}}};
  // Maximizing DA: tilt 0.25 70.5% (exceeded 0%), tilt 4 98.5% (exceeded 81%)
  for (const bool constrained : {true, false}) {
    SCOPED_TRACE(constrained ? "constrained" : "unconstrained");
    ScaledTallies tallies;
    Racer racer(ScaledSetting(tallies, SceneMetric::kDaMean, constrained));
    absl::StatusOr<Evaluation> better =
        AgainstIncumbent(racer, 0.25, 4, constrained ? constraints : Constraints());
    ASSERT_TRUE(better.ok()) << better.status();
    EXPECT_EQ(better->partial, constrained);
    EXPECT_NEAR(better->value, 98.5, 1);
  }
  // The rule itself: only against a feasible incumbent, by the difference or a bound broken
  // by more than settings.standard_errors (4) of the round's standard errors
  const RacingSettings settings;
  const std::vector<double> incumbent = {50, 50, 50, 50}, worse = {40, 40.1, 39.9, 40};
  const std::vector<double> better = {60, 60.1, 59.9, 60};
  const std::vector<Estimated> broken = {{20, 2}}, near = {{17, 2}};
  EXPECT_TRUE(RoundRejects(worse, near, incumbent, true, constraints.bounds, settings));
  EXPECT_FALSE(RoundRejects(worse, near, incumbent, false, constraints.bounds, settings));
  EXPECT_TRUE(RoundRejects(better, broken, incumbent, true, constraints.bounds, settings));
  EXPECT_FALSE(RoundRejects(better, near, incumbent, true, constraints.bounds, settings));
  EXPECT_FALSE(RoundRejects(better, broken, incumbent, false, constraints.bounds, settings));
}

// The paired difference is the difference of the means, with the jackknife error of the
// leave-one-out differences: what both designs share cancels.
TEST(RacingTest, PairedDifferenceCancelsWhatTheDesignsShare) {
  // Versions: the mean, then 4 leave-one-out values; both designs move together by `shared`
  const std::vector<double> shared = {0, 1.0, -2.0, 0.5, 0.5};
  std::vector<double> incumbent, candidate;
  const std::vector<double> own = {0, 0.01, -0.01, 0.02, -0.02};
  for (size_t v = 0; v < shared.size(); ++v) {
    incumbent.push_back(50 + shared[v]);
    candidate.push_back(49 + shared[v] + own[v]);
  }
  const PairedDifference d = Paired(candidate, incumbent);
  EXPECT_DOUBLE_EQ(d.difference, -1.0);
  // sqrt(3/4 sum (own_b - mean)^2), mean 0: sqrt(0.75 * 0.001)
  EXPECT_NEAR(d.standard_error, std::sqrt(0.75 * 0.001), 1e-12);
  RacingSettings settings;
  settings.standard_errors = 5;
  EXPECT_TRUE(Rejects(d, settings));
  EXPECT_FALSE(Rejects({-1.0, 0.5}, settings));  // within 5 standard errors
  EXPECT_FALSE(Rejects({0.3, 0.0}, settings));   // better
}

// Recorded candidate pairs: every candidate of a four-variable search that racing stopped is
// traced to the end as well (the audit), and compared with the incumbent it raced against.
// Racing never stopped one that the full evaluation finds better by more than the standard
// error of the paired difference; it did stop candidates (the check is not empty), and
// every value the search accepted is a full evaluation. The window is one part (as in
// tests/quick_job.h): racing's rounds do not depend on it, and the annual products, most of
// this test's time under the sanitizers with the 12 parts' 3602 columns, are 8 times smaller.
TEST(RacingTest, NeverRejectsACandidateTheFullEvaluationFindsBetter) {
  absl::StatusOr<v1::Job> job =
      ReadJobFile(FENESTRA_SOURCE_DIR "/examples/city_office/four_variables.json");
  ASSERT_TRUE(job.ok()) << job.status();
  job->mutable_budget()->set_max_evaluations(60);
  v1::Sampling& sampling = *job->mutable_sampling();
  sampling.set_indoor_paths_per_sensor(32'000);
  sampling.set_outdoor_paths(48'000);  // per window cell as 576 000 for 12 parts
  sampling.set_backend("cpu");
  sampling.set_final_check(false);
  sampling.set_racing_audit(true);
  sampling.set_window_columns(1);
  sampling.set_window_rows(1);
  absl::StatusOr<PreparedJob> prepared =
      PrepareJob(*job, FENESTRA_SOURCE_DIR "/examples/city_office");
  ASSERT_TRUE(prepared.ok()) << prepared.status();
  absl::StatusOr<v1::JobResult> result = RunJob(*prepared, nullptr);
  ASSERT_TRUE(result.ok()) << result.status();

  ASSERT_TRUE(result->has_racing());
  const v1::Racing& racing = result->racing();
  int raced_out = 0;
  for (const int n : racing.raced_out()) raced_out += n;
  std::printf(
      "%d candidates, %d raced out (%d audited: %d would improve, %d beyond their error); "
      "paths traced %.1f%%\n",
      racing.candidates(), raced_out, racing.audited(), racing.audited_would_improve(),
      racing.audited_better_beyond_error(), 100 * racing.paths_fraction());
  EXPECT_GT(raced_out, 0);
  EXPECT_EQ(racing.audited(), raced_out);
  EXPECT_EQ(racing.audited_better_beyond_error(), 0);
  EXPECT_LT(racing.paths_fraction(), 1.0);
  EXPECT_GT(racing.rays_saved(), 0u);

  int history_raced = 0;
  for (const v1::Evaluation& e : result->history()) {
    if (e.cached()) continue;
    history_raced += e.raced_out() ? 1 : 0;
    if (e.improved()) {
      EXPECT_FALSE(e.raced_out());
      EXPECT_EQ(e.paths_fraction(), 1.0);
    }
    if (e.raced_out()) {
      EXPECT_LT(e.paths_fraction(), 1.0);
    }
  }
  EXPECT_EQ(history_raced, raced_out);
}

// Racing off: every candidate is traced in full, and the result has no racing report.
TEST(RacingTest, OffTracesEveryCandidateInFull) {
  absl::StatusOr<v1::Job> job =
      ReadJobFile(FENESTRA_SOURCE_DIR "/examples/city_office/alpha_max_quick.json");
  ASSERT_TRUE(job.ok()) << job.status();
  job->mutable_budget()->set_max_evaluations(6);
  v1::Sampling& sampling = *job->mutable_sampling();
  sampling.set_indoor_paths_per_sensor(2000);
  sampling.set_outdoor_paths(40000);
  sampling.set_backend("cpu");
  sampling.set_final_check(false);
  sampling.set_racing(false);
  absl::StatusOr<PreparedJob> prepared =
      PrepareJob(*job, FENESTRA_SOURCE_DIR "/examples/city_office");
  ASSERT_TRUE(prepared.ok()) << prepared.status();
  absl::StatusOr<v1::JobResult> result = RunJob(*prepared, nullptr);
  ASSERT_TRUE(result.ok()) << result.status();
  EXPECT_FALSE(result->has_racing());
  for (const v1::Evaluation& e : result->history()) {
    EXPECT_FALSE(e.raced_out());
    if (!e.cached()) {
      EXPECT_EQ(e.paths_fraction(), 1.0);
    }
  }
}

}  // namespace
}  // namespace fenestra
