#include "core/optimize/metric_objective.h"

#include <gtest/gtest.h>

#include <any>

namespace fenestra {
namespace {

TEST(MetricObjectiveTest, PicksValueAndErrorAndKeepsTheEstimate) {
  AnnualMetricsEstimate estimate;
  estimate.value.scene.udi_mean_percent = 32;
  estimate.standard_error.scene.udi_mean_percent = 0.4;
  estimate.value.scene.da_mean_percent = 70;
  estimate.batches = 8;
  const Evaluation e = MetricEvaluation(estimate, SceneMetric::kUdiMean);
  EXPECT_EQ(e.value, 32);
  EXPECT_EQ(e.standard_error, 0.4);
  const auto& payload = std::any_cast<const AnnualMetricsEstimate&>(e.payload);
  EXPECT_EQ(payload.value.scene.da_mean_percent, 70);
  EXPECT_EQ(payload.batches, 8);
}

}  // namespace
}  // namespace fenestra
