#include "core/metrics/metric_errors.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

#include "core/metrics/illuminance.h"
#include "core/metrics/occupancy.h"

namespace fenestra {
namespace {

// One day of 24 hourly steps, lit 6..19, occupied 8..17.
struct Day {
  std::vector<bool> occupied;
  std::vector<int> columns;
  Matrix sky;
};

Day MakeDay(int patches, uint64_t seed) {
  Day day;
  std::vector<double> hours;
  for (int h = 1; h <= 24; ++h) hours.push_back(h - 0.5);
  day.occupied = *OccupiedSteps(hours);
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(0.5, 1.5);
  day.sky = Matrix::Zero(patches, 24);
  for (int h = 6; h < 20; ++h) {
    day.columns.push_back(h);
    for (int p = 0; p < patches; ++p) day.sky(p, h) = u(rng);
  }
  return day;
}

std::vector<Matrix> RandomBatches(int batches, int sensors, int patches, double scale,
                                  uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(0.5, 1.5);
  std::vector<Matrix> out;
  for (int b = 0; b < batches; ++b) {
    Matrix d(sensors, patches);
    for (int i = 0; i < d.size(); ++i) d.data()[i] = scale * u(rng);
    out.push_back(d);
  }
  return out;
}

TEST(MetricErrorsTest, JackknifeOfThreeValues) {
  const std::vector<double> values = {1, 2, 3};
  EXPECT_DOUBLE_EQ(JackknifeStandardError(values), std::sqrt(2.0 * 2 / 3));
  EXPECT_EQ(JackknifeStandardError(std::vector<double>{5}), 0);
}

TEST(MetricErrorsTest, IdenticalBatchesHaveZeroError) {
  const Day day = MakeDay(3, 1);
  const Matrix d = RandomBatches(1, 4, 3, 2.0, 2)[0];
  const std::vector<Matrix> batches(4, d);
  const std::vector<Matrix> sky = {day.sky};
  absl::StatusOr<AnnualMetricsEstimate> estimate =
      AnnualMetricsWithErrors(batches, sky, day.columns, day.occupied);
  ASSERT_TRUE(estimate.ok()) << estimate.status();
  EXPECT_EQ(estimate->batches, 4);

  absl::StatusOr<Matrix> e = Illuminance(d, day.sky, day.columns);
  absl::StatusOr<AnnualMetrics> direct = ComputeAnnualMetrics(*e, day.columns, day.occupied);
  ASSERT_TRUE(direct.ok());
  EXPECT_NEAR(estimate->value.scene.udi_mean_percent, direct->scene.udi_mean_percent, 1e-9);
  EXPECT_NEAR(estimate->value.scene.mean_illuminance_lux, direct->scene.mean_illuminance_lux, 1e-9);
  const AnnualMetrics& se = estimate->standard_error;
  EXPECT_NEAR(se.scene.udi_mean_percent, 0, 1e-9);
  EXPECT_NEAR(se.scene.udi_all_percent, 0, 1e-9);
  EXPECT_NEAR(se.scene.cda_mean_percent, 0, 1e-9);
  EXPECT_NEAR(se.scene.mean_illuminance_lux, 0, 1e-9);
  ASSERT_EQ(se.sensors.size(), 4u);
  for (const SensorMetrics& s : se.sensors) EXPECT_NEAR(s.da_percent, 0, 1e-9);
}

TEST(MetricErrorsTest, LinearMetricsGiveTheClassicalStandardErrorOfTheMean) {
  // Below 300 lx everywhere, so continuous DA is linear in D like the mean illuminance
  const int batches = 6;
  const Day day = MakeDay(3, 3);
  const std::vector<Matrix> dc = RandomBatches(batches, 2, 3, 0.1, 4);
  const std::vector<Matrix> sky = {day.sky};
  absl::StatusOr<AnnualMetricsEstimate> estimate =
      AnnualMetricsWithErrors(dc, sky, day.columns, day.occupied);
  ASSERT_TRUE(estimate.ok());

  std::vector<double> mean_lux, cda;
  for (const Matrix& d : dc) {
    absl::StatusOr<Matrix> e = Illuminance(d, day.sky, day.columns);
    ASSERT_LT(e->maxCoeff(), 300);
    absl::StatusOr<AnnualMetrics> m = ComputeAnnualMetrics(*e, day.columns, day.occupied);
    mean_lux.push_back(m->scene.mean_illuminance_lux);
    cda.push_back(m->sensors[1].cda_percent);
  }
  auto mean_and_se = [](const std::vector<double>& v) {
    double mean = 0, squares = 0;
    for (double x : v) mean += x;
    mean /= v.size();
    for (double x : v) squares += (x - mean) * (x - mean);
    return std::pair(mean, std::sqrt(squares / (v.size() - 1) / v.size()));
  };
  const auto [lux, lux_se] = mean_and_se(mean_lux);
  const auto [c, c_se] = mean_and_se(cda);
  EXPECT_GT(lux_se, 0);
  EXPECT_NEAR(estimate->value.scene.mean_illuminance_lux, lux, 1e-9 * lux);
  EXPECT_NEAR(estimate->standard_error.scene.mean_illuminance_lux, lux_se, 1e-9 * lux_se);
  EXPECT_NEAR(estimate->value.sensors[1].cda_percent, c, 1e-9 * c);
  EXPECT_NEAR(estimate->standard_error.sensors[1].cda_percent, c_se, 1e-9 * c_se);
}

TEST(MetricErrorsTest, ThresholdMetricWithTwoBatches) {
  // Batch 1 gives 50 lx, batch 2 250 lx: the mean, 150 lx, is in range all the time. Leaving
  // out batch 1 gives UDI 100%, leaving out batch 2 gives 0%: SE = |100 - 0| / 2
  const Day day = MakeDay(1, 5);
  Matrix sky = Matrix::Zero(1, 24);
  for (int c : day.columns) sky(0, c) = 1;
  const std::vector<Matrix> dc = {Matrix::Constant(1, 1, 50 / 179.0),
                                  Matrix::Constant(1, 1, 250 / 179.0)};
  const std::vector<Matrix> skies = {sky};
  absl::StatusOr<AnnualMetricsEstimate> estimate =
      AnnualMetricsWithErrors(dc, skies, day.columns, day.occupied);
  ASSERT_TRUE(estimate.ok());
  EXPECT_DOUBLE_EQ(estimate->value.scene.udi_mean_percent, 100);
  EXPECT_NEAR(estimate->standard_error.scene.udi_mean_percent, 50, 1e-9);
  EXPECT_NEAR(estimate->standard_error.scene.udi_mean_fell_short_percent, 50, 1e-9);
  EXPECT_NEAR(estimate->standard_error.scene.mean_illuminance_lux, 100, 1e-9);
}

TEST(MetricErrorsTest, IlluminanceBatchesAgreeWithCoefficientBatches) {
  const Day day = MakeDay(3, 6);
  const std::vector<Matrix> dc = RandomBatches(4, 3, 3, 3.0, 7);
  const std::vector<Matrix> sky = {day.sky};
  std::vector<Matrix> e;
  for (const Matrix& d : dc) e.push_back(*Illuminance(d, day.sky, day.columns));
  const Matrix direct = Matrix::Constant(3, static_cast<int>(day.columns.size()), 2000);
  MetricOptions options;
  options.ase_min_hours = 5;
  absl::StatusOr<AnnualMetricsEstimate> a =
      AnnualMetricsWithErrors(dc, sky, day.columns, day.occupied, options, &direct);
  absl::StatusOr<AnnualMetricsEstimate> b =
      AnnualMetricsFromIlluminanceBatches(e, day.columns, day.occupied, options, &direct);
  ASSERT_TRUE(a.ok()) << a.status();
  ASSERT_TRUE(b.ok()) << b.status();
  EXPECT_NEAR(a->value.scene.udi_mean_percent, b->value.scene.udi_mean_percent, 1e-9);
  EXPECT_NEAR(a->standard_error.scene.udi_mean_percent, b->standard_error.scene.udi_mean_percent,
              1e-9);
  EXPECT_NEAR(a->standard_error.scene.cda_mean_percent, b->standard_error.scene.cda_mean_percent,
              1e-9);
  EXPECT_DOUBLE_EQ(a->value.scene.ase_percent, 100);
  EXPECT_EQ(a->standard_error.scene.ase_percent, 0);
  EXPECT_TRUE(a->standard_error.has_ase);
  EXPECT_EQ(a->standard_error.analysed_hours, 10);
}

TEST(MetricErrorsTest, RejectsBadInput) {
  const Day day = MakeDay(3, 8);
  const std::vector<Matrix> sky = {day.sky};
  const std::vector<Matrix> one = RandomBatches(1, 2, 3, 1, 9);
  EXPECT_EQ(AnnualMetricsWithErrors(one, sky, day.columns, day.occupied).status().code(),
            absl::StatusCode::kInvalidArgument);
  std::vector<Matrix> mixed = RandomBatches(2, 2, 3, 1, 9);
  mixed[1] = Matrix::Ones(3, 3);
  EXPECT_FALSE(AnnualMetricsWithErrors(mixed, sky, day.columns, day.occupied).ok());
  const std::vector<Matrix> two = RandomBatches(2, 2, 3, 1, 9);
  EXPECT_FALSE(AnnualMetricsWithErrors(two, sky, day.columns, std::vector<bool>(48, true)).ok());
  const Matrix direct = Matrix::Zero(2, 3);
  EXPECT_FALSE(AnnualMetricsWithErrors(two, sky, day.columns, day.occupied, {}, &direct).ok());
}

}  // namespace
}  // namespace fenestra
