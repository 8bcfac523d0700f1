#include "core/optimize/final_check.h"

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "core/dc/one_stage.h"
#include "tests/example_scene.h"

namespace fenestra {
namespace {

v1::Estimate Estimate(double value, double standard_error) {
  v1::Estimate e;
  e.set_value(value);
  e.set_standard_error(standard_error);
  return e;
}

TEST(FinalCheckTest, DifferenceAndItsErrorFromBothValues) {
  const v1::FinalCheck c = CompareWithCheck(Estimate(50, 3), Estimate(54, 4));
  EXPECT_EQ(c.two_stage().value(), 50);
  EXPECT_EQ(c.one_stage().standard_error(), 4);
  EXPECT_DOUBLE_EQ(c.difference().value(), 4);
  EXPECT_DOUBLE_EQ(c.difference().standard_error(), 5);  // sqrt(3^2 + 4^2)
  EXPECT_FALSE(c.disagrees());
}

TEST(FinalCheckTest, DisagreesBeyondThreeStandardErrorsEitherWay) {
  // Standard error of the difference: hypot(0.6, 0.8) = 1
  for (const double sign : {1.0, -1.0}) {
    EXPECT_FALSE(CompareWithCheck(Estimate(30, 0.6), Estimate(30 + sign * 2.9, 0.8)).disagrees());
    EXPECT_TRUE(CompareWithCheck(Estimate(30, 0.6), Estimate(30 + sign * 3.1, 0.8)).disagrees());
  }
  EXPECT_EQ(kFinalCheckDisagreementStandardErrors, 3);
  // Without any error, only equal values agree
  EXPECT_FALSE(CompareWithCheck(Estimate(0, 0), Estimate(0, 0)).disagrees());
  EXPECT_TRUE(CompareWithCheck(Estimate(0, 0), Estimate(0.01, 0)).disagrees());
}

TEST(FinalCheckTest, PathsGoWithTheSquareOfTheErrorRatio) {
  bool limited = true;
  // Twice the target's error: four times the pilot's paths
  EXPECT_EQ(CheckPathsPerSensor(1000, 2.0, 1.0, 100000, 8, &limited), 4000);
  EXPECT_FALSE(limited);
  // Already precise enough: the pilot's paths, never fewer
  EXPECT_EQ(CheckPathsPerSensor(1000, 0.5, 1.0, 100000, 8, &limited), 1000);
  EXPECT_FALSE(limited);
  // Rounded up to whole batches
  EXPECT_EQ(CheckPathsPerSensor(1000, 1.1, 1.0, 100000, 8, &limited), 1216);
  // Held at the most, and said so
  EXPECT_EQ(CheckPathsPerSensor(1000, 100.0, 1.0, 50000, 8, &limited), 50000);
  EXPECT_TRUE(limited);
  // A target of 0 with a spread in the pilot: the most
  EXPECT_EQ(CheckPathsPerSensor(1000, 1.0, 0.0, 50000, 8, &limited), 50000);
  EXPECT_TRUE(limited);
  // No spread in the pilot (a metric that no path moves): nothing to scale, the pilot's
  EXPECT_EQ(CheckPathsPerSensor(1000, 0.0, 0.0, 50000, 8, &limited), 1000);
  EXPECT_FALSE(limited);
  EXPECT_EQ(CheckPathsPerSensor(1000, 0.0, 1.0, 50000, 8, &limited), 1000);
  EXPECT_FALSE(limited);
}

// The check of the lightwell with a metric that records what it was given: a pilot of 32
// batches, then the check with the job's batches and streams of its own, as many paths as
// the pilot's error asks.
TEST(FinalCheckTest, PilotThenCheckWithTheirOwnStreams) {
  const Scene scene = LoadExample("lightwell");
  std::vector<std::vector<Matrix>> traced;
  std::vector<Evaluation> evaluated;
  const DaylightMetric sky_sum = [&](std::span<const Matrix> batches) {
    traced.emplace_back(batches.begin(), batches.end());
    // The first sensor's sky sum: the mean of the batches and its standard error
    std::vector<double> sums;
    for (const Matrix& d : batches) sums.push_back(d.row(0).tail(kDaylightBins - 1).sum());
    const double n = static_cast<double>(sums.size());
    double mean = 0, squares = 0;
    for (const double s : sums) mean += s / n;
    for (const double s : sums) squares += (s - mean) * (s - mean);
    Evaluation e;
    e.value = mean;
    e.standard_error = std::sqrt(squares / (n - 1) / n);
    evaluated.push_back(e);
    return absl::StatusOr<Evaluation>(e);
  };
  FinalCheckOptions options;
  options.batches = 4;
  options.seed = 1;
  // 10^5 paths over 3 sensors, in whole pilot batches
  const int64_t pilot_paths = 33344;

  // A loose target: the check traces as many paths as the pilot
  absl::StatusOr<FinalCheckOutcome> loose =
      RunFinalCheck(scene, DefaultDesign(scene), Estimate(0, 1e9), sky_sum, options);
  ASSERT_TRUE(loose.ok()) << loose.status();
  ASSERT_EQ(traced.size(), 2u);
  EXPECT_EQ(traced[0].size(), static_cast<size_t>(kFinalCheckPilotBatches));
  EXPECT_EQ(traced[1].size(), 4u);
  EXPECT_EQ(loose->check.pilot_paths_per_sensor(), pilot_paths);
  EXPECT_EQ(loose->check.paths_per_sensor(), pilot_paths);
  EXPECT_FALSE(loose->check.paths_limited());
  EXPECT_GT(loose->check.seconds(), 0);
  EXPECT_EQ(loose->check.one_stage().value(), evaluated[1].value);
  // The pilot's and the check's traces are independent: the means of their first quarter of
  // paths differ
  Matrix pilot_quarter = Matrix::Zero(3, kDaylightBins);
  for (int b = 0; b < 8; ++b) pilot_quarter += traced[0][b] / 8;
  EXPECT_NE(pilot_quarter(0, 1), traced[1][0](0, 1));

  // Half the pilot's error: four times its paths (the pilot is traced again, the same)
  const Evaluation pilot = evaluated[0];
  traced.clear();
  evaluated.clear();
  absl::StatusOr<FinalCheckOutcome> tight =
      RunFinalCheck(scene, DefaultDesign(scene), Estimate(pilot.value, pilot.standard_error / 2),
                    sky_sum, options);
  ASSERT_TRUE(tight.ok()) << tight.status();
  EXPECT_EQ(evaluated[0].standard_error, pilot.standard_error);
  EXPECT_EQ(tight->check.paths_per_sensor(), 4 * pilot_paths);
  const v1::Estimate& d = tight->check.difference();
  EXPECT_EQ(tight->check.disagrees(), std::abs(d.value()) > 3 * d.standard_error());

  // Cancelled before it starts: nothing traced
  traced.clear();
  options.cancelled = [] { return true; };
  EXPECT_TRUE(absl::IsCancelled(
      RunFinalCheck(scene, DefaultDesign(scene), Estimate(0, 1), sky_sum, options).status()));
  EXPECT_TRUE(traced.empty());
}

}  // namespace
}  // namespace fenestra
