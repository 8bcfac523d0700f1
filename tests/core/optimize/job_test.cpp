#include "core/optimize/job.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "core/optimize/final_check.h"
#include "tests/example_scene.h"

namespace fenestra {
namespace {

// The quick tilt job (examples/city_office/alpha_max_quick.json: 10^4 indoor paths per
// sensor) with `evaluations`, on the CPU, with the jobs' reflection limits (none, as the
// final check traces); `source_limits`: at most 30 outdoor and 5 indoor reflections, the
// source publication's.
PreparedJob QuickJob(int evaluations, bool source_limits = false) {
  absl::StatusOr<v1::Job> job =
      ReadJobFile(FENESTRA_SOURCE_DIR "/examples/city_office/alpha_max_quick.json");
  EXPECT_TRUE(job.ok()) << job.status();
  job->mutable_budget()->set_max_evaluations(evaluations);
  job->mutable_sampling()->set_backend("cpu");
  if (source_limits) {
    job->mutable_sampling()->set_outdoor_bounces(30);
    job->mutable_sampling()->set_indoor_bounces(5);
  }
  absl::StatusOr<PreparedJob> prepared =
      PrepareJob(*job, FENESTRA_SOURCE_DIR "/examples/city_office");
  EXPECT_TRUE(prepared.ok()) << prepared.status();
  return *prepared;
}

// A job's result with what it reported on the way.
struct Reported {
  v1::JobResult result;
  std::vector<std::string> stages;
  std::vector<JobProgress> progress;
};

Reported RunReporting(const PreparedJob& job, std::function<bool()> cancelled = {}) {
  Reported r;
  JobCallbacks callbacks;
  callbacks.stage = [&](const std::string& stage) { r.stages.push_back(stage); };
  callbacks.progress = [&](const JobProgress& p) { r.progress.push_back(p); };
  callbacks.cancelled = std::move(cancelled);
  absl::StatusOr<v1::JobResult> result = RunJob(job, nullptr, callbacks);
  EXPECT_TRUE(result.ok()) << result.status();
  if (result.ok()) r.result = *std::move(result);
  return r;
}

void Print(const v1::FinalCheck& c) {
  std::printf(
      "two-stage %.3f ± %.3f, one-stage %.3f ± %.3f (%lld paths per sensor, pilot %lld, %.2f s), "
      "difference %+.3f ± %.3f\n",
      c.two_stage().value(), c.two_stage().standard_error(), c.one_stage().value(),
      c.one_stage().standard_error(), static_cast<long long>(c.paths_per_sensor()),
      static_cast<long long>(c.pilot_paths_per_sensor()), c.seconds(), c.difference().value(),
      c.difference().standard_error());
}

TEST(JobTest, WindowPartsAreResolvedAndChecked) {
  absl::StatusOr<v1::Sampling> automatic = ResolveSampling(v1::Sampling());
  ASSERT_TRUE(automatic.ok()) << automatic.status();
  const Scene scene = LoadExample("city_office");
  EXPECT_EQ(SamplingWindowParts(*automatic, scene.window), (WindowParts{4, 3}));
  v1::Sampling columns_only = *automatic;
  columns_only.set_window_columns(2);
  EXPECT_EQ(SamplingWindowParts(columns_only, scene.window), (WindowParts{2, 3}));
  for (const int bad : {-1, 17}) {
    v1::Sampling s;
    s.set_window_rows(bad);
    absl::StatusOr<v1::Sampling> resolved = ResolveSampling(s);
    ASSERT_FALSE(resolved.ok());
    EXPECT_NE(resolved.status().message().find("sampling.window_columns/window_rows"),
              std::string::npos)
        << resolved.status();
  }
  // Enough outdoor paths for every window cell
  v1::Sampling few;
  few.set_outdoor_paths(1000);
  few.set_window_columns(2);
  EXPECT_FALSE(ResolveSampling(few).ok());
}

// A job needs an outdoor path per window cell of its resolved parts and batch
TEST(JobTest, PrepareChecksOutdoorPathsAgainstTheWindowCells) {
  absl::StatusOr<v1::Job> job =
      ReadJobFile(FENESTRA_SOURCE_DIR "/examples/city_office/alpha_max_quick.json");
  ASSERT_TRUE(job.ok()) << job.status();
  job->mutable_sampling()->set_outdoor_paths(20000);  // 4 x 3 x 288 cells x 8 batches: 27648
  absl::StatusOr<PreparedJob> prepared =
      PrepareJob(*job, FENESTRA_SOURCE_DIR "/examples/city_office");
  ASSERT_FALSE(prepared.ok());
  EXPECT_NE(prepared.status().message().find("4x3 window parts"), std::string::npos)
      << prepared.status();
  job->mutable_sampling()->set_window_columns(1);
  job->mutable_sampling()->set_window_rows(1);
  prepared = PrepareJob(*job, FENESTRA_SOURCE_DIR "/examples/city_office");
  EXPECT_TRUE(prepared.ok()) << prepared.status();
}

// The outdoor matrix's key follows the window parts it was traced with, not how they
// were asked for.
TEST(JobTest, OutdoorKeyFollowsTheWindowParts) {
  const Scene scene = LoadExample("city_office");
  v1::Sampling automatic = *ResolveSampling(v1::Sampling());
  v1::Sampling explicit_parts = automatic;
  explicit_parts.set_window_columns(4);
  explicit_parts.set_window_rows(3);
  v1::Sampling whole = automatic;
  whole.set_window_columns(1);
  whole.set_window_rows(1);
  EXPECT_EQ(OutdoorMatrixKey(scene, automatic), OutdoorMatrixKey(scene, explicit_parts));
  EXPECT_NE(OutdoorMatrixKey(scene, automatic), OutdoorMatrixKey(scene, whole));
}

TEST(JobTest, FinalCheckIsOnUnlessTheSamplingSaysNo) {
  absl::StatusOr<v1::Sampling> automatic = ResolveSampling(v1::Sampling());
  ASSERT_TRUE(automatic.ok()) << automatic.status();
  EXPECT_TRUE(automatic->final_check());
  v1::Sampling off;
  off.set_final_check(false);
  absl::StatusOr<v1::Sampling> resolved = ResolveSampling(off);
  ASSERT_TRUE(resolved.ok()) << resolved.status();
  EXPECT_FALSE(resolved->final_check());
}

// Where both methods count the same light (no reflection limits), the one-stage check of the
// best design agrees with the two-stage value within the errors (seed 1).
TEST(JobTest, FinalCheckAgreesWhereBothMethodsCountTheSameLight) {
  const PreparedJob job = QuickJob(8);
  const Reported r = RunReporting(job);
  ASSERT_TRUE(r.result.has_final_check());
  const v1::FinalCheck& c = r.result.final_check();
  Print(c);
  EXPECT_EQ(c.two_stage().value(), r.result.best_value().value());
  EXPECT_EQ(c.two_stage().standard_error(), r.result.best_value().standard_error());
  EXPECT_GT(c.one_stage().value(), 0);
  EXPECT_GT(c.one_stage().standard_error(), 0);
  EXPECT_EQ(c.one_stage().value(), c.one_stage_metrics().udi().value());  // the objective: UDI
  EXPECT_EQ(c.one_stage_metrics().sensor_udi_size(), 9);
  EXPECT_DOUBLE_EQ(c.difference().value(), c.one_stage().value() - c.two_stage().value());
  EXPECT_DOUBLE_EQ(c.difference().standard_error(),
                   std::hypot(c.one_stage().standard_error(), c.two_stage().standard_error()));
  EXPECT_LT(std::abs(c.difference().value()), 4 * c.difference().standard_error());
  EXPECT_EQ(c.disagrees(), std::abs(c.difference().value()) > 3 * c.difference().standard_error());
  EXPECT_GE(c.paths_per_sensor(), c.pilot_paths_per_sensor());
  EXPECT_GT(c.seconds(), 0);

  // The check runs after the search, and the last report carries it
  ASSERT_GE(r.stages.size(), 2u);
  EXPECT_EQ(r.stages[r.stages.size() - 2], "search");
  EXPECT_EQ(r.stages.back(), "check");
  ASSERT_GE(r.progress.size(), 2u);
  for (size_t i = 0; i + 1 < r.progress.size(); ++i) EXPECT_FALSE(r.progress[i].final_check);
  const JobProgress& last = r.progress.back();
  ASSERT_TRUE(last.final_check);
  EXPECT_EQ(last.final_check->SerializeAsString(), c.SerializeAsString());
  EXPECT_EQ(last.evaluations, r.result.evaluations());
  EXPECT_EQ(last.best.value().value(), r.result.best_value().value());
  EXPECT_EQ(last.remaining_seconds, 0);
  EXPECT_GE(last.elapsed_seconds, r.progress[r.progress.size() - 2].elapsed_seconds);

  // The same check of the same design, outside the job: the same numbers
  absl::StatusOr<v1::FinalCheck> again =
      CheckJobDesign(job, r.result.best_design(), r.result.best_value());
  ASSERT_TRUE(again.ok()) << again.status();
  v1::FinalCheck timeless = c;
  timeless.clear_seconds();
  again->clear_seconds();
  EXPECT_EQ(again->SerializeAsString(), timeless.SerializeAsString());
}

// The quick job with the source publication's limits (at most 5 indoor reflections): the
// check, which traces without a limit, finds the light the limits leave out (seed 1).
TEST(JobTest, FinalCheckFindsTheLightTheReflectionLimitsLeaveOut) {
  const Reported r = RunReporting(QuickJob(8, /*source_limits=*/true));
  ASSERT_TRUE(r.result.has_final_check());
  const v1::FinalCheck& c = r.result.final_check();
  Print(c);
  EXPECT_TRUE(c.disagrees());
  EXPECT_GT(c.difference().value(), 3 * c.difference().standard_error());
}

// Error against time: each evaluation's value, error and time, and the best value's as the
// search went, one entry per move of the incumbent.
TEST(JobTest, BestOverTimeFollowsTheIncumbent) {
  PreparedJob job = QuickJob(12);
  job.job.mutable_sampling()->set_final_check(false);
  const Reported r = RunReporting(job);
  EXPECT_FALSE(r.result.has_final_check());
  EXPECT_EQ(r.stages.back(), "search");
  const auto& history = r.result.history();
  EXPECT_EQ(r.result.evaluations(), 12);
  ASSERT_GE(history.size(), 12);  // cached repeats included
  for (int i = 0; i < history.size(); ++i) {
    EXPECT_EQ(history[i].index(), i);
    EXPECT_GT(history[i].elapsed_seconds(), 0);
    if (i > 0) EXPECT_GE(history[i].elapsed_seconds(), history[i - 1].elapsed_seconds());
    if (!history[i].cached()) {
      EXPECT_GT(history[i].seconds(), 0);
      EXPECT_GT(history[i].value().standard_error(), 0);
    }
  }
  const auto& best = r.result.best_over_time();
  ASSERT_GE(best.size(), 2);  // the start and at least one move from it
  int improvements = 0;
  for (const v1::Evaluation& e : history) improvements += e.improved() ? 1 : 0;
  EXPECT_EQ(best.size(), improvements);
  EXPECT_EQ(best[0].evaluation(), 0);
  for (int k = 0; k < best.size(); ++k) {
    const v1::Evaluation& e = history[best[k].evaluation()];
    EXPECT_TRUE(e.improved());
    EXPECT_EQ(best[k].value().value(), e.value().value());
    EXPECT_EQ(best[k].value().standard_error(), e.value().standard_error());
    EXPECT_EQ(best[k].elapsed_seconds(), e.elapsed_seconds());
    if (k > 0) {
      EXPECT_GT(best[k].evaluation(), best[k - 1].evaluation());
      EXPECT_GE(best[k].elapsed_seconds(), best[k - 1].elapsed_seconds());
      EXPECT_GT(best[k].value().value(), best[k - 1].value().value());  // maximized
    }
  }
  EXPECT_EQ(best[best.size() - 1].value().value(), r.result.best_value().value());
  EXPECT_EQ(best[best.size() - 1].value().standard_error(), r.result.best_value().standard_error());
  // The progress reports, one per step, carry the same times
  ASSERT_EQ(r.progress.size(), static_cast<size_t>(history.size()));
  EXPECT_EQ(r.progress.back().current.elapsed_seconds(),
            history[history.size() - 1].elapsed_seconds());
}

// A cancelled job stops without its check.
TEST(JobTest, CancelledJobLeavesTheCheckOut) {
  int reports = 0;
  PreparedJob job = QuickJob(12);
  JobCallbacks callbacks;
  std::vector<std::string> stages;
  callbacks.stage = [&](const std::string& stage) { stages.push_back(stage); };
  callbacks.progress = [&](const JobProgress&) { ++reports; };
  callbacks.cancelled = [&] { return reports >= 3; };
  absl::StatusOr<v1::JobResult> result = RunJob(job, nullptr, callbacks);
  ASSERT_TRUE(result.ok()) << result.status();
  EXPECT_EQ(result->stop_reason(), "cancelled");
  EXPECT_FALSE(result->has_final_check());
  EXPECT_EQ(stages.back(), "search");
  EXPECT_EQ(reports, 3);
}

}  // namespace
}  // namespace fenestra
