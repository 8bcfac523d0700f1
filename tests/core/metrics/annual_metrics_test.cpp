#include "core/metrics/annual_metrics.h"

#include <gtest/gtest.h>

#include <limits>
#include <vector>

#include "core/metrics/occupancy.h"

namespace fenestra {
namespace {

// An hourly year of `days` days, steps centred at h - 0.5, default 8-18 occupancy: steps
// 8..17 of each day are occupied.
std::vector<bool> Occupied(int days) {
  std::vector<double> hours;
  for (int d = 0; d < days; ++d) {
    for (int h = 1; h <= 24; ++h) hours.push_back(h - 0.5);
  }
  return *OccupiedSteps(hours);
}

// Daytime steps 6..19 of each of the first `days` days.
std::vector<int> DaytimeColumns(int days) {
  std::vector<int> columns;
  for (int d = 0; d < days; ++d) {
    for (int h = 6; h < 20; ++h) columns.push_back(24 * d + h);
  }
  return columns;
}

// Illuminance over DaytimeColumns(1): the 10 occupied hours get `occupied_lux` in order; the
// unoccupied daytime hours get `other_lux`.
Matrix OneDay(const std::vector<std::vector<double>>& occupied_lux, double other_lux = 1e6) {
  Matrix e = Matrix::Constant(static_cast<int>(occupied_lux.size()), 14, other_lux);
  for (size_t i = 0; i < occupied_lux.size(); ++i) {
    for (int h = 0; h < 10; ++h) e(i, h + 2) = occupied_lux[i][h];
  }
  return e;
}

TEST(AnnualMetricsTest, ThresholdEdgesAreCountedAsHoneybeeDoes) {
  const Matrix e = OneDay({{100, 3000, 99.999, 3000.001, 300, 299.9, 0, 5000, 1500, 50}});
  absl::StatusOr<AnnualMetrics> m = ComputeAnnualMetrics(e, DaytimeColumns(1), Occupied(1));
  ASSERT_TRUE(m.ok()) << m.status();
  EXPECT_EQ(m->analysed_hours, 10);
  const SensorMetrics& s = m->sensors[0];
  EXPECT_DOUBLE_EQ(s.udi_percent, 50);  // 100, 3000, 300, 299.9, 1500
  EXPECT_DOUBLE_EQ(s.udi_fell_short_percent, 30);
  EXPECT_DOUBLE_EQ(s.udi_exceeded_percent, 20);
  EXPECT_DOUBLE_EQ(s.da_percent, 50);  // 300 itself counts
  EXPECT_NEAR(s.cda_percent, (5 + (100 + 99.999 + 299.9 + 50) / 300.0) * 10, 1e-9);
  EXPECT_NEAR(s.mean_illuminance_lux,
              (100 + 3000 + 99.999 + 3000.001 + 300 + 299.9 + 0 + 5000 + 1500 + 50) / 10, 1e-9);
  EXPECT_DOUBLE_EQ(m->scene.udi_mean_percent, 50);
  EXPECT_DOUBLE_EQ(m->scene.udi_all_percent, 50);
  EXPECT_FALSE(m->has_ase);
  EXPECT_EQ(m->scene.ase_percent, 0);
}

TEST(AnnualMetricsTest, CustomRangeAndThreshold) {
  const Matrix e = OneDay({{100, 3000, 99.999, 3000.001, 300, 299.9, 0, 5000, 1500, 50}});
  MetricOptions options;
  options.udi_lower_lux = 300;
  options.udi_upper_lux = 1500;
  options.da_threshold_lux = 1500;
  absl::StatusOr<AnnualMetrics> m =
      ComputeAnnualMetrics(e, DaytimeColumns(1), Occupied(1), options);
  ASSERT_TRUE(m.ok());
  EXPECT_DOUBLE_EQ(m->sensors[0].udi_percent, 20);  // 300, 1500
  EXPECT_DOUBLE_EQ(m->sensors[0].da_percent, 40);   // 3000, 3000.001, 5000, 1500
}

TEST(AnnualMetricsTest, AllNightDayFallsShort) {
  // Two days; the second has no daytime column at all
  const std::vector<bool> occupied = Occupied(2);
  const Matrix e = OneDay({std::vector<double>(10, 500)});
  absl::StatusOr<AnnualMetrics> m = ComputeAnnualMetrics(e, DaytimeColumns(1), occupied);
  ASSERT_TRUE(m.ok());
  EXPECT_EQ(m->analysed_hours, 20);
  EXPECT_DOUBLE_EQ(m->sensors[0].udi_percent, 50);
  EXPECT_DOUBLE_EQ(m->sensors[0].udi_fell_short_percent, 50);
  EXPECT_DOUBLE_EQ(m->sensors[0].da_percent, 50);
  EXPECT_DOUBLE_EQ(m->scene.udi_all_fell_short_percent, 50);

  // No daytime column anywhere
  absl::StatusOr<AnnualMetrics> dark = ComputeAnnualMetrics(Matrix(1, 0), {}, occupied);
  ASSERT_TRUE(dark.ok());
  EXPECT_DOUBLE_EQ(dark->sensors[0].udi_fell_short_percent, 100);
  EXPECT_DOUBLE_EQ(dark->scene.udi_all_fell_short_percent, 100);
  EXPECT_DOUBLE_EQ(dark->scene.udi_mean_percent, 0);
  EXPECT_DOUBLE_EQ(dark->scene.cda_mean_percent, 0);
}

TEST(AnnualMetricsTest, SensorAlwaysInShadow) {
  const Matrix e = OneDay({std::vector<double>(10, 500), std::vector<double>(10, 0)}, 0);
  absl::StatusOr<AnnualMetrics> m = ComputeAnnualMetrics(e, DaytimeColumns(1), Occupied(1));
  ASSERT_TRUE(m.ok());
  EXPECT_DOUBLE_EQ(m->sensors[0].udi_percent, 100);
  EXPECT_DOUBLE_EQ(m->sensors[1].udi_percent, 0);
  EXPECT_DOUBLE_EQ(m->sensors[1].udi_fell_short_percent, 100);
  EXPECT_DOUBLE_EQ(m->sensors[1].cda_percent, 0);
  EXPECT_DOUBLE_EQ(m->scene.udi_mean_percent, 50);
  EXPECT_DOUBLE_EQ(m->scene.udi_mean_fell_short_percent, 50);
  EXPECT_DOUBLE_EQ(m->scene.udi_all_percent, 0);
  EXPECT_DOUBLE_EQ(m->scene.udi_all_fell_short_percent, 100);
  EXPECT_DOUBLE_EQ(m->scene.da_mean_percent, 50);
  EXPECT_DOUBLE_EQ(m->scene.sda_percent, 50);
  EXPECT_DOUBLE_EQ(m->scene.mean_illuminance_lux, 250);
}

TEST(AnnualMetricsTest, AllHoursDenominator) {
  const Matrix e = OneDay({std::vector<double>(10, 500)}, 2000);
  MetricOptions options;
  options.hours = HourBasis::kAllHours;
  absl::StatusOr<AnnualMetrics> m =
      ComputeAnnualMetrics(e, DaytimeColumns(1), Occupied(1), options);
  ASSERT_TRUE(m.ok());
  EXPECT_EQ(m->analysed_hours, 24);
  EXPECT_DOUBLE_EQ(m->sensors[0].udi_percent, 14 * 100.0 / 24);
  EXPECT_DOUBLE_EQ(m->sensors[0].udi_fell_short_percent, 10 * 100.0 / 24);
  EXPECT_DOUBLE_EQ(m->scene.udi_all_percent, 14 * 100.0 / 24);
  EXPECT_DOUBLE_EQ(m->sensors[0].mean_illuminance_lux, (10 * 500 + 4 * 2000) / 24.0);
}

TEST(AnnualMetricsTest, AllSensorsAggregationCountsAnySensorOutOfRange) {
  std::vector<double> a = {50, 500, 50}, b = {5000, 500, 500};
  a.resize(10, 500);
  b.resize(10, 5000);
  absl::StatusOr<AnnualMetrics> m =
      ComputeAnnualMetrics(OneDay({a, b}), DaytimeColumns(1), Occupied(1));
  ASSERT_TRUE(m.ok());
  EXPECT_DOUBLE_EQ(m->scene.udi_all_percent, 10);
  EXPECT_DOUBLE_EQ(m->scene.udi_all_fell_short_percent, 20);
  EXPECT_DOUBLE_EQ(m->scene.udi_all_exceeded_percent, 80);
  EXPECT_DOUBLE_EQ(m->scene.udi_mean_percent, (80 + 20) / 2.0);
  EXPECT_DOUBLE_EQ(m->scene.udi_mean_fell_short_percent, 10);
  EXPECT_DOUBLE_EQ(m->scene.udi_mean_exceeded_percent, 40);
}

TEST(AnnualMetricsTest, SdaCountsSensorsAtExactlyHalf) {
  auto with_da = [](int hours_at_300) {
    std::vector<double> v(10, 100);
    for (int h = 0; h < hours_at_300; ++h) v[h] = 300;
    return v;
  };
  absl::StatusOr<AnnualMetrics> m = ComputeAnnualMetrics(
      OneDay({with_da(6), with_da(5), with_da(4)}), DaytimeColumns(1), Occupied(1));
  ASSERT_TRUE(m.ok());
  EXPECT_DOUBLE_EQ(m->sensors[1].da_percent, 50);
  EXPECT_DOUBLE_EQ(m->scene.sda_percent, 200.0 / 3);
  EXPECT_DOUBLE_EQ(m->scene.da_mean_percent, 50);
}

TEST(AnnualMetricsTest, AseFromDirectOnlyIlluminance) {
  // Sensor 0: 3 occupied hours above 1000 lx; sensor 1: 2, plus one at exactly 1000 lx;
  // the unoccupied daytime hours are far above and must not count
  const Matrix e = OneDay({std::vector<double>(10, 500), std::vector<double>(10, 500)});
  const Matrix direct = OneDay(
      {{1500, 1500, 1500, 0, 0, 0, 0, 0, 0, 0}, {1500, 1500, 1000, 0, 0, 0, 0, 0, 0, 0}}, 5000);
  MetricOptions options;
  options.ase_min_hours = 3;
  absl::StatusOr<AnnualMetrics> m =
      ComputeAnnualMetrics(e, DaytimeColumns(1), Occupied(1), options, &direct);
  ASSERT_TRUE(m.ok());
  EXPECT_TRUE(m->has_ase);
  EXPECT_EQ(m->sensors[0].ase_hours, 3);
  EXPECT_EQ(m->sensors[1].ase_hours, 2);
  EXPECT_DOUBLE_EQ(m->scene.ase_percent, 50);
}

TEST(AnnualMetricsTest, FullYearHas3650HoursAndAse250) {
  const int days = 365;
  const std::vector<int> columns = DaytimeColumns(days);
  const Matrix e = Matrix::Constant(2, static_cast<int>(columns.size()), 500);
  // Direct sun above 1000 lx in the first 250 / 249 occupied hours of the year
  Matrix direct = Matrix::Zero(2, static_cast<int>(columns.size()));
  int counted[2] = {0, 0};
  const std::vector<bool> occupied = Occupied(days);
  for (size_t c = 0; c < columns.size(); ++c) {
    if (!occupied[columns[c]]) continue;
    for (int i = 0; i < 2; ++i) {
      if (counted[i] < 250 - i) {
        direct(i, c) = 1000.5;
        ++counted[i];
      }
    }
  }
  absl::StatusOr<AnnualMetrics> m =
      ComputeAnnualMetrics(e, columns, occupied, MetricOptions{}, &direct);
  ASSERT_TRUE(m.ok());
  EXPECT_EQ(m->analysed_hours, 3650);
  EXPECT_DOUBLE_EQ(m->scene.udi_all_percent, 100);
  EXPECT_EQ(m->sensors[0].ase_hours, 250);
  EXPECT_EQ(m->sensors[1].ase_hours, 249);
  EXPECT_DOUBLE_EQ(m->scene.ase_percent, 50);
}

TEST(AnnualMetricsTest, RejectsBadInput) {
  const std::vector<int> columns = DaytimeColumns(1);
  const std::vector<bool> occupied = Occupied(1);
  const Matrix e = OneDay({std::vector<double>(10, 500)});
  EXPECT_FALSE(ComputeAnnualMetrics(Matrix(0, 14), columns, occupied).ok());
  EXPECT_FALSE(ComputeAnnualMetrics(Matrix::Ones(1, 13), columns, occupied).ok());
  EXPECT_FALSE(ComputeAnnualMetrics(e, columns, std::vector<bool>(24, false)).ok());
  EXPECT_FALSE(ComputeAnnualMetrics(e, columns, std::vector<bool>(12, true)).ok());
  MetricOptions inverted;
  inverted.udi_lower_lux = 3000;
  inverted.udi_upper_lux = 100;
  EXPECT_FALSE(ComputeAnnualMetrics(e, columns, occupied, inverted).ok());
  Matrix nan = e;
  nan(0, 3) = std::numeric_limits<double>::quiet_NaN();
  EXPECT_FALSE(ComputeAnnualMetrics(nan, columns, occupied).ok());
  const Matrix wrong_direct = Matrix::Zero(2, 14);
  EXPECT_FALSE(ComputeAnnualMetrics(e, columns, occupied, {}, &wrong_direct).ok());
}

TEST(AnnualMetricsTest, SceneMetricNamesRoundTrip) {
  for (SceneMetric metric : {SceneMetric::kUdiAll, SceneMetric::kUdiMean, SceneMetric::kSda,
                             SceneMetric::kAse, SceneMetric::kMeanIlluminance}) {
    absl::StatusOr<SceneMetric> back = SceneMetricFromName(SceneMetricName(metric));
    ASSERT_TRUE(back.ok());
    EXPECT_EQ(*back, metric);
  }
  EXPECT_EQ(SceneMetricName(SceneMetric::kUdiMean), "udi_mean");
  EXPECT_FALSE(SceneMetricFromName("udi").ok());
  SceneMetrics scene;
  scene.cda_mean_percent = 42;
  EXPECT_EQ(SceneMetricValue(scene, SceneMetric::kCdaMean), 42);
}

}  // namespace
}  // namespace fenestra
