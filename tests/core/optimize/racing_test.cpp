#include "core/optimize/racing.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <vector>

#include "core/optimize/job.h"

namespace fenestra {
namespace {

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
