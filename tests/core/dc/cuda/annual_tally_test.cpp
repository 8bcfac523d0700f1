// The GPU's annual product by each of its I_b O_b kernels (the FP64 tensor cores' and the
// CUDA cores') against the same product on the CPU. Skips without a CUDA device.
#include "core/dc/cuda/annual_tally.h"

#include <gtest/gtest.h>

#include <cstdio>
#include <memory>
#include <string>
#include <vector>

#include "core/common/radiance_matrix.h"
#include "core/trace/path.h"

namespace fenestra {
namespace {

// E = (I_b O_b) S for a batch's rows within one block's row tiles (9 sensors: one design's)
// and across two blocks (40), with k (the window cells) not a multiple of the chunks'.
TEST(CudaAnnualTallyTest, BothKernelsOfIOGiveTheCpuProduct) {
  absl::StatusOr<std::unique_ptr<CudaAnnualTally>> created = CudaAnnualTally::Create(0);
  if (!created.ok()) GTEST_SKIP() << created.status();
  std::unique_ptr<CudaAnnualTally> tally = *std::move(created);
  const int cells = 3456 + kTregenzaBinCount, batches = 3, steps = 50;
  std::srand(5);
  std::vector<Matrix> outdoor;
  std::vector<const double*> outdoor_data;
  for (int b = 0; b < batches; ++b) {
    outdoor.push_back(Matrix::Random(cells, kTregenzaBinCount).cwiseAbs());
    outdoor_data.push_back(outdoor.back().data());
  }
  const Matrix sky = Matrix::Random(kTregenzaBinCount, steps).cwiseAbs();
  ASSERT_EQ(tally->SetProduct(outdoor_data, cells, sky.data(), steps, kTregenzaBinCount),
            absl::OkStatus());
  std::printf("the tensor cores' kernel runs on this device: %s\n",
              tally->UsesTensorCores() ? "yes" : "no (compute capability below 8.0)");
  for (const int sensors : {9, 40}) {
    const int rows = batches * sensors;
    const Matrix indoor = Matrix::Random(rows, cells).cwiseAbs();
    Matrix expected(rows, steps);
    for (int b = 0; b < batches; ++b) {
      expected.middleRows(b * sensors, sensors) =
          indoor.middleRows(b * sensors, sensors) * outdoor[b] * sky;
    }
    for (const bool tensor_cores : {false, true}) {
      tally->UseTensorCores(tensor_cores);
      Matrix e(rows, steps);
      ASSERT_EQ(tally->Illuminance(indoor.data(), rows, e.data()), absl::OkStatus());
      EXPECT_LT((e - expected).cwiseAbs().maxCoeff(), 1e-12 * expected.cwiseAbs().maxCoeff())
          << sensors << " sensors, tensor cores " << tally->UsesTensorCores();
    }
  }
}

}  // namespace
}  // namespace fenestra
