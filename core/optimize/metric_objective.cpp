#include "core/optimize/metric_objective.h"

#include <utility>

namespace fenestra {

Evaluation MetricEvaluation(AnnualMetricsEstimate estimate, SceneMetric metric) {
  Evaluation evaluation;
  evaluation.value = SceneMetricValue(estimate.value.scene, metric);
  evaluation.standard_error = SceneMetricValue(estimate.standard_error.scene, metric);
  evaluation.payload = std::move(estimate);
  return evaluation;
}

}  // namespace fenestra
