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

// Every number of two results, exactly.
void ExpectSameMetrics(const AnnualMetrics& a, const AnnualMetrics& b) {
  EXPECT_EQ(a.analysed_hours, b.analysed_hours);
  EXPECT_EQ(a.has_ase, b.has_ase);
  ASSERT_EQ(a.sensors.size(), b.sensors.size());
  for (size_t i = 0; i < a.sensors.size(); ++i) {
    const SensorMetrics &s = a.sensors[i], &t = b.sensors[i];
    EXPECT_EQ(s.udi_percent, t.udi_percent) << i;
    EXPECT_EQ(s.udi_fell_short_percent, t.udi_fell_short_percent) << i;
    EXPECT_EQ(s.udi_exceeded_percent, t.udi_exceeded_percent) << i;
    EXPECT_EQ(s.da_percent, t.da_percent) << i;
    EXPECT_EQ(s.cda_percent, t.cda_percent) << i;
    EXPECT_EQ(s.mean_illuminance_lux, t.mean_illuminance_lux) << i;
    EXPECT_EQ(s.ase_hours, t.ase_hours) << i;
  }
  for (SceneMetric metric :
       {SceneMetric::kUdiAll, SceneMetric::kUdiAllFellShort, SceneMetric::kUdiAllExceeded,
        SceneMetric::kUdiMean, SceneMetric::kUdiMeanFellShort, SceneMetric::kUdiMeanExceeded,
        SceneMetric::kDaMean, SceneMetric::kCdaMean, SceneMetric::kSda, SceneMetric::kAse,
        SceneMetric::kMeanIlluminance}) {
    EXPECT_EQ(SceneMetricValue(a.scene, metric), SceneMetricValue(b.scene, metric))
        << SceneMetricName(metric);
  }
}

// Sensor 0 has hours at both UDI limits and at the DA threshold, sensor 1 is always dark
// (out of range), sensor 2 in range but for one hour.
const std::vector<std::vector<double>> kTallyCase = {
    {100, 3000, 99.9, 3000.5, 300, 299.9, 0, 5000, 1500, 50},
    std::vector<double>(10, 0),
    {500, 500, 500, 500, 500, 500, 500, 500, 500, 4000}};

TEST(AnnualMetricsTest, TallyCountsEachSensorAndHour) {
  const Matrix e = OneDay(kTallyCase)(Eigen::all, Eigen::seq(2, 11));  // the occupied hours
  const HourTally t = TallyHours(e, MetricOptions{});
  EXPECT_EQ(t.hours, 10);
  ASSERT_EQ(t.sensors.size(), 3u);
  EXPECT_EQ(t.sensors[0].below, 3);  // 99.9, 0, 50
  EXPECT_EQ(t.sensors[0].above, 2);  // 3000.5, 5000
  EXPECT_EQ(t.sensors[0].da, 5);     // 3000, 3000.5, 300, 5000, 1500
  EXPECT_NEAR(t.sensors[0].credit, 5 + (100 + 99.9 + 299.9 + 50) / 300.0, 1e-12);
  EXPECT_NEAR(t.sensors[0].sum, 13350.3, 1e-9);
  EXPECT_EQ(t.sensors[1].below, 10);
  EXPECT_EQ(t.sensors[1].da, 0);
  EXPECT_EQ(t.sensors[1].credit, 0);
  EXPECT_EQ(t.sensors[2].above, 1);
  EXPECT_EQ(t.sensors[2].da, 10);
  EXPECT_EQ(t.sensors[2].credit, 10);
  EXPECT_EQ(t.sensors[2].sum, 8500);
  // Sensor 1 is below in every hour
  EXPECT_EQ(t.all_in, 0);
  EXPECT_EQ(t.any_below, 10);
  EXPECT_EQ(t.any_above, 3);
  // Without it, sensors 0 and 2 are both in range in hours 0, 1, 4, 5, 8
  const std::vector<int> rows = {0, 2};
  const HourTally two = TallyHours(e(rows, Eigen::all), MetricOptions{});
  EXPECT_EQ(two.all_in, 5);
  EXPECT_EQ(two.any_below, 3);
  EXPECT_EQ(two.any_above, 3);
}

TEST(AnnualMetricsTest, MetricsFromTallyCountDarkHoursAsComputeAnnualMetricsDoes) {
  // Two days: the first day's occupied hours lit, the second's dark
  const Matrix e = OneDay(kTallyCase);
  const Matrix lit = e(Eigen::all, Eigen::seq(2, 11));
  const std::vector<bool> occupied = Occupied(2);
  MetricOptions zero_lower;
  zero_lower.udi_lower_lux = 0;  // dark hours in range
  for (const MetricOptions& options : {MetricOptions{}, zero_lower}) {
    absl::StatusOr<AnnualMetrics> expected =
        ComputeAnnualMetrics(e, DaytimeColumns(1), occupied, options);
    ASSERT_TRUE(expected.ok()) << expected.status();
    const AnnualMetrics m = MetricsFromTally(TallyHours(lit, options), 20, options);
    ExpectSameMetrics(m, *expected);
    // The analysed hours beyond the tally are E = 0 exactly
    Matrix with_dark = Matrix::Zero(3, 20);
    with_dark.leftCols(10) = lit;
    ExpectSameMetrics(MetricsFromTally(TallyHours(with_dark, options), 20, options), m);
  }

  // By hand, with the default options
  const AnnualMetrics m = MetricsFromTally(TallyHours(lit, MetricOptions{}), 20, MetricOptions{});
  EXPECT_EQ(m.analysed_hours, 20);
  EXPECT_DOUBLE_EQ(m.sensors[0].udi_percent, 25);
  EXPECT_DOUBLE_EQ(m.sensors[0].udi_fell_short_percent, 65);
  EXPECT_DOUBLE_EQ(m.sensors[0].udi_exceeded_percent, 10);
  EXPECT_DOUBLE_EQ(m.sensors[0].da_percent, 25);
  EXPECT_NEAR(m.sensors[0].mean_illuminance_lux, 13350.3 / 20, 1e-9);
  EXPECT_DOUBLE_EQ(m.sensors[1].udi_fell_short_percent, 100);
  EXPECT_DOUBLE_EQ(m.sensors[2].udi_percent, 45);
  EXPECT_DOUBLE_EQ(m.sensors[2].cda_percent, 50);
  EXPECT_DOUBLE_EQ(m.scene.udi_all_percent, 0);
  EXPECT_DOUBLE_EQ(m.scene.udi_all_fell_short_percent, 100);
  EXPECT_DOUBLE_EQ(m.scene.udi_all_exceeded_percent, 15);
  EXPECT_DOUBLE_EQ(m.scene.sda_percent, 100.0 / 3);  // sensor 2 only
  EXPECT_FALSE(m.has_ase);

  // With the lower limit at 0, the dark sensor and the dark hours are in range
  const AnnualMetrics z = MetricsFromTally(TallyHours(lit, zero_lower), 20, zero_lower);
  EXPECT_DOUBLE_EQ(z.sensors[1].udi_percent, 100);
  EXPECT_DOUBLE_EQ(z.sensors[0].udi_percent, 90);  // 8 lit hours + 10 dark
  EXPECT_DOUBLE_EQ(z.scene.udi_all_percent, 85);   // hours 0, 1, 2, 4, 5, 6, 8 + 10 dark
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
