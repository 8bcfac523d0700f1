// The final check of a job (job.proto, FinalCheck): its best design traced again by the
// one-stage method (core/dc/one_stage.h), the whole scene at once, with random streams of its
// own and no reflection limit, and its metric compared with the two-stage value.
//
// How many paths: the check should know the metric about as well as the search did. A
// pilot measures the one-stage metric's standard error at a few paths; a Monte Carlo
// standard error falls as 1/sqrt(paths), so the check traces pilot x (SE_pilot / SE_target)^2
// paths per sensor, within kFinalCheckMaxPaths. A jackknife over B batches knows a standard
// error to about 1/sqrt(2 (B - 1)) (27% at the jobs' 8), and the paths go with its square, so
// the pilot uses more batches; the check itself uses the job's, as the search does. In the
// city office the check's standard error came out within 0.6-1.7 times the target
// (bench/results/final_check_cpu2.txt).
#pragma once

#include <cstdint>
#include <functional>
#include <span>

#include "absl/status/statusor.h"
#include "core/common/radiance_matrix.h"
#include "core/dc/dc_backend.h"
#include "core/dc/two_stage.h"
#include "core/geometry/scene.h"
#include "core/optimize/vns.h"
#include "fenestra/v1/job.pb.h"

namespace fenestra {

// The check disagrees when |one-stage - two-stage| exceeds this many standard errors of the
// difference.
inline constexpr double kFinalCheckDisagreementStandardErrors = 3;
// Paths of the pilot, all sensors together (at least kFinalCheckMinPathsPerSensor each).
inline constexpr int64_t kFinalCheckPilotPaths = 100'000;
inline constexpr int64_t kFinalCheckMinPathsPerSensor = 1'000;
// Batches of the pilot: its standard error known to about 13%.
inline constexpr int kFinalCheckPilotBatches = 32;
// The most paths of the check, all sensors together: about 3 s on 2 CPU cores in the city
// office (bench/results/final_check_cpu2.txt).
inline constexpr int64_t kFinalCheckMaxPaths = 5'000'000;

// The metric and its standard error from B >= 2 batch estimates of the daylight
// coefficients D (each sensors x 146, core/dc/one_stage.h; with
// FinalCheckOptions::with_direct_part [D | D_0], sensors x 292), as the job computes them.
using DaylightMetric =
    std::function<absl::StatusOr<Evaluation>(std::span<const Matrix> dc_batches)>;

struct FinalCheckOptions {
  int batches = kDefaultBatches;  // independent batches of paths, for the jackknife; >= 2
  // Hand the metric each batch's D with its unreflected part D_0 beside it, for a split sky
  // (core/README.md, "Direct sun").
  bool with_direct_part = false;
  // The job's seed: the check's streams are derived from it, apart from the two stages'.
  uint64_t seed = kDefaultSeed;
  Sequence sequence = kDefaultSequence;  // the job's (Sampling.sequence)
  // Polled before each trace; true leaves the check out (Cancelled).
  std::function<bool()> cancelled;
};

// The check of one design: the comparison, and the one-stage evaluation (its payload is
// what the metric function put there).
struct FinalCheckOutcome {
  v1::FinalCheck check;
  Evaluation one_stage;
};

// The difference one_stage - two_stage, its standard error sqrt(se_1^2 + se_2^2) (independent
// estimates) and whether it disagrees (|difference| > kFinalCheckDisagreementStandardErrors
// of it; a non-zero difference with a zero standard error disagrees). Fills two_stage,
// one_stage, difference and disagrees.
v1::FinalCheck CompareWithCheck(const v1::Estimate& two_stage, const v1::Estimate& one_stage);

// Paths per sensor that bring a metric whose standard error is `pilot_standard_error` at
// `pilot_paths` per sensor to `target_standard_error`: at least the pilot's, at most
// max(pilot_paths, max_paths), then rounded up to a multiple of `batches`. Without a spread
// to scale (a pilot standard error of 0) the pilot's; with a target of 0 and a spread, the
// most. `limited` (may be null) tells whether the most was less than needed.
int64_t CheckPathsPerSensor(int64_t pilot_paths, double pilot_standard_error,
                            double target_standard_error, int64_t max_paths, int batches,
                            bool* limited = nullptr);

// Checks `design` of `scene` against the two-stage estimate `two_stage` of the same metric:
// a pilot, then the check's own trace, both by `backend` (the CPU when null) and without a
// reflection limit, each reduced to the metric by `metric`. Cancelled when options.cancelled
// turns true before a trace; the backend's or the metric's errors as they come.
absl::StatusOr<FinalCheckOutcome> RunFinalCheck(const Scene& scene, const BlindDesign& design,
                                                const v1::Estimate& two_stage,
                                                const DaylightMetric& metric,
                                                const FinalCheckOptions& options,
                                                DcBackend* backend = nullptr);

}  // namespace fenestra
