// One-stage daylight coefficients against analytic answers. Monte Carlo tolerances are in
// standard errors (the ones the result reports) and the seeds are fixed.
#include "core/dc/one_stage.h"

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "core/geometry/scene.h"
#include "tests/core/trace/test_meshes.h"

namespace fenestra {
namespace {

using testing_meshes::AddBox;
using testing_meshes::AddSquare;

constexpr double kPi = 3.14159265358979323846;
constexpr double kDeg = kPi / 180;

// Cosine-weighted solid angle of every Tregenza bin (0 for the ground): a band patch of
// n patches between altitudes a and b gets (1/n) * integral over phi and altitude of
// sin(alt) cos(alt) = pi (sin^2 b - sin^2 a) / n; the 6 degree cap gets pi cos^2(84).
std::vector<double> CosineWeightedPatches() {
  const int counts[] = {30, 30, 24, 24, 18, 12, 6};
  std::vector<double> w = {0.0};
  for (int row = 0; row < 7; ++row) {
    const double lo = std::sin(12.0 * row * kDeg), hi = std::sin(12.0 * (row + 1) * kDeg);
    for (int k = 0; k < counts[row]; ++k) w.push_back(kPi * (hi * hi - lo * lo) / counts[row]);
  }
  w.push_back(kPi * std::pow(std::cos(84 * kDeg), 2));
  return w;
}

// View factor from a downward-facing point at height h to the centred square of half
// side a below it: four corner rectangles, each (Howell's catalogue, B-3)
// F = [X/sqrt(1+X^2) atan(Y/sqrt(1+X^2)) + Y/sqrt(1+Y^2) atan(X/sqrt(1+Y^2))] / (2 pi).
double SquareViewFactor(double a, double h) {
  const double x = a / h, s = std::sqrt(1 + x * x);
  return 4 * (2 * x / s * std::atan(x / s)) / (2 * kPi);
}

Sensor MakeSensor(Vec3d position, Vec3d direction) { return {"s", position, direction}; }

OneStageOptions Options(int64_t paths, uint64_t seed) {
  OneStageOptions options;
  options.paths_per_sensor = paths;
  options.seed = seed;
  return options;
}

TEST(OneStageTest, UnobstructedUpwardSensorSeesPiSplitByPatch) {
  TriangleMesh mesh;
  AddSquare(mesh, 0, 0, 50, -1, 0);  // a floor below, never seen
  const auto result = ComputeOneStage(mesh, {{"floor", 0.2, -1}},
                                      {MakeSensor({0, 0, 0}, {0, 0, 1})}, Options(400000, 1));
  ASSERT_TRUE(result.ok()) << result.status();
  const std::vector<double> expected = CosineWeightedPatches();
  double expected_total = 0;
  for (double w : expected) expected_total += w;
  ASSERT_NEAR(expected_total, kPi, 1e-12);

  // Every path escapes upwards: the sum is pi up to rounding
  EXPECT_NEAR(result->sky_sum(0), kPi, 1e-12);
  EXPECT_EQ(result->coefficients(0, 0), 0.0);
  EXPECT_EQ(result->rays_traced, 400000u + result->pilot_paths);  // one ray each
  double chi_square = 0;
  for (int b = 1; b < kDaylightBins; ++b) {
    const double z = (result->coefficients(0, b) - expected[b]) / result->standard_error(0, b);
    EXPECT_LT(std::fabs(z), 4.5) << "bin " << b;
    chi_square += z * z;
  }
  // 145 terms (one linear constraint): mean 144, sd 17
  EXPECT_LT(std::fabs(chi_square - 144), 4 * 17) << chi_square;
}

// The same sensor with Sobol draws: each patch's coefficient is the share of the first
// directions that fall in it, where the scrambled points are stratified, so the batches'
// scatter (the standard errors then) is far below the pseudo-random draws' and the values
// still agree with the patches' within it.
TEST(OneStageTest, SobolDrawsSplitTheSkyByPatchWithSmallerErrors) {
  TriangleMesh mesh;
  AddSquare(mesh, 0, 0, 50, -1, 0);
  const std::vector<double> expected = CosineWeightedPatches();
  double variance[2] = {0, 0}, chi_square = 0;
  for (const Sequence sequence : {Sequence::kPseudoRandom, Sequence::kSobol}) {
    OneStageOptions options = Options(400000, 1);
    options.sequence = sequence;
    options.batches = sequence == Sequence::kSobol ? 0 : 8;  // Sobol: kSobolBatches
    const auto result =
        ComputeOneStage(mesh, {{"floor", 0.2, -1}}, {MakeSensor({0, 0, 0}, {0, 0, 1})}, options);
    ASSERT_TRUE(result.ok()) << result.status();
    ASSERT_EQ(result->batch_coefficients.size(), static_cast<size_t>(kSobolBatches));
    EXPECT_NEAR(result->sky_sum(0), kPi, 1e-12);
    for (int b = 1; b < kDaylightBins; ++b) {
      variance[static_cast<int>(sequence)] += std::pow(result->standard_error(0, b), 2);
      if (sequence != Sequence::kSobol) continue;
      const double z = (result->coefficients(0, b) - expected[b]) / result->standard_error(0, b);
      chi_square += z * z;
    }
  }
  std::printf("patches: variance %.3g pseudo-random, %.3g Sobol (%.0f times); chi-square %.0f\n",
              variance[0], variance[1], variance[0] / variance[1], chi_square);
  EXPECT_GT(variance[0] / variance[1], 20.0);
  // 145 z-scores from 8 batches each (Student's t of 7 degrees: variance 1.4): mean 203
  EXPECT_LT(chi_square, 203 + 4 * 40) << chi_square;
}

TEST(OneStageTest, DownwardSensorOverGroundSeesPiRhoLessWhatMissesTheGround) {
  const double rho = 0.3, half = 5000, height = 1;
  TriangleMesh mesh;
  AddSquare(mesh, 0, 0, half, 0, 0);
  // Roulette at every reflection (threshold 1), so the sum has Monte Carlo error
  OneStageOptions options = Options(400000, 2);
  options.roulette_threshold = 1.0;
  const auto result = ComputeOneStage(mesh, {{"ground", rho, -1}},
                                      {MakeSensor({0, 0, height}, {0, 0, -1})}, options);
  ASSERT_TRUE(result.ok()) << result.status();
  // The share of cosine-weighted directions that misses the square escapes below the
  // horizon (bin 0); the rest reflects once and sees the sky
  const double hit = SquareViewFactor(half, height);
  EXPECT_GT(1 - hit, 0);
  EXPECT_LT(1 - hit, 1e-6);
  EXPECT_NEAR(result->sky_sum(0), kPi * rho * hit, 4 * result->sky_sum_standard_error(0));
  EXPECT_NEAR(result->coefficients(0, 0), kPi * (1 - hit), 1e-4);
  const std::vector<double> expected = CosineWeightedPatches();
  for (int b = 1; b < kDaylightBins; ++b) {
    EXPECT_NEAR(result->coefficients(0, b), rho * hit * expected[b],
                4.5 * result->standard_error(0, b))
        << "bin " << b;
  }
}

TEST(OneStageTest, SquareViewFactorMatchesNumericalIntegration) {
  // Midpoint rule over the cosine-weighted disk of directions, as a check of the formula
  const double a = 2.0, h = 1.0;
  const int n = 2000;
  double hit = 0;
  for (int i = 0; i < n; ++i) {
    for (int j = 0; j < n; ++j) {
      const double x = -1 + (i + 0.5) * 2.0 / n, y = -1 + (j + 0.5) * 2.0 / n;
      const double r2 = x * x + y * y;
      if (r2 >= 1) continue;
      // Disk point (x, y) lifts to the direction (x, y, -sqrt(1 - r2)) (Malley)
      const double scale = h / std::sqrt(1 - r2);
      if (std::fabs(x * scale) < a && std::fabs(y * scale) < a) hit += 1;
    }
  }
  hit *= (2.0 / n) * (2.0 / n) / kPi;
  EXPECT_NEAR(SquareViewFactor(a, h), hit, 2e-3);
}

TEST(OneStageTest, ClosedBoxGivesExactlyZero) {
  TriangleMesh mesh;
  AddBox(mesh, {-1.5, -6.25, 0}, {1.5, 0, 3}, 0);
  OneStageOptions options = Options(100000, 3);
  const auto result = ComputeOneStage(
      mesh, {{"wall", 0.9, -1}},
      {MakeSensor({0, -1, 0.7}, {0, 0, 1}), MakeSensor({1.5, -3, 1.5}, {-1, 0, 0})}, options);
  ASSERT_TRUE(result.ok()) << result.status();
  EXPECT_EQ(result->coefficients.cwiseAbs().maxCoeff(), 0.0);
  EXPECT_EQ(result->standard_error.cwiseAbs().maxCoeff(), 0.0);
  EXPECT_EQ(result->escaped_paths, 0u);
  EXPECT_GT(result->rays_traced, 10u * 200000u);  // about 1 / (1 - 0.9) rays per path
}

// Sensor facing up at z = 0.5 between a ground (z = 0, reflectance rho_g) and a glazed
// ceiling (z = 1, tau, rho_p), both 20 km wide: light reaches the sky only through the
// pane, after k round trips with probability (rho_p rho_g)^k, so the sky sees
// pi tau / (1 - rho_p rho_g) in total, split like an unobstructed sensor's.
struct GlazedSlab {
  double tau = 0.5, rho_p = 0.3, rho_g = 0.5;
  TriangleMesh mesh;
  std::vector<Material> materials;
  std::vector<Sensor> sensors = {MakeSensor({0, 0, 0.5}, {0, 0, 1})};

  GlazedSlab() {
    AddSquare(mesh, 0, 0, 1e4, 0, 0);
    AddSquare(mesh, 0, 0, 1e4, 1, 1);
    materials = {{"ground", rho_g, -1}, {"pane", rho_p, tau}};
  }
  // Expected sky sum with at most `max_bounces` reflections (< 0: unlimited).
  double SkySum(int max_bounces) const {
    const double r = rho_p * rho_g;
    if (max_bounces < 0) return kPi * tau / (1 - r);
    return kPi * tau * (1 - std::pow(r, max_bounces / 2 + 1)) / (1 - r);
  }
};

TEST(OneStageTest, RouletteAndBounceLimitsAreUnbiased) {
  const GlazedSlab slab;
  struct Case {
    bool roulette;
    double threshold;
    int max_bounces;
    bool weight_windows;
  };
  // max_bounces -1: unlimited; 0: the direct component alone
  const Case cases[] = {{true, 1.0, -1, false},    {true, 0.3, -1, false}, {true, 0.01, -1, false},
                        {false, 1.0, 1000, false}, {true, 1.0, 1, false},  {false, 1.0, 2, false},
                        {true, 0.3, 3, false},     {true, 1.0, 4, false},  {false, 1.0, -1, false},
                        {true, 0.25, -1, true},    {true, 0.25, 3, true},  {false, 1.0, 6, true},
                        {true, 1.0, 0, false},     {false, 1.0, 0, false}};
  for (const Case& c : cases) {
    OneStageOptions options = Options(200000, 4);
    options.russian_roulette = c.roulette;
    options.roulette_threshold = c.threshold;
    options.max_bounces = c.max_bounces;
    options.weight_windows = c.weight_windows;
    const auto result = ComputeOneStage(slab.mesh, slab.materials, slab.sensors, options);
    if (!c.roulette && c.max_bounces < 0) {
      EXPECT_EQ(result.status().code(), absl::StatusCode::kInvalidArgument);
      continue;
    }
    ASSERT_TRUE(result.ok()) << result.status();
    SCOPED_TRACE(testing::Message()
                 << "roulette " << c.roulette << " threshold " << c.threshold << " bounces "
                 << c.max_bounces << " weight windows " << c.weight_windows);
    if (c.weight_windows) {
      EXPECT_GT(result->importance_cells, 0u);
    }
    EXPECT_NEAR(result->sky_sum(0), slab.SkySum(c.max_bounces),
                4 * result->sky_sum_standard_error(0));
    EXPECT_LE(result->max_path_weight, 1.0);
    EXPECT_EQ(result->coefficients(0, 0), 0.0);
  }
}

// z-scores of many independent runs against the analytic value: mean 0, sd 1.
struct ZStats {
  double mean = 0, sd = 0;
  int n = 0;
};
ZStats Summarize(const std::vector<double>& z) {
  ZStats s;
  s.n = static_cast<int>(z.size());
  for (double v : z) s.mean += v / s.n;
  for (double v : z) s.sd += (v - s.mean) * (v - s.mean) / (s.n - 1);
  s.sd = std::sqrt(s.sd);
  return s;
}

TEST(OneStageTest, StandardErrorsAreCalibrated) {
  // 100 seeds of 10^5 paths through the glazed slab, with variable path weights (roulette
  // below 0.3): z of the sky sum and of every sky bin against the analytic values
  const GlazedSlab slab;
  const std::vector<double> patches = CosineWeightedPatches();
  const double share = slab.SkySum(kUnlimitedBounces) / kPi;
  const int kSeeds = 100;
  std::vector<double> z_sum, z_bins;
  for (int seed = 0; seed < kSeeds; ++seed) {
    OneStageOptions options = Options(100000, 1000 + seed);
    options.roulette_threshold = 0.3;
    options.weight_windows = false;
    const auto result = ComputeOneStage(slab.mesh, slab.materials, slab.sensors, options);
    ASSERT_TRUE(result.ok()) << result.status();
    z_sum.push_back((result->sky_sum(0) - slab.SkySum(kUnlimitedBounces)) /
                    result->sky_sum_standard_error(0));
    for (int b = 1; b < kDaylightBins; ++b) {
      z_bins.push_back((result->coefficients(0, b) - share * patches[b]) /
                       result->standard_error(0, b));
    }
  }
  // Sky sum: 100 values; sd of their mean 0.1, of their sd about 0.07
  const ZStats sum = Summarize(z_sum);
  EXPECT_LT(std::fabs(sum.mean), 0.35) << sum.mean;
  EXPECT_LT(std::fabs(sum.sd - 1), 0.25) << sum.sd;
  // Bins: 14500 values, weakly correlated within a run (sd of the mean about 0.01). With
  // about 100 to 1000 escapes per bin and run, z computed with its own estimated error is
  // skewed by about -1 / (2 sqrt(count)), hence the wider bands
  const ZStats bins = Summarize(z_bins);
  EXPECT_LT(std::fabs(bins.mean), 0.07) << bins.mean;
  EXPECT_LT(std::fabs(bins.sd - 1), 0.07) << bins.sd;
  std::printf(
      "calibration (roulette): sky sum z mean %.3f sd %.3f (n %d); bins z mean %.3f "
      "sd %.3f (n %d)\n",
      sum.mean, sum.sd, sum.n, bins.mean, bins.sd, bins.n);
}

// An upward sensor at the bottom of a 1 x 1 x 4 m shaft open at the top (walls 0.8, floor
// 0.2): importance grows with height, so weight windows split climbing paths and a path
// scores in several bins. No closed form: each seed's weight-window run is compared with an
// independent plain-roulette run, z = difference / combined standard error. Unlimited
// reflections, and at most 3.
void CheckSplitCalibration(int max_bounces, int seeds) {
  TriangleMesh mesh;
  AddBox(mesh, {-0.5, -0.5, 0}, {0.5, 0.5, 4}, 0);
  mesh.vertices.erase(mesh.vertices.begin() + 6, mesh.vertices.begin() + 12);  // no roof
  mesh.material.erase(mesh.material.begin() + 2, mesh.material.begin() + 4);
  mesh.side.erase(mesh.side.begin() + 2, mesh.side.begin() + 4);
  mesh.part.erase(mesh.part.begin() + 2, mesh.part.begin() + 4);
  mesh.material[0] = mesh.material[1] = 1;
  const std::vector<Material> materials = {{"wall", 0.8, -1}, {"floor", 0.2, -1}};
  const std::vector<Sensor> sensors = {MakeSensor({0.2, -0.1, 0.3}, {0, 0, 1})};
  // Bins above 10% of the row maximum (fewer escapes skew z, as above)
  OneStageOptions selection_options = Options(200000, 77);
  selection_options.max_bounces = max_bounces;
  const OneStageResult selection = *ComputeOneStage(mesh, materials, sensors, selection_options);
  std::vector<int> bins;
  for (int b = 1; b < kDaylightBins; ++b) {
    if (selection.coefficients(0, b) > 0.1 * selection.coefficients.row(0).maxCoeff()) {
      bins.push_back(b);
    }
  }

  std::vector<double> z_sum, z_bins;
  uint64_t branches = 0, paths = 0;
  for (int seed = 0; seed < seeds; ++seed) {
    OneStageOptions options = Options(100000, 2000 + seed);
    options.max_bounces = max_bounces;
    options.pilot_paths_per_sensor = 20000;
    const auto windows = ComputeOneStage(mesh, materials, sensors, options);
    options.seed = 5000 + seed;
    options.weight_windows = false;
    const auto plain = ComputeOneStage(mesh, materials, sensors, options);
    ASSERT_TRUE(windows.ok() && plain.ok());
    ASSERT_GT(windows->importance_cells, 0u);
    branches += windows->branches;
    paths += windows->paths_per_sensor;
    z_sum.push_back(
        (windows->sky_sum(0) - plain->sky_sum(0)) /
        std::hypot(windows->sky_sum_standard_error(0), plain->sky_sum_standard_error(0)));
    for (int b : bins) {
      z_bins.push_back((windows->coefficients(0, b) - plain->coefficients(0, b)) /
                       std::hypot(windows->standard_error(0, b), plain->standard_error(0, b)));
    }
  }
  EXPECT_GT(branches, paths + paths / 50);  // splitting did happen
  // Sky sum: sd of the mean 1 / sqrt(seeds), of the sd about 1 / sqrt(2 seeds)
  const ZStats sum = Summarize(z_sum);
  EXPECT_LT(std::fabs(sum.mean), 3.5 / std::sqrt(seeds)) << sum.mean;
  EXPECT_LT(std::fabs(sum.sd - 1), 2.5 / std::sqrt(seeds)) << sum.sd;
  const ZStats bin_stats = Summarize(z_bins);
  EXPECT_LT(std::fabs(bin_stats.mean), 0.12) << bin_stats.mean;
  EXPECT_LT(std::fabs(bin_stats.sd - 1), 0.12) << bin_stats.sd;
  std::printf(
      "calibration (weight windows against roulette, bounces %d, %.2f branches per "
      "path): sky sum z mean %.3f sd %.3f (n %d); bins z mean %.3f sd %.3f (n %d)\n",
      max_bounces, double(branches) / paths, sum.mean, sum.sd, sum.n, bin_stats.mean, bin_stats.sd,
      bin_stats.n);
}

TEST(OneStageTest, StandardErrorsAreCalibratedWhenPathsSplit) {
  CheckSplitCalibration(kUnlimitedBounces, 60);
}

TEST(OneStageTest, WeightWindowsWithABounceLimitAreUnbiased) { CheckSplitCalibration(3, 40); }

TEST(OneStageTest, ResultsDoNotDependOnTheThreadCount) {
  TriangleMesh mesh;
  AddBox(mesh, {-1.5, -6.25, 0}, {1.5, 0, 3}, 0);
  // Open the box: remove the ceiling's two triangles (indices 2, 3)
  mesh.vertices.erase(mesh.vertices.begin() + 6, mesh.vertices.begin() + 12);
  mesh.material.erase(mesh.material.begin() + 2, mesh.material.begin() + 4);
  mesh.side.erase(mesh.side.begin() + 2, mesh.side.begin() + 4);
  mesh.part.erase(mesh.part.begin() + 2, mesh.part.begin() + 4);
  const std::vector<Sensor> sensors = {MakeSensor({0, -1, 0.7}, {0, 0, 1}),
                                       MakeSensor({0, -5, 0.7}, {0, 0, 1})};
  OneStageOptions options = Options(40007, 5);  // not a multiple of the chunk size
  options.batches = 3;
  std::vector<OneStageResult> results;
  for (int threads : {1, 2, 3, 8}) {
    options.threads = threads;
    auto result = ComputeOneStage(mesh, {{"wall", 0.8, -1}}, sensors, options);
    ASSERT_TRUE(result.ok()) << result.status();
    EXPECT_EQ(result->threads, threads);
    results.push_back(*std::move(result));
  }
  EXPECT_GT(results[0].importance_cells, 0u);  // weight windows on
  for (size_t i = 1; i < results.size(); ++i) {
    EXPECT_TRUE(results[i].coefficients == results[0].coefficients);  // bitwise
    EXPECT_TRUE(results[i].standard_error == results[0].standard_error);
    EXPECT_EQ(results[i].rays_traced, results[0].rays_traced);
    for (int b = 0; b < 3; ++b) {
      EXPECT_TRUE(results[i].batch_coefficients[b] == results[0].batch_coefficients[b]);
    }
  }
  EXPECT_GT(results[0].sky_sum(0), 0);
}

TEST(OneStageTest, BatchesSplitThePathsAndAverageToTheTotal) {
  TriangleMesh mesh;
  AddSquare(mesh, 0, 0, 100, 0, 0);
  OneStageOptions options = Options(30001, 6);
  options.batches = 7;
  const auto result =
      ComputeOneStage(mesh, {{"ground", 0.5, -1}}, {MakeSensor({0, 0, 1}, {0, 0, -1})}, options);
  ASSERT_TRUE(result.ok()) << result.status();
  ASSERT_EQ(result->batch_coefficients.size(), 7u);
  // Batches of 4285 or 4286 paths: their path-weighted mean is the total
  Matrix mean = Matrix::Zero(1, kDaylightBins);
  for (int b = 0; b < 7; ++b) {
    const double paths = double((30001 * (b + 1)) / 7 - (30001 * b) / 7);
    mean += result->batch_coefficients[b] * (paths / 30001);
  }
  EXPECT_LT((mean - result->coefficients).cwiseAbs().maxCoeff(), 1e-12);
  // Each batch is a D of its own: about pi * 0.5 in total
  for (const Matrix& d : result->batch_coefficients) {
    EXPECT_NEAR(d.sum(), kPi * 0.5, 0.1);
  }
  options.batches = 0;
  EXPECT_TRUE(
      ComputeOneStage(mesh, {{"ground", 0.5, -1}}, {MakeSensor({0, 0, 1}, {0, 0, -1})}, options)
          ->batch_coefficients.empty());
}

TEST(OneStageTest, RejectsBadOptionsAndSensors) {
  TriangleMesh mesh;
  AddSquare(mesh, 0, 0, 1, 0, 0);
  const std::vector<Material> materials = {{"m", 0.5, -1}};
  const std::vector<Sensor> good = {MakeSensor({0, 0, 1}, {0, 0, 1})};
  const auto code = [&](const std::vector<Sensor>& sensors, OneStageOptions options) {
    return ComputeOneStage(mesh, materials, sensors, options).status().code();
  };
  const auto kInvalid = absl::StatusCode::kInvalidArgument;
  OneStageOptions options = Options(100, 1);
  EXPECT_EQ(code(good, options), absl::StatusCode::kOk);
  EXPECT_EQ(code({}, options), kInvalid);
  EXPECT_EQ(code({MakeSensor({0, 0, NAN}, {0, 0, 1})}, options), kInvalid);
  EXPECT_EQ(code({MakeSensor({0, 0, 1}, {0, 0, 0})}, options), kInvalid);
  options.paths_per_sensor = 1;
  EXPECT_EQ(code(good, options), kInvalid);
  options = Options(100, 1);
  options.threads = -1;
  EXPECT_EQ(code(good, options), kInvalid);
  options = Options(100, 1);
  options.roulette_threshold = 0;
  EXPECT_EQ(code(good, options), kInvalid);
  options.roulette_threshold = 1.5;
  EXPECT_EQ(code(good, options), kInvalid);
  options = Options(100, 1);
  options.importance_cell_m = 0;
  EXPECT_EQ(code(good, options), kInvalid);
  options = Options(100, 1);
  options.pilot_paths_per_sensor = -5;
  EXPECT_EQ(code(good, options), kInvalid);
  options = Options(100, 1);
  options.batches = 101;
  EXPECT_EQ(code(good, options), kInvalid);
  options.batches = -1;
  EXPECT_EQ(code(good, options), kInvalid);
  EXPECT_EQ(ComputeOneStage(mesh, {{"m", 1.0, -1}}, good, Options(100, 1)).status().code(),
            kInvalid);
}

// Nearly closed slats pass light through slits about a millimetre wide; the trace frame
// centred on the sensors keeps them that wide however far the city reaches. Centred on the
// scene's bounding box, a triangle 1 km away moved the local frame's origin with it, the ray
// offsets grew with the coordinates, and light leaked through the slits: sky sums 4% (100 m)
// to 40% higher.
TEST(OneStageTest, FarGeometryLeavesTheSlitsOfANearlyClosedBlind) {
  absl::StatusOr<Scene> scene = LoadScene(FENESTRA_SOURCE_DIR "/examples/city_office/scene.json");
  ASSERT_TRUE(scene.ok()) << scene.status();
  absl::StatusOr<BlindDesign> design = DesignWithOverrides(*scene, {{"alpha", 0.1136}});
  ASSERT_TRUE(design.ok()) << design.status();
  const TriangleMesh near = AssembleMesh(*scene, *design);
  TriangleMesh far = near;
  far.Add({0, 0, -1000}, {1, 0, -1000}, {0, 1, -1000}, 0, Side::kOutdoor, 0);
  OneStageOptions options = Options(20000, 5);
  options.weight_windows = false;
  const auto a = ComputeOneStage(near, scene->materials, scene->sensors, options);
  const auto b = ComputeOneStage(far, scene->materials, scene->sensors, options);
  ASSERT_TRUE(a.ok() && b.ok()) << a.status() << b.status();
  for (Eigen::Index s = 0; s < a->sky_sum.size(); ++s) {
    EXPECT_GT(a->sky_sum(s), 0);
    EXPECT_NEAR(b->sky_sum(s), a->sky_sum(s), 1e-9 * a->sky_sum(s)) << "sensor " << s;
  }
}

}  // namespace
}  // namespace fenestra
