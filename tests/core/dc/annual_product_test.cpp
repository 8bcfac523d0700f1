#include <gtest/gtest.h>

#include <memory>
#include <vector>

#include "core/dc/dc_backend.h"
#include "core/dc/two_stage.h"
#include "tests/example_scene.h"

namespace fenestra {
namespace {

// The backend's annual product (I_b O) S is each batch's D times the sky.
TEST(AnnualProductTest, IsDTimesTheSky) {
  const Scene scene = LoadExample("city_office");
  IndoorOptions indoor;
  indoor.paths_per_sensor = 4'000;
  indoor.parts = {2, 1};
  OutdoorOptions outdoor;
  outdoor.paths = 2 * 288 * 20;
  outdoor.parts = indoor.parts;
  absl::StatusOr<IndoorResult> i = ComputeIndoorStage(scene, DefaultDesign(scene), indoor);
  absl::StatusOr<OutdoorResult> o = ComputeOutdoorStage(scene, outdoor);
  ASSERT_TRUE(i.ok() && o.ok());
  absl::StatusOr<TwoStageResult> d = CombineStages(*i, *o);
  ASSERT_TRUE(d.ok());
  const Matrix sky = Matrix::Random(kDaylightBins, 40).cwiseAbs();
  std::unique_ptr<DcBackend> backend = MakeEmbreeBackend();
  absl::StatusOr<std::unique_ptr<AnnualProduct>> product =
      backend->MakeAnnualProduct(o->coefficients, sky);
  ASSERT_TRUE(product.ok()) << product.status();
  absl::StatusOr<std::vector<Matrix>> e = (*product)->Apply(i->batches);
  ASSERT_TRUE(e.ok()) << e.status();
  ASSERT_EQ(e->size(), i->batches.size());
  for (size_t b = 0; b < e->size(); ++b) {
    const Matrix expected = d->batches[b] * sky;
    EXPECT_LT(((*e)[b] - expected).cwiseAbs().maxCoeff(), 1e-12 * expected.cwiseAbs().maxCoeff());
  }
  // Batches of another window split are rejected
  std::vector<Matrix> wrong = {Matrix::Zero(9, 288)};
  EXPECT_EQ((*product)->Apply(wrong).status().code(), absl::StatusCode::kInvalidArgument);
  EXPECT_FALSE(backend->MakeAnnualProduct(o->coefficients, Matrix::Zero(10, 4)).ok());
}

}  // namespace
}  // namespace fenestra
