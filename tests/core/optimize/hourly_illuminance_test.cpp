#include "core/optimize/hourly_illuminance.h"

#include <gtest/gtest.h>

#include <cmath>

#include "core/metrics/annual_metrics.h"
#include "core/metrics/occupancy.h"
#include "core/optimize/job.h"
#include "core/sky/epw.h"
#include "tests/example_scene.h"
#include "tests/quick_job.h"

namespace fenestra {
namespace {

// E as a sensors x steps matrix.
Matrix HourlyMatrix(const v1::HourlyIlluminance& hourly) {
  const int sensors = hourly.sensors_size(), steps = hourly.month_size();
  Matrix e(sensors, steps);
  for (int i = 0; i < sensors; ++i) {
    for (int j = 0; j < steps; ++j) e(i, j) = hourly.illuminance_lux(i * steps + j);
  }
  return e;
}

TEST(HourlyIlluminanceTest, TheResultHoldsTheBestDesignsIlluminanceEveryHour) {
  const v1::JobResult& result = QuickJobResult();
  ASSERT_TRUE(result.has_best_hourly());
  const v1::HourlyIlluminance& hourly = result.best_hourly();
  ASSERT_EQ(hourly.sensors_size(), 9);
  EXPECT_EQ(hourly.sensors(0), "S1");
  ASSERT_EQ(hourly.month_size(), 8760);
  ASSERT_EQ(hourly.illuminance_lux_size(), 9 * 8760);
  ASSERT_EQ(hourly.standard_error_lux_size(), 9 * 8760);
  EXPECT_EQ(hourly.month(0), 1);
  EXPECT_EQ(hourly.day(0), 1);
  EXPECT_EQ(hourly.hour(0), 0.5);
  EXPECT_EQ(hourly.month(8759), 12);
  EXPECT_EQ(hourly.day(8759), 31);
  EXPECT_EQ(hourly.hour(8759), 23.5);
  // Midnight is dark, noon is not; errors are finite and small against the values
  for (int i = 0; i < 9; ++i) {
    EXPECT_EQ(hourly.illuminance_lux(i * 8760), 0.0f);
    EXPECT_EQ(hourly.standard_error_lux(i * 8760), 0.0f);
    const int noon = i * 8760 + 11;  // 1 January, 11:00-12:00
    EXPECT_GT(hourly.illuminance_lux(noon), 0.0f);
    EXPECT_GT(hourly.standard_error_lux(noon), 0.0f);
    EXPECT_LT(hourly.standard_error_lux(noon), hourly.illuminance_lux(noon));
  }
}

// The metrics of the hourly illuminance are the best design's metrics: the same E
TEST(HourlyIlluminanceTest, ItsMetricsAreTheBestDesignsMetrics) {
  const v1::JobResult& result = QuickJobResult();
  const v1::HourlyIlluminance& hourly = result.best_hourly();
  const v1::MetricSettings& settings = result.job().metrics();
  const std::vector<double> hours(hourly.hour().begin(), hourly.hour().end());
  absl::StatusOr<std::vector<bool>> occupied =
      OccupiedSteps(hours, {settings.occupied_start_h(), settings.occupied_end_h()});
  ASSERT_TRUE(occupied.ok()) << occupied.status();
  std::vector<int> columns(hours.size());
  for (size_t j = 0; j < hours.size(); ++j) columns[j] = static_cast<int>(j);
  absl::StatusOr<AnnualMetrics> metrics =
      ComputeAnnualMetrics(HourlyMatrix(hourly), columns, *occupied, MetricOptions());
  ASSERT_TRUE(metrics.ok()) << metrics.status();
  // Stored as float: an hour right at a limit may flip, no more
  const double one_hour = 100.0 / metrics->analysed_hours;
  for (int i = 0; i < 9; ++i) {
    EXPECT_NEAR(metrics->sensors[i].udi_percent, result.best_metrics().sensor_udi(i).value(),
                one_hour + 1e-9)
        << hourly.sensors(i);
    EXPECT_NEAR(metrics->sensors[i].da_percent, result.best_metrics().sensor_da(i).value(),
                one_hour + 1e-9)
        << hourly.sensors(i);
  }
}

TEST(HourlyIlluminanceTest, TheResultSaysHowItWasMade) {
  const v1::JobResult& result = QuickJobResult();
  EXPECT_EQ(result.job().scene_file(), "");
  EXPECT_EQ(result.job().weather_file(), "");
  EXPECT_EQ(result.job().sampling().indoor_paths_per_sensor(), 2000);
  EXPECT_EQ(result.job().metrics().udi_upper_lux(), 3000);  // defaults filled in
  absl::StatusOr<Scene> scene = BuildScene(result.job().scene(), "result.json");
  ASSERT_TRUE(scene.ok()) << scene.status();
  EXPECT_EQ(scene->sensors.size(), 9u);
  ASSERT_TRUE(scene->blind().has_value());
  EXPECT_EQ(result.weather_location(), "MONTEVIDEO, URY");
  EXPECT_EQ(result.versions().at("fenestra"), "0.1.0");
  EXPECT_TRUE(result.versions().contains("embree"));
}

// Two seeds of both stages differ by about their standard errors, which hold both stages'
// noise
TEST(HourlyIlluminanceTest, StandardErrorsMatchTheSpreadBetweenSeeds) {
  const Scene scene = LoadExample("city_office");
  absl::StatusOr<v1::Sampling> sampling = ResolveSampling(QuickJob().sampling());
  ASSERT_TRUE(sampling.ok()) << sampling.status();
  absl::StatusOr<EpwData> weather = ReadEpw(scene.site.weather_file);
  ASSERT_TRUE(weather.ok()) << weather.status();
  absl::StatusOr<SkyMatrix> sky = BuildSkyMatrix(*weather);
  ASSERT_TRUE(sky.ok()) << sky.status();
  IndoorOptions options;
  options.paths_per_sensor = 2000;
  options.batches = sampling->batches();
  BlindDesign design = DefaultDesign(scene);
  design.tilt_rad = 0.5;
  std::unique_ptr<DcBackend> backend = MakeEmbreeBackend();
  std::vector<v1::HourlyIlluminance> runs;
  for (const uint64_t seed : {1, 2}) {
    sampling->set_seed(seed);
    absl::StatusOr<OutdoorMatrix> outdoor = ComputeOutdoorMatrix(scene, *sampling);
    ASSERT_TRUE(outdoor.ok()) << outdoor.status();
    options.parts = outdoor->parts;
    options.seed = seed;
    absl::StatusOr<IndoorResult> indoor = ComputeIndoorStage(scene, design, options, backend.get());
    ASSERT_TRUE(indoor.ok()) << indoor.status();
    absl::StatusOr<std::unique_ptr<AnnualProduct>> product =
        backend->MakeAnnualProduct(outdoor->batches, Matrix::Zero(kDaylightBins, 1));
    ASSERT_TRUE(product.ok()) << product.status();
    absl::StatusOr<v1::HourlyIlluminance> hourly = DesignHourlyIlluminance(
        scene, *sky,
        [&](const Matrix& lux) { return (*product)->ApplyToSky(indoor->batches, lux); }, {});
    ASSERT_TRUE(hourly.ok()) << hourly.status();
    runs.push_back(*std::move(hourly));
  }
  double sum_z2 = 0;
  int count = 0;
  for (int k = 0; k < runs[0].illuminance_lux_size(); ++k) {
    const double se = std::hypot(runs[0].standard_error_lux(k), runs[1].standard_error_lux(k));
    if (se == 0) continue;
    const double z = (runs[0].illuminance_lux(k) - runs[1].illuminance_lux(k)) / se;
    sum_z2 += z * z;
    ++count;
  }
  ASSERT_GT(count, 9 * 4000);
  // E[z²] = 1.4 with errors from 8 batches (t with 7 degrees of freedom); the hours of one
  // sensor share their paths, so the mean over them scatters more than 9 x 4000 values would
  const double rms = std::sqrt(sum_z2 / count);
  EXPECT_GT(rms, 0.6);
  EXPECT_LT(rms, 2.0);
}

// Errors need two batches or more, each a row per sensor and a column per step with daylight
TEST(HourlyIlluminanceTest, NeedsTwoBatchesOfTheSensorsAndLitSteps) {
  const Scene scene = LoadExample("city_office");
  SkyMatrix sky;
  sky.radiance = Matrix::Zero(kDaylightBins, 3);
  sky.radiance.col(1).setOnes();
  sky.steps.resize(3);
  const Eigen::Index sensors = static_cast<Eigen::Index>(scene.sensors.size());
  const auto returning = [](std::vector<Matrix> batches) {
    return [batches](const Matrix& lux) -> absl::StatusOr<std::vector<Matrix>> {
      EXPECT_EQ(lux.cols(), 1);
      return batches;
    };
  };
  const Matrix one_step = Matrix::Constant(sensors, 1, 100.0);
  EXPECT_EQ(DesignHourlyIlluminance(scene, sky, returning({one_step}), {}).status().code(),
            absl::StatusCode::kInvalidArgument);
  EXPECT_EQ(DesignHourlyIlluminance(scene, sky, returning({one_step, Matrix::Zero(sensors, 2)}), {})
                .status()
                .code(),
            absl::StatusCode::kInvalidArgument);
  absl::StatusOr<v1::HourlyIlluminance> hourly =
      DesignHourlyIlluminance(scene, sky, returning({one_step, 3 * one_step}), {});
  ASSERT_TRUE(hourly.ok()) << hourly.status();
  // The mean of 100 and 300 lx at the lit step, nothing at the others
  ASSERT_EQ(hourly->illuminance_lux_size(), 3 * sensors);
  EXPECT_FLOAT_EQ(hourly->illuminance_lux(1), 200.0f);
  EXPECT_FLOAT_EQ(hourly->standard_error_lux(1), 100.0f);
  EXPECT_EQ(hourly->illuminance_lux(0), 0.0f);
  EXPECT_EQ(hourly->illuminance_lux(2), 0.0f);
}

}  // namespace
}  // namespace fenestra
