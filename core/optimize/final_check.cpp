#include "core/optimize/final_check.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <utility>

#include "absl/strings/str_cat.h"
#include "core/common/seconds.h"
#include "core/common/status_macros.h"
#include "core/dc/one_stage.h"

namespace fenestra {
namespace {

// Mixed into the job's seed so that the pilot and the check trace streams of their own: the
// stages key theirs with the seed itself, and the indoor stage's (seed, sensor, path) streams
// would otherwise start the one-stage paths in the same directions.
constexpr uint64_t kPilotSeedKey = 0x9E3779B97F4A7C15;
constexpr uint64_t kCheckSeedKey = 0xD1B54A32D192ED03;

int64_t RoundUp(int64_t n, int64_t multiple) { return (n + multiple - 1) / multiple * multiple; }

// One one-stage trace of `design` without a reflection limit, reduced to the metric.
absl::StatusOr<Evaluation> TraceMetric(const Scene& scene, const BlindDesign& design,
                                       int64_t paths_per_sensor, uint64_t seed, int batches,
                                       Sequence sequence, bool with_direct_part,
                                       const DaylightMetric& metric, DcBackend* backend) {
  OneStageOptions options;
  options.sequence = sequence;
  options.paths_per_sensor = paths_per_sensor;
  options.max_bounces = kUnlimitedBounces;  // Russian roulette alone ends the paths
  options.seed = seed;
  options.batches = batches;
  FENESTRA_ASSIGN_OR_RETURN(result, ComputeOneStage(scene, design, options, backend));
  if (!with_direct_part) return metric(result.batch_coefficients);
  std::vector<Matrix> split;
  for (size_t b = 0; b < result.batch_coefficients.size(); ++b) {
    const Matrix& d = result.batch_coefficients[b];
    Matrix both(d.rows(), 2 * d.cols());
    both << d, result.batch_direct_coefficients[b];
    split.push_back(std::move(both));
  }
  return metric(split);
}

}  // namespace

v1::FinalCheck CompareWithCheck(const v1::Estimate& two_stage, const v1::Estimate& one_stage) {
  v1::FinalCheck check;
  *check.mutable_two_stage() = two_stage;
  *check.mutable_one_stage() = one_stage;
  const double difference = one_stage.value() - two_stage.value();
  const double standard_error = std::hypot(two_stage.standard_error(), one_stage.standard_error());
  check.mutable_difference()->set_value(difference);
  check.mutable_difference()->set_standard_error(standard_error);
  check.set_disagrees(std::abs(difference) >
                      kFinalCheckDisagreementStandardErrors * standard_error);
  return check;
}

int64_t CheckPathsPerSensor(int64_t pilot_paths, double pilot_standard_error,
                            double target_standard_error, int64_t max_paths, int batches,
                            bool* limited) {
  const int64_t most = std::max(pilot_paths, max_paths);
  // SE ~ 1/sqrt(paths); a target of 0 asks for infinitely many
  double wanted = static_cast<double>(pilot_paths);
  if (pilot_standard_error > 0 && std::isfinite(pilot_standard_error)) {
    const double ratio = pilot_standard_error / target_standard_error;
    wanted *= ratio * ratio;
  }
  const bool capped = !(wanted <= static_cast<double>(most));
  if (limited != nullptr) *limited = capped;
  const int64_t paths =
      capped ? most : std::max(pilot_paths, static_cast<int64_t>(std::ceil(wanted)));
  return RoundUp(paths, std::max(1, batches));
}

absl::StatusOr<FinalCheckOutcome> RunFinalCheck(const Scene& scene, const BlindDesign& design,
                                                const v1::Estimate& two_stage,
                                                const DaylightMetric& metric,
                                                const FinalCheckOptions& options,
                                                DcBackend* backend) {
  const auto start = std::chrono::steady_clock::now();
  if (options.batches < 2) {
    return absl::InvalidArgumentError(
        absl::StrCat("the final check needs at least 2 batches, got ", options.batches));
  }
  const auto cancelled = [&] { return options.cancelled && options.cancelled(); };
  const int64_t sensors = std::max<int64_t>(1, static_cast<int64_t>(scene.sensors.size()));
  const int64_t pilot_paths =
      RoundUp(std::max(kFinalCheckMinPathsPerSensor, kFinalCheckPilotPaths / sensors),
              kFinalCheckPilotBatches);
  const int64_t max_paths = std::max(pilot_paths, kFinalCheckMaxPaths / sensors);

  // The pilot: how the one-stage metric's error goes with paths
  if (cancelled()) return absl::CancelledError("cancelled before the final check");
  FENESTRA_ASSIGN_OR_RETURN(
      pilot,
      TraceMetric(scene, design, pilot_paths, options.seed ^ kPilotSeedKey, kFinalCheckPilotBatches,
                  options.sequence, options.with_direct_part, metric, backend));
  bool limited = false;
  const int64_t paths =
      CheckPathsPerSensor(pilot_paths, pilot.standard_error, two_stage.standard_error(), max_paths,
                          options.batches, &limited);

  // The check itself, with streams of its own
  if (cancelled()) return absl::CancelledError("cancelled during the final check");
  FENESTRA_ASSIGN_OR_RETURN(
      one_stage, TraceMetric(scene, design, paths, options.seed ^ kCheckSeedKey, options.batches,
                             options.sequence, options.with_direct_part, metric, backend));
  v1::Estimate estimate;
  estimate.set_value(one_stage.value);
  estimate.set_standard_error(one_stage.standard_error);
  FinalCheckOutcome outcome;
  outcome.check = CompareWithCheck(two_stage, estimate);
  outcome.check.set_paths_per_sensor(paths);
  outcome.check.set_pilot_paths_per_sensor(pilot_paths);
  outcome.check.set_paths_limited(limited);
  outcome.check.set_seconds(SecondsSince(start));
  outcome.one_stage = std::move(one_stage);
  return outcome;
}

}  // namespace fenestra
