#include "core/dc/rounds.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <utility>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "core/common/seconds.h"
#include "core/common/status_macros.h"
#include "core/dc/backend_support.h"
#include "core/dc/one_stage.h"

namespace fenestra {
namespace {

// A round that would add less than this share of the paths traced so far is not worth its
// start-up (scene preparation, a pilot): the limits stop the run instead.
constexpr double kMinRoundShare = 0.1;

// The weights of a and b in their merge, from their path counts.
std::pair<double, double> Weights(double paths_a, double paths_b) {
  return {paths_a / (paths_a + paths_b), paths_b / (paths_a + paths_b)};
}

// b becomes the mean of a and b weighted by `w`, in place (a round's matrices are large).
template <class M>
void MergeMeanInto(const M& a, M& b, std::pair<double, double> w) {
  b = w.first * a + w.second * b;
}

template <class M>
M MergeErrors(const M& a, const M& b, std::pair<double, double> w) {
  return (w.first * w.first * a.cwiseAbs2() + w.second * w.second * b.cwiseAbs2()).cwiseSqrt();
}

absl::Status SameShape(const Matrix& a, const Matrix& b, const char* what) {
  if (a.rows() != b.rows() || a.cols() != b.cols()) {
    return absl::InvalidArgumentError(absl::StrCat("rounds of different shapes: ", what, " ",
                                                   a.rows(), "x", a.cols(), " and ", b.rows(), "x",
                                                   b.cols()));
  }
  return absl::OkStatus();
}

absl::Status CheckTarget(const TargetErrorOptions& target) {
  if (!(target.relative_error > 0 && target.relative_error < 1)) {
    return absl::InvalidArgumentError(
        absl::StrCat("target relative error must be in (0, 1), got ", target.relative_error));
  }
  if (!(target.max_seconds > 0)) {
    return absl::InvalidArgumentError("maximum seconds must be positive");
  }
  if (target.max_paths_per_sensor < 2 || target.max_outdoor_paths < 2) {
    return absl::InvalidArgumentError("maximum path counts must be at least 2");
  }
  return absl::OkStatus();
}

// The report of a state: its largest relative error and where.
RoundReport Report(int round, const Eigen::VectorXd& sum, const Eigen::VectorXd& error,
                   double elapsed_seconds) {
  RoundReport report;
  report.round = round;
  report.elapsed_seconds = elapsed_seconds;
  const Eigen::VectorXd relative = RelativeErrors(sum, error);
  if (relative.size() > 0) {
    Eigen::Index worst = 0;
    report.max_relative_error = relative.maxCoeff(&worst);
    report.worst_sensor = static_cast<size_t>(worst);
  }
  return report;
}

std::string StopMessage(const char* limit, double needed_paths_factor, double needed_seconds) {
  return absl::StrFormat(
      "stopped by %s before reaching the target: about %.3g times the paths traced so far "
      "(%.3g s more) would reach it",
      limit, needed_paths_factor, needed_seconds);
}

// Growth factors of the paths of the stages, to be limited by time and counts.
struct Plan {
  std::vector<double> factor;     // paths after the round / paths so far, >= 1 per stage
  std::vector<double> seconds;    // seconds the paths so far took, per stage
  std::vector<double> overhead;   // seconds a round of the stage takes besides its paths
  std::vector<double> paths;      // paths so far, per stage
  std::vector<double> max_paths;  // limits, per stage
};

// Scales the plan's growth, every stage's by one fraction (so the split between the stages
// stays the chosen one), to at most kMaxRoundGrowth, the time left and the path limits; the
// stop reason when too little of a round would remain.
std::string LimitPlan(Plan& plan, double remaining_seconds) {
  double wanted = 1, wanted_seconds = 0, overhead = 0;
  for (size_t s = 0; s < plan.factor.size(); ++s) {
    wanted = std::max(wanted, plan.factor[s]);
    wanted_seconds += (plan.factor[s] - 1) * plan.seconds[s];
    if (plan.factor[s] > 1) overhead += plan.overhead[s];
  }
  double fraction = wanted > kMaxRoundGrowth ? (kMaxRoundGrowth - 1) / (wanted - 1) : 1.0;
  const char* limit = "";
  const double time_left = std::max(0.0, remaining_seconds - overhead);
  if (wanted_seconds * fraction > time_left) {
    fraction = time_left / wanted_seconds;
    limit = "the maximum time";
  }
  for (size_t s = 0; s < plan.factor.size(); ++s) {
    const double room = std::max(0.0, plan.max_paths[s] / plan.paths[s] - 1);
    if (plan.factor[s] > 1 && room < (plan.factor[s] - 1) * fraction) {
      fraction = room / (plan.factor[s] - 1);
      limit = "the maximum path count";
    }
  }
  for (double& f : plan.factor) f = 1 + (f - 1) * fraction;
  if (*limit != '\0' && (wanted - 1) * fraction < kMinRoundShare) {
    return StopMessage(limit, wanted, wanted_seconds);
  }
  return "";
}

// The growth of the (indoor, outdoor) paths that brings every sensor's variance, split into
// x_i (indoor) and y_i (outdoor) in units of its aimed variance, to x_i / a + y_i / b <= 1 at
// the least cost a * indoor_cost + b * outdoor_cost; a, b >= 1.
std::pair<double, double> CheapestGrowth(const Eigen::VectorXd& x, const Eigen::VectorXd& y,
                                         double indoor_cost, double outdoor_cost) {
  // For a given b the least a is fixed; search b on a fine logarithmic grid
  const auto least_a = [&](double b) {
    double a = 1;
    for (Eigen::Index i = 0; i < x.size(); ++i) a = std::max(a, x(i) / (1 - y(i) / b));
    return a;
  };
  const double b_min = std::max(1.0, y.size() > 0 ? y.maxCoeff() * (1 + 1e-6) : 1.0);
  std::pair<double, double> best{least_a(b_min), b_min};
  double best_cost = best.first * indoor_cost + best.second * outdoor_cost;
  for (double b = b_min; b < b_min * 1e6; b *= 1.01) {
    const double a = least_a(b);
    const double cost = a * indoor_cost + b * outdoor_cost;
    if (cost < best_cost) {
      best_cost = cost;
      best = {a, b};
    }
    if (a == 1) break;  // more outdoor paths only cost more
  }
  return best;
}

// Merges the batches of round a into those of round b, batch by batch, weighted by `w`, and
// sets `standard_error` from their scatter about `merged_mean`.
void MergeBatchesInto(const std::vector<Matrix>& a, std::vector<Matrix>& b,
                      std::pair<double, double> w, const Matrix& merged_mean,
                      Matrix& standard_error) {
  const double batches = static_cast<double>(b.size());
  Matrix variance = Matrix::Zero(merged_mean.rows(), merged_mean.cols());
  for (size_t k = 0; k < b.size(); ++k) {
    MergeMeanInto(a[k], b[k], w);
    variance += (b[k] - merged_mean).cwiseAbs2();
  }
  standard_error = (variance / (batches * (batches - 1))).cwiseSqrt();
}

}  // namespace

uint64_t RoundSeed(uint64_t seed, int round) {
  if (round == 0) return seed;
  // SplitMix64 (Steele, Lea & Flood 2014) of seed + round x its increment: a bijection, so
  // distinct rounds of one seed get distinct keys
  uint64_t z = seed + static_cast<uint64_t>(round) * 0x9e3779b97f4a7c15ULL;
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
  return z ^ (z >> 31);
}

absl::StatusOr<OneStageResult> MergeRounds(const OneStageResult& a, OneStageResult b) {
  FENESTRA_RETURN_IF_ERROR(SameShape(a.coefficients, b.coefficients, "D"));
  if (a.batch_coefficients.size() != b.batch_coefficients.size()) {
    return absl::InvalidArgumentError("rounds with different batch counts");
  }
  const auto w = Weights(a.paths_per_sensor, b.paths_per_sensor);
  OneStageResult m = std::move(b);
  MergeMeanInto(a.coefficients, m.coefficients, w);
  m.standard_error = MergeErrors(a.standard_error, m.standard_error, w);
  MergeMeanInto(a.sky_sum, m.sky_sum, w);
  m.sky_sum_standard_error = MergeErrors(a.sky_sum_standard_error, m.sky_sum_standard_error, w);
  for (size_t k = 0; k < m.batch_coefficients.size(); ++k) {
    MergeMeanInto(a.batch_coefficients[k], m.batch_coefficients[k], w);
  }
  m.paths_per_sensor += a.paths_per_sensor;
  m.rays_traced += a.rays_traced;
  m.branches += a.branches;
  m.pilot_paths += a.pilot_paths;
  m.importance_cells = std::max(a.importance_cells, m.importance_cells);
  m.escaped_paths += a.escaped_paths;
  m.roulette_paths += a.roulette_paths;
  m.bounce_limit_paths += a.bounce_limit_paths;
  m.truncated_paths += a.truncated_paths;
  m.max_path_weight = std::max(a.max_path_weight, m.max_path_weight);
  m.wall_seconds += a.wall_seconds;
  return m;
}

absl::StatusOr<OutdoorResult> MergeRounds(const OutdoorResult& a, OutdoorResult b) {
  FENESTRA_RETURN_IF_ERROR(SameShape(a.coefficients, b.coefficients, "O"));
  if (a.basis_cells != b.basis_cells || !(a.parts == b.parts)) {
    return absl::InvalidArgumentError("outdoor rounds with different window cells");
  }
  if (a.batches.size() != b.batches.size() || a.batches.size() < 2) {
    return absl::InvalidArgumentError(
        "outdoor rounds with different batch counts (at least 2 needed)");
  }
  const auto w = Weights(a.paths_per_cell, b.paths_per_cell);
  OutdoorResult m = std::move(b);
  MergeMeanInto(a.coefficients, m.coefficients, w);
  MergeBatchesInto(a.batches, m.batches, w, m.coefficients, m.standard_error);
  MergeMeanInto(a.sky_view, m.sky_view, w);
  m.paths_per_cell += a.paths_per_cell;
  m.rays_traced += a.rays_traced;
  m.wall_seconds += a.wall_seconds;
  return m;
}

absl::StatusOr<IndoorResult> MergeRounds(const IndoorResult& a, IndoorResult b) {
  FENESTRA_RETURN_IF_ERROR(SameShape(a.coefficients, b.coefficients, "I"));
  if (!(a.parts == b.parts) || a.batches.size() != b.batches.size() || a.batches.size() < 2) {
    return absl::InvalidArgumentError(
        "indoor rounds with different window parts or batch counts (at least 2 needed)");
  }
  const auto w = Weights(a.paths_per_sensor, b.paths_per_sensor);
  IndoorResult m = std::move(b);
  MergeMeanInto(a.coefficients, m.coefficients, w);
  MergeBatchesInto(a.batches, m.batches, w, m.coefficients, m.standard_error);
  m.paths_per_sensor += a.paths_per_sensor;
  m.rays_traced += a.rays_traced;
  m.wall_seconds += a.wall_seconds;
  m.trace_seconds += a.trace_seconds;
  return m;
}

Eigen::VectorXd RelativeErrors(const Eigen::VectorXd& sky_sum,
                               const Eigen::VectorXd& sky_sum_standard_error) {
  Eigen::VectorXd relative(sky_sum.size());
  for (Eigen::Index i = 0; i < sky_sum.size(); ++i) {
    const double se = sky_sum_standard_error(i);
    relative(i) = sky_sum(i) > 0 ? se / sky_sum(i)
                  : se > 0       ? std::numeric_limits<double>::infinity()
                                 : 0.0;
  }
  return relative;
}

Eigen::VectorXd IndoorSkySumVariance(const IndoorResult& indoor, const OutdoorResult& outdoor) {
  const Eigen::Index sensors = indoor.coefficients.rows();
  const double batches = static_cast<double>(indoor.batches.size());
  Eigen::VectorXd variance = Eigen::VectorXd::Zero(sensors);
  if (batches < 2 || indoor.coefficients.cols() != outdoor.coefficients.rows()) return variance;
  // The sky sum of I_b O is I_b times O's row sums over the sky bins
  const Eigen::VectorXd sky_rows =
      outdoor.coefficients.rightCols(kDaylightBins - 1).rowwise().sum();
  const Eigen::VectorXd mean = indoor.coefficients * sky_rows;
  for (const Matrix& batch : indoor.batches) variance += (batch * sky_rows - mean).cwiseAbs2();
  return variance / (batches * (batches - 1));
}

absl::StatusOr<OneStageToTarget> TraceOneStageToTarget(
    const Scene& scene, const BlindDesign& design, const OneStageOptions& first_round,
    const TargetErrorOptions& target, DcBackend* backend,
    const std::function<void(const RoundReport&)>& on_round) {
  FENESTRA_RETURN_IF_ERROR(CheckTarget(target));
  const auto start = std::chrono::steady_clock::now();
  OneStageToTarget run;
  OneStageOptions options = first_round;
  options.paths_per_sensor = std::min(options.paths_per_sensor, target.max_paths_per_sensor);
  if (options.weight_windows && options.pilot_paths_per_sensor == 0) {
    // Every round learns its map from the pilot a long run would use: its paths are then as
    // efficient as a long run's, and the error predicted from the first round holds
    OneStageOptions longest = options;
    longest.paths_per_sensor = target.max_paths_per_sensor;
    options.pilot_paths_per_sensor = PilotPathsPerSensor(longest, scene.sensors.size());
  }
  FENESTRA_ASSIGN_OR_RETURN(first, ComputeOneStage(scene, design, options, backend));
  run.result = std::move(first);
  for (int round = 0;; ++round) {
    // Report, stop when reached
    RoundReport report =
        Report(round, run.result.sky_sum, run.result.sky_sum_standard_error, SecondsSince(start));
    report.paths_per_sensor = run.result.paths_per_sensor;
    run.outcome.rounds.push_back(report);
    if (on_round) on_round(report);
    if (report.max_relative_error <= target.relative_error) {
      run.outcome.reached = true;
      return run;
    }

    // Size the next round: relative error ~ 1 / sqrt(paths)
    // and each round's weight-window pilot costs as much as that many paths
    const double paths = static_cast<double>(run.result.paths_per_sensor);
    const double sensors = static_cast<double>(scene.sensors.size());
    const double per_path =
        report.elapsed_seconds / (paths * sensors + static_cast<double>(run.result.pilot_paths));
    const double pilot = run.result.pilot_paths / static_cast<double>(round + 1);
    Plan plan{{std::pow(report.max_relative_error / (kTargetAim * target.relative_error), 2)},
              {per_path * paths * sensors},
              {per_path * pilot},
              {paths},
              {static_cast<double>(target.max_paths_per_sensor)}};
    run.outcome.stop_reason = LimitPlan(plan, target.max_seconds - SecondsSince(start));
    if (!run.outcome.stop_reason.empty()) return run;
    options.paths_per_sensor = std::max<int64_t>(2, std::llround((plan.factor[0] - 1) * paths));
    options.seed = RoundSeed(first_round.seed, round + 1);
    FENESTRA_ASSIGN_OR_RETURN(next, ComputeOneStage(scene, design, options, backend));
    FENESTRA_ASSIGN_OR_RETURN(merged, MergeRounds(run.result, std::move(next)));
    run.result = std::move(merged);
  }
}

absl::StatusOr<TwoStageToTarget> TraceTwoStageToTarget(
    const Scene& scene, const BlindDesign& design, const OutdoorOptions& first_outdoor,
    const IndoorOptions& first_indoor, const TargetErrorOptions& target, DcBackend* backend,
    const std::function<void(const RoundReport&)>& on_round) {
  FENESTRA_RETURN_IF_ERROR(CheckTarget(target));
  const auto start = std::chrono::steady_clock::now();
  TwoStageToTarget run;
  OutdoorOptions outdoor = first_outdoor;
  IndoorOptions indoor = first_indoor;
  outdoor.paths = std::min(outdoor.paths, target.max_outdoor_paths);
  indoor.paths_per_sensor = std::min(indoor.paths_per_sensor, target.max_paths_per_sensor);
  FENESTRA_ASSIGN_OR_RETURN(o, ComputeOutdoorStage(scene, outdoor, backend));
  FENESTRA_ASSIGN_OR_RETURN(i, ComputeIndoorStage(scene, design, indoor, backend));
  run.outdoor = std::move(o);
  run.indoor = std::move(i);
  const int64_t window_cells = run.outdoor.sky_view.size();
  int outdoor_rounds = 1, indoor_rounds = 1;
  for (int round = 0;; ++round) {
    // Combine, report, stop when reached
    FENESTRA_ASSIGN_OR_RETURN(combined, CombineStages(run.indoor, run.outdoor));
    run.combined = std::move(combined);
    const TwoStageResult& d = run.combined;
    RoundReport report = Report(round, d.sky_sum, d.sky_sum_standard_error, SecondsSince(start));
    report.paths_per_sensor = run.indoor.paths_per_sensor;
    report.outdoor_paths = run.outdoor.paths_per_cell * window_cells;
    const Eigen::VectorXd indoor_variance = IndoorSkySumVariance(run.indoor, run.outdoor);
    const Eigen::VectorXd variance = d.sky_sum_standard_error.cwiseAbs2();
    const size_t w = report.worst_sensor;
    report.indoor_variance_share =
        variance(w) > 0 ? std::min(1.0, indoor_variance(w) / variance(w)) : 0.0;
    run.outcome.rounds.push_back(report);
    if (on_round) on_round(report);
    if (report.max_relative_error <= target.relative_error) {
      run.outcome.reached = true;
      return run;
    }

    // Split each sensor's variance in units of its aim, then the cheapest growth of each stage
    Eigen::VectorXd x(variance.size()), y(variance.size());
    for (Eigen::Index s = 0; s < variance.size(); ++s) {
      const double aim = std::pow(kTargetAim * target.relative_error * d.sky_sum(s), 2);
      const double in = std::min(indoor_variance(s), variance(s));
      x(s) = aim > 0 ? in / aim : 0;
      y(s) = aim > 0 ? (variance(s) - in) / aim : 0;
    }
    // Each stage priced in the rays it traced so far rather than in seconds, so that the split
    // (and with it the result) is the same for a seed on any machine and under any load
    const auto [a, b] = CheapestGrowth(x, y, static_cast<double>(run.indoor.rays_traced),
                                       std::max(static_cast<double>(run.outdoor.rays_traced), 1.0));
    Plan plan{{a, b},
              {run.indoor.wall_seconds, run.outdoor.wall_seconds},
              {0, 0},
              {static_cast<double>(run.indoor.paths_per_sensor),
               static_cast<double>(report.outdoor_paths)},
              {static_cast<double>(target.max_paths_per_sensor),
               static_cast<double>(target.max_outdoor_paths)}};
    run.outcome.stop_reason = LimitPlan(plan, target.max_seconds - SecondsSince(start));
    if (!run.outcome.stop_reason.empty()) return run;

    // Trace the stages that grow by at least 1%
    if (plan.factor[0] > 1.01) {
      indoor.paths_per_sensor =
          std::max<int64_t>(indoor.batches, std::llround((plan.factor[0] - 1) * plan.paths[0]));
      indoor.seed = RoundSeed(first_indoor.seed, indoor_rounds++);
      FENESTRA_ASSIGN_OR_RETURN(next, ComputeIndoorStage(scene, design, indoor, backend));
      FENESTRA_ASSIGN_OR_RETURN(merged, MergeRounds(run.indoor, std::move(next)));
      run.indoor = std::move(merged);
    }
    if (plan.factor[1] > 1.01) {
      outdoor.paths = std::max<int64_t>(window_cells * outdoor.batches,
                                        std::llround((plan.factor[1] - 1) * plan.paths[1]));
      outdoor.seed = RoundSeed(first_outdoor.seed, outdoor_rounds++);
      FENESTRA_ASSIGN_OR_RETURN(next, ComputeOutdoorStage(scene, outdoor, backend));
      FENESTRA_ASSIGN_OR_RETURN(merged, MergeRounds(run.outdoor, std::move(next)));
      run.outdoor = std::move(merged);
    }
  }
}

}  // namespace fenestra
