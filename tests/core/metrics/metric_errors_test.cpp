#include "core/metrics/metric_errors.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>
#include <span>
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

TEST(MetricErrorsTest, TalliesOfTheVersionsGiveTheBatchEstimate) {
  const int batches = 5;
  const Day day = MakeDay(3, 10);
  const std::vector<Matrix> dc = RandomBatches(batches, 4, 3, 2.0, 11);
  std::vector<Matrix> e;
  for (const Matrix& d : dc) e.push_back(*Illuminance(d, day.sky, day.columns));
  MetricOptions all_hours;  // 24 analysed hours, 10 of them dark
  all_hours.hours = HourBasis::kAllHours;
  for (const MetricOptions& options : {MetricOptions{}, all_hours}) {
    absl::StatusOr<AnnualMetricsEstimate> expected =
        AnnualMetricsFromIlluminanceBatches(e, day.columns, day.occupied, options);
    ASSERT_TRUE(expected.ok()) << expected.status();

    // The versions formed and tallied here, over the analysed columns only
    std::vector<int> steps, positions;
    for (size_t c = 0; c < day.columns.size(); ++c) {
      if (options.hours == HourBasis::kAllHours || day.occupied[day.columns[c]]) {
        steps.push_back(day.columns[c]);
        positions.push_back(static_cast<int>(c));
      }
    }
    Matrix mean = Matrix::Zero(4, static_cast<int>(steps.size()));
    for (const Matrix& e_b : e) mean += e_b(Eigen::all, positions);
    mean /= batches;
    std::vector<Matrix> versions = {mean};
    for (const Matrix& e_b : e) {
      versions.push_back((batches * mean - e_b(Eigen::all, positions)) / (batches - 1.0));
    }
    std::vector<HourTally> tallies;
    for (const Matrix& v : versions) tallies.push_back(TallyHours(v, options));
    const int analysed_hours = options.hours == HourBasis::kAllHours ? 24 : 10;
    absl::StatusOr<AnnualMetricsEstimate> got =
        AnnualMetricsFromTallies(tallies, analysed_hours, options);
    ASSERT_TRUE(got.ok()) << got.status();
    EXPECT_EQ(got->batches, batches);
    EXPECT_EQ(got->value.analysed_hours, analysed_hours);
    EXPECT_EQ(got->standard_error.analysed_hours, analysed_hours);

    // The value and the jackknife over ComputeAnnualMetrics of each version
    std::vector<AnnualMetrics> direct;
    for (const Matrix& v : versions) {
      absl::StatusOr<AnnualMetrics> m = ComputeAnnualMetrics(v, steps, day.occupied, options);
      ASSERT_TRUE(m.ok()) << m.status();
      direct.push_back(*m);
    }
    auto jackknife = [&](auto field) {
      std::vector<double> values;
      for (int b = 1; b <= batches; ++b) values.push_back(field(direct[b]));
      return JackknifeStandardError(values);
    };
    for (SceneMetric metric :
         {SceneMetric::kUdiAll, SceneMetric::kUdiAllFellShort, SceneMetric::kUdiAllExceeded,
          SceneMetric::kUdiMean, SceneMetric::kUdiMeanFellShort, SceneMetric::kUdiMeanExceeded,
          SceneMetric::kDaMean, SceneMetric::kCdaMean, SceneMetric::kSda,
          SceneMetric::kMeanIlluminance}) {
      SCOPED_TRACE(SceneMetricName(metric));
      const double value = SceneMetricValue(got->value.scene, metric);
      const double se = SceneMetricValue(got->standard_error.scene, metric);
      EXPECT_NEAR(value, SceneMetricValue(direct[0].scene, metric), 1e-9);
      EXPECT_NEAR(
          se, jackknife([&](const AnnualMetrics& m) { return SceneMetricValue(m.scene, metric); }),
          1e-9);
      EXPECT_NEAR(value, SceneMetricValue(expected->value.scene, metric), 1e-9);
      EXPECT_NEAR(se, SceneMetricValue(expected->standard_error.scene, metric), 1e-9);
    }
    ASSERT_EQ(got->standard_error.sensors.size(), 4u);
    for (int i = 0; i < 4; ++i) {
      EXPECT_NEAR(got->value.sensors[i].udi_percent, expected->value.sensors[i].udi_percent, 1e-9);
      EXPECT_NEAR(got->standard_error.sensors[i].da_percent,
                  jackknife([&](const AnnualMetrics& m) { return m.sensors[i].da_percent; }), 1e-9);
      EXPECT_NEAR(got->standard_error.sensors[i].cda_percent,
                  expected->standard_error.sensors[i].cda_percent, 1e-9);
    }
    EXPECT_GT(got->standard_error.scene.mean_illuminance_lux, 0);
  }
}

TEST(MetricErrorsTest, TalliesRejectBadVersions) {
  const Day day = MakeDay(3, 12);
  std::vector<Matrix> e;
  for (const Matrix& d : RandomBatches(3, 2, 3, 1, 13)) {
    e.push_back(*Illuminance(d, day.sky, day.columns));
  }
  absl::StatusOr<std::vector<HourTally>> tallies = TallyBatchVersions(e, MetricOptions{});
  ASSERT_TRUE(tallies.ok()) << tallies.status();
  ASSERT_EQ(tallies->size(), 4u);
  EXPECT_TRUE(AnnualMetricsFromTallies(*tallies, 14, {}).ok());
  for (size_t count : {0, 1, 2}) {
    const std::span<const HourTally> few(tallies->data(), count);
    EXPECT_EQ(AnnualMetricsFromTallies(few, 14, {}).status().code(),
              absl::StatusCode::kInvalidArgument)
        << count;
  }
  std::vector<HourTally> other_sensors = *tallies;
  other_sensors[2].sensors.pop_back();
  EXPECT_EQ(AnnualMetricsFromTallies(other_sensors, 14, {}).status().code(),
            absl::StatusCode::kInvalidArgument);
  EXPECT_FALSE(AnnualMetricsFromTallies(*tallies, 13, {}).ok());  // fewer than tallied
  EXPECT_FALSE(AnnualMetricsFromTallies(*tallies, 0, {}).ok());
  MetricOptions inverted;
  inverted.udi_lower_lux = 3000;
  inverted.udi_upper_lux = 100;
  EXPECT_FALSE(AnnualMetricsFromTallies(*tallies, 14, inverted).ok());
  // The versions need two batches of one shape
  EXPECT_FALSE(TallyBatchVersions(std::span<const Matrix>(e.data(), 1), {}).ok());
  e[1] = Matrix::Ones(2, 13);
  EXPECT_FALSE(TallyBatchVersions(e, {}).ok());
}

// Two tallies equal to the last bit.
void ExpectSameTally(const HourTally& got, const HourTally& want) {
  EXPECT_EQ(got.hours, want.hours);
  EXPECT_EQ(got.all_in, want.all_in);
  EXPECT_EQ(got.any_below, want.any_below);
  EXPECT_EQ(got.any_above, want.any_above);
  ASSERT_EQ(got.sensors.size(), want.sensors.size());
  for (size_t i = 0; i < got.sensors.size(); ++i) {
    EXPECT_EQ(got.sensors[i].below, want.sensors[i].below) << i;
    EXPECT_EQ(got.sensors[i].above, want.sensors[i].above) << i;
    EXPECT_EQ(got.sensors[i].da, want.sensors[i].da) << i;
    EXPECT_EQ(got.sensors[i].credit, want.sensors[i].credit) << i;
    EXPECT_EQ(got.sensors[i].sum, want.sensors[i].sum) << i;
  }
}

// The versions' tallies from batches stacked in one matrix, as the CPU's annual product makes
// them, and from the batches apart: both those of the version matrices, to the last bit.
TEST(MetricErrorsTest, StackedBatchesTallyAsTheVersionMatrices) {
  const int batches = 5, sensors = 3, hours = 200;
  std::mt19937_64 rng(21);
  std::uniform_real_distribution<double> log_lux(std::log(20.0), std::log(8000.0));
  std::vector<Matrix> e(batches, Matrix(sensors, hours));
  Matrix stacked(batches * sensors, hours);
  for (int b = 0; b < batches; ++b) {
    for (int i = 0; i < sensors; ++i) {
      for (int h = 0; h < hours; ++h) e[b](i, h) = std::exp(log_lux(rng));
    }
    stacked.middleRows(b * sensors, sensors) = e[b];
  }
  MetricOptions options;
  Matrix mean = e[0];
  for (int b = 1; b < batches; ++b) mean += e[b];
  mean /= batches;
  std::vector<HourTally> want = {TallyHours(mean, options)};
  for (const Matrix& e_b : e) {
    want.push_back(TallyHours((batches * mean - e_b) * (1.0 / (batches - 1)), options));
  }
  // Every class occurs: below, within and above the UDI range, some hours all within
  EXPECT_GT(want[0].any_below, 0);
  EXPECT_GT(want[0].any_above, 0);
  EXPECT_GT(want[0].all_in, 0);

  absl::StatusOr<std::vector<HourTally>> apart = TallyBatchVersions(e, options);
  absl::StatusOr<std::vector<HourTally>> together = TallyStackedVersions(stacked, batches, options);
  ASSERT_TRUE(apart.ok()) << apart.status();
  ASSERT_TRUE(together.ok()) << together.status();
  ASSERT_EQ(apart->size(), want.size());
  ASSERT_EQ(together->size(), want.size());
  for (size_t v = 0; v < want.size(); ++v) {
    SCOPED_TRACE(v);
    ExpectSameTally((*apart)[v], want[v]);
    ExpectSameTally((*together)[v], want[v]);
  }

  // One batch, rows that do not split into the batches, a value that is not finite
  EXPECT_EQ(TallyStackedVersions(stacked.topRows(sensors), 1, options).status().code(),
            absl::StatusCode::kInvalidArgument);
  EXPECT_EQ(TallyStackedVersions(stacked, 4, options).status().code(),
            absl::StatusCode::kInvalidArgument);
  stacked(7, 3) = std::numeric_limits<double>::quiet_NaN();
  EXPECT_EQ(TallyStackedVersions(stacked, batches, options).status().code(),
            absl::StatusCode::kInvalidArgument);
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
