// Glue between the annual metrics and the search: one scene metric as the objective value.
#pragma once

#include <span>

#include "core/metrics/annual_metrics.h"
#include "core/metrics/metric_errors.h"
#include "core/optimize/vns.h"

namespace fenestra {

// The value and jackknife standard error of `metric` from `estimate`, and those of each of
// `constraint_metrics` (Evaluation::constraints, in their order); `estimate` becomes the
// payload (read it back with std::any_cast<const AnnualMetricsEstimate&>).
Evaluation MetricEvaluation(AnnualMetricsEstimate estimate, SceneMetric metric,
                            std::span<const SceneMetric> constraint_metrics = {});

}  // namespace fenestra
