#include "core/dc/rounds.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <set>

#include "core/dc/one_stage.h"
#include "tests/example_scene.h"

namespace fenestra {
namespace {

TEST(RoundSeedTest, RoundZeroKeepsTheSeedAndLaterRoundsDiffer) {
  for (const uint64_t seed : {uint64_t{0}, uint64_t{1}, uint64_t{12345}, ~uint64_t{0}}) {
    EXPECT_EQ(RoundSeed(seed, 0), seed);
    std::set<uint64_t> seeds{seed};
    for (int round = 1; round <= 1000; ++round) seeds.insert(RoundSeed(seed, round));
    EXPECT_EQ(seeds.size(), 1001u) << seed;
  }
}

// One sensor, D = value everywhere, sky sum over the 145 sky bins.
OneStageResult Constant(int64_t paths, double value, double error) {
  OneStageResult r;
  r.coefficients = Matrix::Constant(1, kDaylightBins, value);
  r.standard_error = Matrix::Constant(1, kDaylightBins, error);
  r.sky_sum = Eigen::VectorXd::Constant(1, 145 * value);
  r.sky_sum_standard_error = Eigen::VectorXd::Constant(1, 145 * error);
  r.paths_per_sensor = paths;
  r.rays_traced = static_cast<uint64_t>(10 * paths);
  r.wall_seconds = 1;
  return r;
}

TEST(MergeRoundsTest, OneStageIsThePathWeightedMean) {
  absl::StatusOr<OneStageResult> m = MergeRounds(Constant(100, 1.0, 0.4), Constant(300, 3.0, 0.2));
  ASSERT_TRUE(m.ok()) << m.status();
  EXPECT_DOUBLE_EQ(m->coefficients(0, 7), 0.25 * 1.0 + 0.75 * 3.0);
  EXPECT_DOUBLE_EQ(m->standard_error(0, 7),
                   std::sqrt(0.25 * 0.25 * 0.4 * 0.4 + 0.75 * 0.75 * 0.2 * 0.2));
  EXPECT_DOUBLE_EQ(m->sky_sum(0), 145 * 2.5);
  EXPECT_DOUBLE_EQ(m->sky_sum_standard_error(0), 145 * m->standard_error(0, 7));
  EXPECT_EQ(m->paths_per_sensor, 400);
  EXPECT_EQ(m->rays_traced, 4000u);
  EXPECT_DOUBLE_EQ(m->wall_seconds, 2);
}

TEST(MergeRoundsTest, ShapesMustAgree) {
  OneStageResult other = Constant(100, 1, 1);
  other.coefficients = Matrix::Zero(2, kDaylightBins);
  EXPECT_EQ(MergeRounds(Constant(100, 1, 1), other).status().code(),
            absl::StatusCode::kInvalidArgument);
  IndoorResult a, b;
  a.coefficients = b.coefficients = Matrix::Zero(1, 4);
  a.batches = {Matrix::Zero(1, 4), Matrix::Zero(1, 4)};
  b.batches = {Matrix::Zero(1, 4), Matrix::Zero(1, 4), Matrix::Zero(1, 4)};
  EXPECT_EQ(MergeRounds(a, b).status().code(), absl::StatusCode::kInvalidArgument);
}

// Batches merge batch by batch, and the standard error is their scatter.
TEST(MergeRoundsTest, IndoorBatchesMergeOneByOne) {
  IndoorResult a, b;
  a.paths_per_sensor = 100, b.paths_per_sensor = 100;
  a.batches = {Matrix::Constant(1, 2, 1.0), Matrix::Constant(1, 2, 3.0)};
  b.batches = {Matrix::Constant(1, 2, 5.0), Matrix::Constant(1, 2, 11.0)};
  a.coefficients = Matrix::Constant(1, 2, 2.0);
  b.coefficients = Matrix::Constant(1, 2, 8.0);
  absl::StatusOr<IndoorResult> m = MergeRounds(a, b);
  ASSERT_TRUE(m.ok()) << m.status();
  EXPECT_DOUBLE_EQ(m->batches[0](0, 1), 3.0);
  EXPECT_DOUBLE_EQ(m->batches[1](0, 1), 7.0);
  EXPECT_DOUBLE_EQ(m->coefficients(0, 0), 5.0);
  // Two batches 3 and 7 around 5: variance of the mean (4 + 4) / (2 x 1)
  EXPECT_DOUBLE_EQ(m->standard_error(0, 0), 2.0);
  EXPECT_EQ(m->paths_per_sensor, 200);
}

// The outdoor stage's batches merge as the indoor stage's, and pair up afterwards.
TEST(MergeRoundsTest, OutdoorBatchesMergeOneByOne) {
  OutdoorResult a, b;
  a.paths_per_cell = 100, b.paths_per_cell = 300;
  a.batches = {Matrix::Constant(2, 1, 1.0), Matrix::Constant(2, 1, 3.0)};
  b.batches = {Matrix::Constant(2, 1, 5.0), Matrix::Constant(2, 1, 9.0)};
  a.coefficients = Matrix::Constant(2, 1, 2.0);
  b.coefficients = Matrix::Constant(2, 1, 7.0);
  a.sky_view = Eigen::VectorXd::Constant(1, 0.2);
  b.sky_view = Eigen::VectorXd::Constant(1, 0.6);
  absl::StatusOr<OutdoorResult> m = MergeRounds(a, b);
  ASSERT_TRUE(m.ok()) << m.status();
  // Weights 1/4 and 3/4: batches 4 and 7.5 around 5.75
  EXPECT_DOUBLE_EQ(m->batches[0](1, 0), 4.0);
  EXPECT_DOUBLE_EQ(m->batches[1](1, 0), 7.5);
  EXPECT_DOUBLE_EQ(m->coefficients(0, 0), 5.75);
  EXPECT_DOUBLE_EQ(m->standard_error(0, 0), 1.75);
  EXPECT_DOUBLE_EQ(m->sky_view(0), 0.5);
  EXPECT_EQ(m->paths_per_cell, 400);
  b.batches.push_back(b.batches[0]);
  EXPECT_EQ(MergeRounds(a, b).status().code(), absl::StatusCode::kInvalidArgument);
}

OneStageOptions PlainRoulette(int64_t paths, uint64_t seed) {
  OneStageOptions options;
  options.paths_per_sensor = paths;
  options.seed = seed;
  options.weight_windows = false;
  return options;
}

// Two rounds of N paths, merged, estimate what one run of 2N paths does: the same sky sums
// within 4 combined standard errors and the same standard errors within 20%.
TEST(MergeRoundsTest, TwoRoundsAreOneRunOfTheirPaths) {
  const Scene scene = LoadExample("lightwell");
  const BlindDesign design = DefaultDesign(scene);
  constexpr int64_t kPaths = 100000;
  absl::StatusOr<OneStageResult> first =
      ComputeOneStage(scene, design, PlainRoulette(kPaths, RoundSeed(5, 0)));
  absl::StatusOr<OneStageResult> second =
      ComputeOneStage(scene, design, PlainRoulette(kPaths, RoundSeed(5, 1)));
  absl::StatusOr<OneStageResult> single =
      ComputeOneStage(scene, design, PlainRoulette(2 * kPaths, 77));
  ASSERT_TRUE(first.ok() && second.ok() && single.ok());
  EXPECT_NE(first->sky_sum(0), second->sky_sum(0));  // other streams
  absl::StatusOr<OneStageResult> merged = MergeRounds(*first, *second);
  ASSERT_TRUE(merged.ok()) << merged.status();
  EXPECT_EQ(merged->paths_per_sensor, 2 * kPaths);
  for (int s = 0; s < 3; ++s) {
    const double a = merged->sky_sum(s), b = single->sky_sum(s);
    const double ea = merged->sky_sum_standard_error(s), eb = single->sky_sum_standard_error(s);
    EXPECT_NEAR(a, b, 4 * std::hypot(ea, eb)) << "sensor " << s;
    EXPECT_NEAR(ea / eb, 1.0, 0.2) << "sensor " << s;
  }
}

TEST(TargetErrorTest, OneStageStopsAtOrJustBelowTheTarget) {
  const Scene scene = LoadExample("lightwell");
  TargetErrorOptions target;
  target.relative_error = 0.05;
  std::vector<RoundReport> seen;
  absl::StatusOr<OneStageToTarget> run =
      TraceOneStageToTarget(scene, DefaultDesign(scene), PlainRoulette(5000, 3), target, nullptr,
                            [&](const RoundReport& r) { seen.push_back(r); });
  ASSERT_TRUE(run.ok()) << run.status();
  EXPECT_TRUE(run->outcome.reached);
  EXPECT_TRUE(run->outcome.stop_reason.empty());
  ASSERT_EQ(seen.size(), run->outcome.rounds.size());
  ASSERT_GE(seen.size(), 2u);
  for (size_t k = 1; k < seen.size(); ++k) {
    EXPECT_GT(seen[k].paths_per_sensor, seen[k - 1].paths_per_sensor);
    EXPECT_LE(seen[k].paths_per_sensor, kMaxRoundGrowth * seen[k - 1].paths_per_sensor);
  }
  const Eigen::VectorXd relative =
      RelativeErrors(run->result.sky_sum, run->result.sky_sum_standard_error);
  EXPECT_DOUBLE_EQ(relative.maxCoeff(), seen.back().max_relative_error);
  EXPECT_LE(relative.maxCoeff(), 0.05);
  EXPECT_GE(relative.maxCoeff(), 0.7 * 0.05);
  EXPECT_EQ(run->result.paths_per_sensor, seen.back().paths_per_sensor);
}

TEST(TargetErrorTest, PathLimitStopsShortWithAReason) {
  const Scene scene = LoadExample("lightwell");
  TargetErrorOptions target;
  target.relative_error = 0.001;
  target.max_paths_per_sensor = 8000;
  absl::StatusOr<OneStageToTarget> run =
      TraceOneStageToTarget(scene, DefaultDesign(scene), PlainRoulette(5000, 3), target, nullptr);
  ASSERT_TRUE(run.ok()) << run.status();
  EXPECT_FALSE(run->outcome.reached);
  EXPECT_NE(run->outcome.stop_reason.find("maximum path count"), std::string::npos)
      << run->outcome.stop_reason;
  EXPECT_EQ(run->result.paths_per_sensor, 8000);
}

TEST(TargetErrorTest, TimeLimitStopsAfterTheFirstRound) {
  const Scene scene = LoadExample("lightwell");
  TargetErrorOptions target;
  target.relative_error = 0.001;
  target.max_seconds = 1e-9;
  absl::StatusOr<OneStageToTarget> run =
      TraceOneStageToTarget(scene, DefaultDesign(scene), PlainRoulette(2000, 3), target, nullptr);
  ASSERT_TRUE(run.ok()) << run.status();
  EXPECT_FALSE(run->outcome.reached);
  EXPECT_EQ(run->outcome.rounds.size(), 1u);
  EXPECT_NE(run->outcome.stop_reason.find("maximum time"), std::string::npos);
}

TEST(TargetErrorTest, TargetOutsideZeroOneIsInvalid) {
  const Scene scene = LoadExample("lightwell");
  for (const double e : {0.0, -0.1, 1.0, std::numeric_limits<double>::quiet_NaN()}) {
    TargetErrorOptions target;
    target.relative_error = e;
    EXPECT_EQ(
        TraceOneStageToTarget(scene, DefaultDesign(scene), PlainRoulette(100, 1), target, nullptr)
            .status()
            .code(),
        absl::StatusCode::kInvalidArgument)
        << e;
  }
}

IndoorOptions Indoor(int64_t paths) {
  IndoorOptions options;
  options.paths_per_sensor = paths;
  options.batches = 32;
  return options;
}

// As many batches as Indoor's, to pair with them.
OutdoorOptions Outdoor(int64_t paths) {
  OutdoorOptions options;
  options.paths = paths;
  options.batches = 32;
  return options;
}

TEST(TargetErrorTest, TwoStageReachesTheTargetAndSplitsTheVariance) {
  const Scene scene = LoadExample("lightwell");
  TargetErrorOptions target;
  target.relative_error = 0.05;
  absl::StatusOr<TwoStageToTarget> run = TraceTwoStageToTarget(
      scene, DefaultDesign(scene), Outdoor(100000), Indoor(2000), target, nullptr);
  ASSERT_TRUE(run.ok()) << run.status();
  EXPECT_TRUE(run->outcome.reached);
  const TwoStageResult& d = run->combined;
  const Eigen::VectorXd relative = RelativeErrors(d.sky_sum, d.sky_sum_standard_error);
  EXPECT_LE(relative.maxCoeff(), 0.05);
  EXPECT_GE(relative.maxCoeff(), 0.7 * 0.05);
  const Eigen::VectorXd indoor = IndoorSkySumVariance(run->indoor, run->outdoor);
  for (int s = 0; s < 3; ++s) {
    EXPECT_GT(indoor(s), 0);
    EXPECT_LT(indoor(s), std::pow(d.sky_sum_standard_error(s), 2));
  }
  for (const RoundReport& r : run->outcome.rounds) {
    EXPECT_GE(r.indoor_variance_share, 0);
    EXPECT_LE(r.indoor_variance_share, 1);
  }
  // The result is the merged stages'
  EXPECT_EQ(run->indoor.paths_per_sensor, run->outcome.rounds.back().paths_per_sensor);
  EXPECT_EQ(run->outdoor.paths_per_cell * run->outdoor.sky_view.size(),
            run->outcome.rounds.back().outdoor_paths);
}

// With the indoor stage already precise (many paths, cheap) and the outdoor stage coarse, the
// outdoor stage is traced again and the indoor stage hardly: the indoor stage may get a few
// percent more paths, not a round of its own size.
TEST(TargetErrorTest, TwoStageRefinesOnlyTheStageThatNeedsIt) {
  const Scene scene = LoadExample("lightwell");
  TargetErrorOptions target;
  target.relative_error = 0.05;
  absl::StatusOr<TwoStageToTarget> run = TraceTwoStageToTarget(
      scene, DefaultDesign(scene), Outdoor(20000), Indoor(100000), target, nullptr);
  ASSERT_TRUE(run.ok()) << run.status();
  EXPECT_TRUE(run->outcome.reached);
  ASSERT_GE(run->outcome.rounds.size(), 2u);
  EXPECT_LT(run->outcome.rounds[0].indoor_variance_share, 0.2);
  EXPECT_GE(run->indoor.paths_per_sensor, 100000);
  EXPECT_LE(run->indoor.paths_per_sensor, 105000);
  EXPECT_GT(run->outcome.rounds.back().outdoor_paths, 2 * run->outcome.rounds[0].outdoor_paths);
}

}  // namespace
}  // namespace fenestra
