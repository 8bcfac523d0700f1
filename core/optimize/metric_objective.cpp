#include "core/optimize/metric_objective.h"

#include <utility>

namespace fenestra {

Evaluation MetricEvaluation(AnnualMetricsEstimate estimate, SceneMetric metric,
                            std::span<const SceneMetric> constraint_metrics) {
  Evaluation evaluation;
  evaluation.value = SceneMetricValue(estimate.value.scene, metric);
  evaluation.standard_error = SceneMetricValue(estimate.standard_error.scene, metric);
  for (const SceneMetric m : constraint_metrics) {
    evaluation.constraints.push_back({SceneMetricValue(estimate.value.scene, m),
                                      SceneMetricValue(estimate.standard_error.scene, m)});
  }
  evaluation.payload = std::move(estimate);
  return evaluation;
}

}  // namespace fenestra
