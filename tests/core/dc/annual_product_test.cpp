#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <memory>
#include <span>
#include <vector>

#include "core/dc/dc_backend.h"
#include "core/dc/two_stage.h"
#include "core/metrics/annual_metrics.h"
#include "core/metrics/illuminance.h"
#include "core/metrics/metric_errors.h"
#include "tests/example_scene.h"

namespace fenestra {
namespace {

// The backend's annual product (I_b O_b) S is each batch's D times the sky.
TEST(AnnualProductTest, IsDTimesTheSky) {
  const Scene scene = LoadExample("city_office");
  IndoorOptions indoor;
  indoor.paths_per_sensor = 4'000;
  indoor.parts = {2, 1};
  OutdoorOptions outdoor;
  outdoor.paths = 2 * 288 * 16;
  outdoor.parts = indoor.parts;
  absl::StatusOr<IndoorResult> i = ComputeIndoorStage(scene, DefaultDesign(scene), indoor);
  absl::StatusOr<OutdoorResult> o = ComputeOutdoorStage(scene, outdoor);
  ASSERT_TRUE(i.ok() && o.ok());
  absl::StatusOr<TwoStageResult> d = CombineStages(*i, *o);
  ASSERT_TRUE(d.ok());
  const Matrix sky = Matrix::Random(kDaylightBins, 40).cwiseAbs();
  std::unique_ptr<DcBackend> backend = MakeEmbreeBackend();
  absl::StatusOr<std::unique_ptr<AnnualProduct>> product =
      backend->MakeAnnualProduct(o->batches, sky);
  ASSERT_TRUE(product.ok()) << product.status();
  absl::StatusOr<std::vector<Matrix>> e = (*product)->Apply(i->batches);
  ASSERT_TRUE(e.ok()) << e.status();
  ASSERT_EQ(e->size(), i->batches.size());
  for (size_t b = 0; b < e->size(); ++b) {
    const Matrix expected = d->batches[b] * sky;
    EXPECT_LT(((*e)[b] - expected).cwiseAbs().maxCoeff(), 1e-12 * expected.cwiseAbs().maxCoeff());
  }
  // Another sky for one call: its E, and the product's own S after it
  const Matrix other = Matrix::Random(kDaylightBins, 7).cwiseAbs();
  absl::StatusOr<std::vector<Matrix>> e_other = (*product)->ApplyToSky(i->batches, other);
  absl::StatusOr<std::vector<Matrix>> e_again = (*product)->Apply(i->batches);
  ASSERT_TRUE(e_other.ok() && e_again.ok()) << e_other.status();
  for (size_t b = 0; b < e->size(); ++b) {
    const Matrix expected = d->batches[b] * other;
    EXPECT_LT(((*e_other)[b] - expected).cwiseAbs().maxCoeff(),
              1e-12 * expected.cwiseAbs().maxCoeff());
    EXPECT_EQ((*e_again)[b], (*e)[b]);
  }
  EXPECT_EQ((*product)->ApplyToSky(i->batches, Matrix::Zero(10, 4)).status().code(),
            absl::StatusCode::kInvalidArgument);
  // Batches of another window split, or other batch counts, are rejected
  std::vector<Matrix> wrong(i->batches.size(), Matrix::Zero(9, 288));
  EXPECT_EQ((*product)->Apply(wrong).status().code(), absl::StatusCode::kInvalidArgument);
  std::vector<Matrix> fewer(i->batches.begin(), i->batches.end() - 1);
  EXPECT_EQ((*product)->Apply(fewer).status().code(), absl::StatusCode::kInvalidArgument);
  EXPECT_FALSE(backend->MakeAnnualProduct(o->batches, Matrix::Zero(10, 4)).ok());
  EXPECT_FALSE(backend->MakeAnnualProduct({o->coefficients}, sky).ok());
}

// The default tallies are those of the mean and leave-one-out E formed from Apply's E.
TEST(AnnualProductTest, TalliesTheVersionsOfE) {
  const int batches = 4, sensors = 5, cells = 12, hours = 40;
  std::srand(7);
  std::vector<Matrix> outdoor;
  for (int b = 0; b < batches; ++b)
    outdoor.push_back(Matrix::Random(cells, kDaylightBins).cwiseAbs());
  // Hours from dim to bright, so E crosses 100, 300 and 3000 lx
  Matrix sky = Matrix::Random(kDaylightBins, hours).cwiseAbs();
  for (int h = 0; h < hours; ++h) sky.col(h) *= 0.2 * std::pow(1.13, h);
  std::vector<Matrix> indoor;
  for (int b = 0; b < batches; ++b) indoor.push_back(Matrix::Random(sensors, cells).cwiseAbs());
  std::unique_ptr<DcBackend> backend = MakeEmbreeBackend();
  absl::StatusOr<std::unique_ptr<AnnualProduct>> product = backend->MakeAnnualProduct(outdoor, sky);
  ASSERT_TRUE(product.ok()) << product.status();
  absl::StatusOr<std::vector<Matrix>> e = (*product)->Apply(indoor);
  ASSERT_TRUE(e.ok()) << e.status();
  const MetricOptions options;
  absl::StatusOr<std::vector<HourTally>> tallies = (*product)->Tally(indoor, options);
  ASSERT_TRUE(tallies.ok()) << tallies.status();
  ASSERT_EQ(tallies->size(), batches + 1u);

  Matrix mean = Matrix::Zero(sensors, hours);
  for (const Matrix& e_b : *e) mean += e_b;
  mean /= batches;
  EXPECT_LT(mean.minCoeff(), 100);
  EXPECT_GT(mean.maxCoeff(), 3000);
  for (int v = 0; v <= batches; ++v) {
    SCOPED_TRACE(v);
    const Matrix version = v == 0 ? mean : Matrix((batches * mean - (*e)[v - 1]) / (batches - 1.0));
    const HourTally expected = TallyHours(version, options);
    const HourTally& got = (*tallies)[v];
    EXPECT_EQ(got.hours, hours);
    EXPECT_EQ(got.all_in, expected.all_in);
    EXPECT_EQ(got.any_below, expected.any_below);
    EXPECT_EQ(got.any_above, expected.any_above);
    ASSERT_EQ(got.sensors.size(), static_cast<size_t>(sensors));
    for (int i = 0; i < sensors; ++i) {
      EXPECT_EQ(got.sensors[i].below, expected.sensors[i].below);
      EXPECT_EQ(got.sensors[i].above, expected.sensors[i].above);
      EXPECT_EQ(got.sensors[i].da, expected.sensors[i].da);
      EXPECT_NEAR(got.sensors[i].credit, expected.sensors[i].credit, 1e-9);
      EXPECT_NEAR(got.sensors[i].sum, expected.sensors[i].sum, 1e-9 * expected.sensors[i].sum);
    }
  }
  // Each E_b is batch b through its own O_b
  for (int b = 0; b < batches; ++b) {
    const Matrix expected = indoor[b] * outdoor[b] * sky;
    EXPECT_LT(((*e)[b] - expected).cwiseAbs().maxCoeff(), 1e-12 * expected.cwiseAbs().maxCoeff());
  }
  // Another batch count, or a batch of another window split, is rejected
  EXPECT_EQ((*product)->Tally({indoor[0]}, options).status().code(),
            absl::StatusCode::kInvalidArgument);
  std::vector<Matrix> wrong = indoor;
  wrong[0] = Matrix::Zero(sensors, cells + 1);
  EXPECT_EQ((*product)->Tally(wrong, options).status().code(), absl::StatusCode::kInvalidArgument);
}

// The metrics and errors of one-stage D_b times the sky's analysed columns in lux, directly.
absl::StatusOr<AnnualMetricsEstimate> DirectMetrics(std::span<const Matrix> dc,
                                                    const Matrix& radiance,
                                                    const std::vector<int>& columns,
                                                    const std::vector<bool>& occupied,
                                                    const MetricOptions& options) {
  return AnnualMetricsWithErrors(dc, std::span<const Matrix>(&radiance, 1), columns, occupied,
                                 options);
}

void ExpectSameMetrics(const AnnualMetricsEstimate& direct, const AnnualMetricsEstimate& tallied) {
  const SceneMetrics& a = direct.value.scene;
  const SceneMetrics& b = tallied.value.scene;
  EXPECT_GT(a.udi_mean_percent, 0);
  EXPECT_LT(a.udi_mean_percent, 100);
  EXPECT_GT(a.udi_mean_fell_short_percent, 0);
  EXPECT_GT(a.udi_mean_exceeded_percent, 0);
  EXPECT_NEAR(b.udi_mean_percent, a.udi_mean_percent, 1e-9);
  EXPECT_NEAR(b.udi_mean_fell_short_percent, a.udi_mean_fell_short_percent, 1e-9);
  EXPECT_NEAR(b.udi_all_percent, a.udi_all_percent, 1e-9);
  EXPECT_NEAR(b.da_mean_percent, a.da_mean_percent, 1e-9);
  EXPECT_NEAR(b.cda_mean_percent, a.cda_mean_percent, 1e-9);
  EXPECT_NEAR(b.mean_illuminance_lux, a.mean_illuminance_lux, 1e-9 * a.mean_illuminance_lux);
  const SceneMetrics& ea = direct.standard_error.scene;
  const SceneMetrics& eb = tallied.standard_error.scene;
  EXPECT_GT(ea.udi_mean_percent, 0);
  EXPECT_NEAR(eb.udi_mean_percent, ea.udi_mean_percent, 1e-9);
  EXPECT_NEAR(eb.cda_mean_percent, ea.cda_mean_percent, 1e-9);
}

// One-stage coefficients through the product of the sky alone (as a job's final check takes
// them, its pilot's 32 batches and then the check's 8 through one product): the metrics and
// errors of D_b times the sky's analysed columns in lux.
TEST(AnnualProductTest, TheSkysProductGivesTheMetricsOfDTimesTheSky) {
  const int batches = 32, sensors = 4, steps = 300;
  std::srand(11);
  std::vector<Matrix> dc;
  // Batches that differ by up to a factor of 3, so that the leave-one-out versions cross the
  // thresholds at different hours
  for (int b = 0; b < batches; ++b) {
    dc.push_back((1.0 + std::abs(Matrix::Random(1, 1)(0, 0))) *
                 Matrix::Random(sensors, kDaylightBins).cwiseAbs());
  }
  // Radiance from dim to bright, and every third step unoccupied
  Matrix radiance = Matrix::Random(kDaylightBins, steps).cwiseAbs();
  for (int h = 0; h < steps; ++h) radiance.col(h) *= 1e-3 * std::pow(1.03, h);
  std::vector<bool> occupied(steps);
  std::vector<int> columns;
  for (int h = 0; h < steps; ++h) {
    occupied[h] = h % 3 != 0;
    if (occupied[h]) columns.push_back(h);
  }
  Matrix lit_sky(kDaylightBins, static_cast<Eigen::Index>(columns.size()));
  for (size_t c = 0; c < columns.size(); ++c) {
    lit_sky.col(c) = kWhiteEfficacyLumensPerWatt * radiance.col(columns[c]);
  }
  const MetricOptions options;
  std::unique_ptr<DcBackend> backend = MakeEmbreeBackend();
  absl::StatusOr<std::unique_ptr<AnnualProduct>> product = backend->MakeSkyProduct(lit_sky);
  ASSERT_TRUE(product.ok()) << product.status();
  for (const int count : {batches, 8}) {
    SCOPED_TRACE(count);
    const std::vector<Matrix> some(dc.begin(), dc.begin() + count);
    absl::StatusOr<AnnualMetricsEstimate> direct =
        DirectMetrics(some, radiance, columns, occupied, options);
    ASSERT_TRUE(direct.ok()) << direct.status();
    absl::StatusOr<std::vector<HourTally>> versions = (*product)->Tally(some, options);
    ASSERT_TRUE(versions.ok()) << versions.status();
    absl::StatusOr<AnnualMetricsEstimate> tallied =
        AnnualMetricsFromTallies(*versions, AnalysedHours(occupied, options.hours), options);
    ASSERT_TRUE(tallied.ok()) << tallied.status();
    ExpectSameMetrics(*direct, *tallied);
  }
  // One batch has no error; coefficients of other columns, or a sky of other rows, are refused
  EXPECT_EQ((*product)->Tally({dc[0]}, options).status().code(),
            absl::StatusCode::kInvalidArgument);
  EXPECT_EQ((*product)->Tally({dc[0], Matrix::Zero(sensors, 288)}, options).status().code(),
            absl::StatusCode::kInvalidArgument);
  EXPECT_EQ(backend->MakeSkyProduct(Matrix::Zero(10, 4)).status().code(),
            absl::StatusCode::kInvalidArgument);
}

}  // namespace
}  // namespace fenestra
