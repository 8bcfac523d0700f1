#pragma once

// Monte Carlo tracing in rounds: each round traces more paths with random streams independent
// of every other round's (RoundSeed), and the rounds make one estimate, their mean weighted by
// path counts, whose standard error is that of independent estimates. Tracing to a target
// error adds rounds until every sensor's sky sum (D summed over bins 1..145) has a relative
// standard error at most the target.
#include <Eigen/Core>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "absl/status/statusor.h"
#include "core/dc/dc_backend.h"
#include "core/dc/two_stage.h"
#include "core/geometry/scene.h"

namespace fenestra {

// The seed of round `round` (0, 1, ...) of a run seeded `seed`: round 0 keeps `seed`, so a
// run of one round is the plain run; later rounds get other Philox keys, hence streams
// independent of every other round's.
uint64_t RoundSeed(uint64_t seed, int round);

// Two independent estimates of the same quantity as one: the mean weighted by path counts,
// standard errors sqrt(w_a^2 se_a^2 + w_b^2 se_b^2), counts and times added. The stages'
// batches are merged batch by batch (so they stay independent, alike and paired) and their
// standard errors come from their scatter, as for one trace. InvalidArgument when the shapes,
// bases, window parts or batch counts differ. The merge is made in b's matrices: pass the
// later round by std::move, as the stages' batches are large.
absl::StatusOr<OneStageResult> MergeRounds(const OneStageResult& a, OneStageResult b);
absl::StatusOr<OutdoorResult> MergeRounds(const OutdoorResult& a, OutdoorResult b);
absl::StatusOr<IndoorResult> MergeRounds(const IndoorResult& a, IndoorResult b);

// Per sensor: standard error / sky sum; 0 where both are 0 (no light reached the sensor),
// +inf where only the sum is 0.
Eigen::VectorXd RelativeErrors(const Eigen::VectorXd& sky_sum,
                               const Eigen::VectorXd& sky_sum_standard_error);

// Per sensor: the variance of D's sky sum from the indoor stage alone, the scatter of the
// batches I_b O through the mean O (to first order; the batch products I_b O_b see both
// stages). The rest of CombineStages' sky_sum_standard_error^2 is the outdoor stage's.
Eigen::VectorXd IndoorSkySumVariance(const IndoorResult& indoor, const OutdoorResult& outdoor);

// When tracing to a target error stops.
struct TargetErrorOptions {
  // Every sensor's sky-sum relative standard error must reach at most this, in (0, 1).
  double relative_error = 0.02;
  // Wall-clock limit of the tracing, the first round included [s].
  double max_seconds = 600;
  // Paths per sensor at most (one-stage; the indoor stage of the two-stage method).
  int64_t max_paths_per_sensor = 1'000'000'000;
  // Outdoor paths at most (two-stage).
  int64_t max_outdoor_paths = 10'000'000'000;
};

// Each round aims at this fraction of the target, so that the round predicted from the
// standard errors so far (which are themselves estimates) lands at or just below the target
// rather than just above it, which would cost another round.
inline constexpr double kTargetAim = 0.9;
// A round at most multiplies the paths traced so far by this: the standard error of a small
// first round is itself uncertain (rare paths that reach bright sky carry much of the light),
// and an overestimate would overshoot the target; the next round then sizes itself from the
// better estimate of the larger sample.
inline constexpr double kMaxRoundGrowth = 4;

// The state after a round.
struct RoundReport {
  int round = 0;
  int64_t paths_per_sensor = 0;  // so far: one-stage paths, or the indoor stage's
  int64_t outdoor_paths = 0;     // so far (two-stage)
  double elapsed_seconds = 0;    // since the first round started
  double max_relative_error = 0;
  size_t worst_sensor = 0;           // the sensor with that error
  double indoor_variance_share = 0;  // two-stage: of the worst sensor's variance
};

// How tracing to a target ended.
struct TargetOutcome {
  bool reached = false;
  std::string stop_reason;  // why it stopped short; empty when reached
  std::vector<RoundReport> rounds;
};

struct OneStageToTarget {
  OneStageResult result;  // all rounds merged
  TargetOutcome outcome;
};

// One-stage rounds, the first of `first_round.paths_per_sensor` paths, then each sized from
// the errors so far (relative SE ~ 1/sqrt(paths)) to reach kTargetAim x the target, within
// the limits. `on_round` (optional) sees each round's report as it ends. InvalidArgument for
// bad options or a target outside (0, 1).
absl::StatusOr<OneStageToTarget> TraceOneStageToTarget(
    const Scene& scene, const BlindDesign& design, const OneStageOptions& first_round,
    const TargetErrorOptions& target, DcBackend* backend,
    const std::function<void(const RoundReport&)>& on_round = {});

struct TwoStageToTarget {
  OutdoorResult outdoor;  // all outdoor rounds merged
  IndoorResult indoor;    // all indoor rounds merged
  TwoStageResult combined;
  TargetOutcome outcome;
};

// Two-stage rounds: the first traces both stages as `first_outdoor` and `first_indoor` ask;
// each later round multiplies each stage's paths by the factor that reaches kTargetAim x the
// target for every sensor at the least tracing time, from each stage's share of each sensor's
// variance (the indoor share from the batches, the outdoor share the rest of the combined
// error) and its cost per path so far, in closest-hit rays, which unlike seconds are the same
// for a seed on any machine and load (Neyman allocation: paths of stage s in proportion to
// sqrt(variance_s / rays_s)). A stage whose error is already small is not traced again.
absl::StatusOr<TwoStageToTarget> TraceTwoStageToTarget(
    const Scene& scene, const BlindDesign& design, const OutdoorOptions& first_outdoor,
    const IndoorOptions& first_indoor, const TargetErrorOptions& target, DcBackend* backend,
    const std::function<void(const RoundReport&)>& on_round = {});

}  // namespace fenestra
