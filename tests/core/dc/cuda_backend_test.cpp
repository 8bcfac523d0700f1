// The CUDA backend against the Embree backend: same path code, same random streams.
// The GPU cases skip on hosts without a CUDA device.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <limits>
#include <map>
#include <memory>
#include <numbers>
#include <string>
#include <vector>

#include "core/dc/dc_backend.h"
#include "core/dc/one_stage.h"
#include "core/dc/two_stage.h"
#include "core/metrics/metric_errors.h"
#include "tests/core/dc/replay_checks.h"
#include "tests/core/dc/two_stage_checks.h"
#include "tests/example_scene.h"

namespace fenestra {
namespace {

std::unique_ptr<DcBackend> Gpu() {
  absl::StatusOr<std::unique_ptr<DcBackend>> backend = MakeCudaBackend(0);
  return backend.ok() ? *std::move(backend) : nullptr;
}

// An outdoor stage of `paths` paths in `batches` batches over the window's automatic parts.
OutdoorOptions OutdoorInParts(const Scene& scene, int64_t paths, int batches) {
  OutdoorOptions outdoor;
  outdoor.paths = paths;
  outdoor.parts = AutomaticWindowParts(scene.window());
  outdoor.batches = batches;
  return outdoor;
}

// The indoor stage paired with `outdoor`: its parts and batches.
IndoorOptions IndoorPairedWith(const OutdoorOptions& outdoor, int64_t paths_per_sensor) {
  IndoorOptions indoor;
  indoor.paths_per_sensor = paths_per_sensor;
  indoor.batches = outdoor.batches;
  indoor.parts = outdoor.parts;
  return indoor;
}

// Every entry above 1% of its row maximum agrees within 3 combined standard errors.
void ExpectParity(const Matrix& a, const Matrix& a_se, const Matrix& b, const Matrix& b_se,
                  const std::string& what) {
  double worst = 0;
  int compared = 0;
  for (Eigen::Index i = 0; i < a.rows(); ++i) {
    const double row_max = std::max(a.row(i).maxCoeff(), b.row(i).maxCoeff());
    for (Eigen::Index j = 0; j < a.cols(); ++j) {
      ASSERT_TRUE(std::isfinite(a(i, j)) && std::isfinite(b(i, j))) << what;
      if (std::max(a(i, j), b(i, j)) <= 0.01 * row_max) continue;
      const double se = std::hypot(a_se(i, j), b_se(i, j));
      const double z = se > 0 ? std::abs(a(i, j) - b(i, j)) / se : 0;
      worst = std::max(worst, z);
      ++compared;
      EXPECT_LE(std::abs(a(i, j) - b(i, j)), 3 * se) << what << " row " << i << " col " << j;
    }
  }
  std::printf("%s: %d entries compared, largest difference %.2f combined standard errors\n",
              what.c_str(), compared, worst);
}

// O as the device forms it from its sums: its mean and standard error are those of its
// batches (as the host computes them), and below the window cells each batch is the identity.
void ExpectFormedAsOnTheHost(const OutdoorResult& o) {
  const double count = static_cast<double>(o.batches.size());
  Matrix mean = Matrix::Zero(o.coefficients.rows(), o.coefficients.cols());
  for (const Matrix& b : o.batches) mean += b / count;
  Matrix variance = Matrix::Zero(mean.rows(), mean.cols());
  for (const Matrix& b : o.batches) variance += (b - mean).cwiseAbs2();
  const Matrix standard_error = (variance / (count * (count - 1))).cwiseSqrt();
  EXPECT_LE((o.coefficients - mean).cwiseAbs().maxCoeff(), 1e-12 * mean.cwiseAbs().maxCoeff());
  EXPECT_LE((o.standard_error - standard_error).cwiseAbs().maxCoeff(),
            1e-9 * standard_error.maxCoeff());
  EXPECT_GT(standard_error.maxCoeff(), 0.0);
  for (const Matrix& b : o.batches) {
    EXPECT_TRUE(b.bottomRows(kDaylightBins).isIdentity(0));
    EXPECT_TRUE(b.middleRows(b.rows() - kIndoorDirectColumns, kDaylightBins).isIdentity(0));
  }
}

TEST(CudaBackendTest, MissingGpuIsAClearError) {
  if (CudaDevices() > 0) GTEST_SKIP() << "a CUDA device is present";
  absl::StatusOr<std::unique_ptr<DcBackend>> backend = MakeBackend("cuda");
  ASSERT_FALSE(backend.ok());
  EXPECT_EQ(backend.status().code(), absl::StatusCode::kUnavailable);
  EXPECT_NE(backend.status().message().find("cannot use the GPU"), std::string::npos);
  absl::StatusOr<std::unique_ptr<DcBackend>> automatic = MakeBackend("auto");
  ASSERT_TRUE(automatic.ok());
  EXPECT_EQ((*automatic)->Name(), "embree-cpu");
}

void OneStageParity(const std::string& name, const BlindDesign* design, int bounces,
                    Sequence sequence = Sequence::kPseudoRandom) {
  std::unique_ptr<DcBackend> gpu = Gpu();
  if (!gpu) GTEST_SKIP() << "no CUDA device";
  const Scene scene = LoadExample(name);
  OneStageOptions options;
  options.paths_per_sensor = 1'000'000;
  options.max_bounces = bounces;
  options.seed = 5;
  options.weight_windows = false;  // the GPU plays plain roulette
  options.sequence = sequence;
  const BlindDesign d = design ? *design : DefaultDesign(scene);
  absl::StatusOr<OneStageResult> cpu = ComputeOneStage(scene, d, options);
  absl::StatusOr<OneStageResult> cuda = ComputeOneStage(scene, d, options, gpu.get());
  ASSERT_TRUE(cpu.ok()) << cpu.status();
  ASSERT_TRUE(cuda.ok()) << cuda.status();
  ExpectParity(cpu->coefficients, cpu->standard_error, cuda->coefficients, cuda->standard_error,
               name + " one-stage");
  std::printf("%s: CPU %.3f s, GPU %.3f s (%s), GPU rays %llu\n", name.c_str(), cpu->wall_seconds,
              cuda->wall_seconds, cuda->backend.c_str(),
              static_cast<unsigned long long>(cuda->rays_traced));
}

TEST(CudaBackendTest, LightwellOneStageMatchesEmbree) { OneStageParity("lightwell", nullptr, 29); }

TEST(CudaBackendTest, LightwellOneStageOfSobolDrawsMatchesEmbree) {
  OneStageParity("lightwell", nullptr, 29, Sequence::kSobol);
}

TEST(CudaBackendTest, CityOfficeOneStageMatchesEmbree) {
  const Scene scene = LoadExample("city_office");
  const BlindDesign design = *DesignWithOverrides(scene, {{"alpha", 0.6}, {"spacing", 0.05}});
  OneStageParity("city_office", &design, 10);
}

// Both stages and their product on the GPU and on the CPU, each window in parts as by default
// (4 x 3 for the city office's and the corner office's): the GPU's per-part cells and shared
// rows.
void ExpectTwoStageParity(DcBackend* gpu, const Scene& scene, const BlindDesign& design,
                          Sequence sequence = Sequence::kPseudoRandom) {
  OutdoorOptions outdoor;
  outdoor.paths = 2'000'000;
  outdoor.parts = WindowParts{0, 0};
  outdoor.sequence = sequence;
  IndoorOptions indoor;
  indoor.paths_per_sensor = 200'000;
  indoor.parts = outdoor.parts;
  indoor.sequence = sequence;
  absl::StatusOr<OutdoorResult> o_cpu = ComputeOutdoorStage(scene, outdoor);
  absl::StatusOr<OutdoorResult> o_gpu = ComputeOutdoorStage(scene, outdoor, gpu);
  ASSERT_TRUE(o_cpu.ok() && o_gpu.ok());
  ExpectParity(o_cpu->coefficients, o_cpu->standard_error, o_gpu->coefficients,
               o_gpu->standard_error, "outdoor matrix");
  ExpectFormedAsOnTheHost(*o_gpu);
  // The same random streams decide which first segments reach the sky: each window cell's
  // share agrees but for paths that graze an edge
  const double sky_view_difference = (o_cpu->sky_view - o_gpu->sky_view).cwiseAbs().maxCoeff();
  std::printf("sky view: largest difference %.2e over %lld window cells\n", sky_view_difference,
              static_cast<long long>(o_gpu->sky_view.size()));
  EXPECT_LT(sky_view_difference, 0.005);
  EXPECT_GT(o_gpu->sky_view.maxCoeff(), 0.5);
  absl::StatusOr<IndoorResult> i_cpu = ComputeIndoorStage(scene, design, indoor);
  absl::StatusOr<IndoorResult> i_gpu = ComputeIndoorStage(scene, design, indoor, gpu);
  ASSERT_TRUE(i_cpu.ok() && i_gpu.ok());
  ExpectParity(i_cpu->coefficients, i_cpu->standard_error, i_gpu->coefficients,
               i_gpu->standard_error, "indoor matrix");
  // Both tell direct light from light through the window cells alike
  const double direct_cpu = i_cpu->coefficients.rightCols(kIndoorDirectColumns).sum();
  const double direct_gpu = i_gpu->coefficients.rightCols(kIndoorDirectColumns).sum();
  EXPECT_GT(direct_cpu, 0.1 * i_cpu->coefficients.sum());
  EXPECT_NEAR(direct_gpu, direct_cpu, 0.02 * direct_cpu);
  absl::StatusOr<TwoStageResult> d_cpu = CombineStages(*i_cpu, *o_cpu);
  absl::StatusOr<TwoStageResult> d_gpu = CombineStages(*i_gpu, *o_gpu);
  ASSERT_TRUE(d_cpu.ok() && d_gpu.ok());
  ExpectParity(d_cpu->coefficients, d_cpu->standard_error, d_gpu->coefficients,
               d_gpu->standard_error, "daylight coefficients");
  std::printf("outdoor: CPU %.3f s, GPU %.3f s; indoor: CPU %.3f s, GPU %.3f s\n",
              o_cpu->wall_seconds, o_gpu->wall_seconds, i_cpu->wall_seconds, i_gpu->wall_seconds);
}

TEST(CudaBackendTest, TwoStageMatchesEmbree) {
  std::unique_ptr<DcBackend> gpu = Gpu();
  if (!gpu) GTEST_SKIP() << "no CUDA device";
  const Scene scene = LoadExample("city_office");
  ExpectTwoStageParity(gpu.get(), scene,
                       *DesignWithOverrides(scene, {{"alpha", 0.6}, {"spacing", 0.05}}));
}

// The same with the Sobol draws (PathRandom): the device draws what the host draws.
TEST(CudaBackendTest, TwoStageOfSobolDrawsMatchesEmbree) {
  std::unique_ptr<DcBackend> gpu = Gpu();
  if (!gpu) GTEST_SKIP() << "no CUDA device";
  const Scene scene = LoadExample("city_office");
  ExpectTwoStageParity(gpu.get(), scene,
                       *DesignWithOverrides(scene, {{"alpha", 0.6}, {"spacing", 0.05}}),
                       Sequence::kSobol);
}

// Two windows on two walls (examples/corner_office): both backends stack the windows' cells
// alike and draw the same window points.
TEST(CudaBackendTest, TwoStageOfTwoWindowsMatchesEmbree) {
  std::unique_ptr<DcBackend> gpu = Gpu();
  if (!gpu) GTEST_SKIP() << "no CUDA device";
  const Scene scene = LoadExample("corner_office");
  ASSERT_EQ(scene.windows.size(), 2u);
  ExpectTwoStageParity(gpu.get(), scene,
                       *DesignWithOverrides(scene, {{"alpha", 0.6}, {"spacing", 0.05}}));
}

// A skylight with its blind under it (examples/skylight_room): a window facing up.
TEST(CudaBackendTest, TwoStageOfASkylightMatchesEmbree) {
  std::unique_ptr<DcBackend> gpu = Gpu();
  if (!gpu) GTEST_SKIP() << "no CUDA device";
  const Scene scene = LoadExample("skylight_room");
  ASSERT_GT(scene.windows.front().window.normal.z, 0.5);
  ExpectTwoStageParity(gpu.get(), scene,
                       *DesignWithOverrides(scene, {{"alpha", 0.6}, {"spacing", 0.05}}));
}

// The GPU's two-stage sky sums of the corner office and of the skylight room lie within 3
// combined SE + 1% of its one-stage ones over a grid of designs (as on the CPU:
// tests/core/dc/several_windows_test.cpp).
TEST(CudaBackendTest, SeveralWindowsTwoStageMatchesOneStageOverADesignGrid) {
  std::unique_ptr<DcBackend> gpu = Gpu();
  if (!gpu) GTEST_SKIP() << "no CUDA device";
  for (const char* name : {"corner_office", "skylight_room"}) {
    const Scene scene = LoadExample(name);
    ExpectTwoStageMatchesOneStage(scene, static_cast<int>(scene.sensors.size()), gpu.get());
  }
}

// A city-office-sized annual product with random entries: 8 batches of O (window cells and
// direct columns x bins) and of I (9 sensors), and S (bins x steps).
struct RandomInputs {
  std::vector<Matrix> outdoor;
  Matrix sky;
  std::vector<Matrix> indoor;
};
RandomInputs RandomProduct(int steps) {
  const int rows = 3456 + kIndoorDirectColumns, sensors = 9, batches = 8;
  RandomInputs inputs{{}, Matrix::Random(kDaylightBins, steps).cwiseAbs(), {}};
  for (int b = 0; b < batches; ++b) {
    inputs.outdoor.push_back(Matrix::Random(rows, kDaylightBins).cwiseAbs());
    inputs.indoor.push_back(Matrix::Random(sensors, rows).cwiseAbs());
  }
  return inputs;
}

// The same counts in every version, and sums within rounding.
void ExpectSameTallies(const std::vector<HourTally>& got, const std::vector<HourTally>& expected) {
  ASSERT_EQ(got.size(), expected.size());
  for (size_t v = 0; v < got.size(); ++v) {
    const HourTally &a = got[v], &b = expected[v];
    EXPECT_EQ(a.hours, b.hours);
    EXPECT_EQ(a.all_in, b.all_in) << "version " << v;
    EXPECT_EQ(a.any_below, b.any_below) << "version " << v;
    EXPECT_EQ(a.any_above, b.any_above) << "version " << v;
    ASSERT_EQ(a.sensors.size(), b.sensors.size());
    for (size_t i = 0; i < a.sensors.size(); ++i) {
      const SensorHourTally &x = a.sensors[i], &y = b.sensors[i];
      EXPECT_EQ(x.below, y.below) << "version " << v << " sensor " << i;
      EXPECT_EQ(x.above, y.above) << "version " << v << " sensor " << i;
      EXPECT_EQ(x.da, y.da) << "version " << v << " sensor " << i;
      EXPECT_NEAR(x.credit, y.credit, 1e-10 * y.credit);
      EXPECT_NEAR(x.sum, y.sum, 1e-10 * y.sum);
    }
  }
}

// The annual product (I_b O_b) S on the GPU equals the CPU's, also with another sky for one
// call, and a second product on the same backend does not disturb the first.
TEST(CudaBackendTest, AnnualProductMatchesCpu) {
  std::unique_ptr<DcBackend> gpu = Gpu();
  if (!gpu) GTEST_SKIP() << "no CUDA device";
  const auto [outdoor, sky, indoor] = RandomProduct(4380);
  const int rows = static_cast<int>(outdoor[0].rows()), batches = static_cast<int>(indoor.size());
  std::unique_ptr<DcBackend> cpu = MakeEmbreeBackend();
  absl::StatusOr<std::unique_ptr<AnnualProduct>> expected = cpu->MakeAnnualProduct(outdoor, sky);
  absl::StatusOr<std::unique_ptr<AnnualProduct>> first = gpu->MakeAnnualProduct(outdoor, sky);
  absl::StatusOr<std::unique_ptr<AnnualProduct>> second =
      gpu->MakeAnnualProduct(std::vector<Matrix>(batches, Matrix::Zero(rows, kDaylightBins)), sky);
  ASSERT_TRUE(expected.ok() && first.ok() && second.ok());
  absl::StatusOr<std::vector<Matrix>> e_cpu = (*expected)->Apply(indoor);
  absl::StatusOr<std::vector<Matrix>> e_zero = (*second)->Apply(indoor);
  absl::StatusOr<std::vector<Matrix>> e_gpu = (*first)->Apply(indoor);
  ASSERT_TRUE(e_cpu.ok() && e_gpu.ok() && e_zero.ok()) << e_gpu.status();
  for (int b = 0; b < batches; ++b) {
    EXPECT_LT(((*e_gpu)[b] - (*e_cpu)[b]).cwiseAbs().maxCoeff(),
              1e-12 * (*e_cpu)[b].cwiseAbs().maxCoeff());
    EXPECT_EQ((*e_zero)[b].cwiseAbs().maxCoeff(), 0.0);
  }
  // Another sky for one call, as on the CPU; S stays on the device for the next
  const Matrix other = Matrix::Random(kDaylightBins, 777).cwiseAbs();
  absl::StatusOr<std::vector<Matrix>> o_cpu = (*expected)->ApplyToSky(indoor, other);
  absl::StatusOr<std::vector<Matrix>> o_gpu = (*first)->ApplyToSky(indoor, other);
  absl::StatusOr<std::vector<Matrix>> e_again = (*first)->Apply(indoor);
  ASSERT_TRUE(o_cpu.ok() && o_gpu.ok() && e_again.ok()) << o_gpu.status();
  for (int b = 0; b < batches; ++b) {
    ASSERT_EQ((*o_gpu)[b].cols(), 777);
    EXPECT_LT(((*o_gpu)[b] - (*o_cpu)[b]).cwiseAbs().maxCoeff(),
              1e-12 * (*o_cpu)[b].cwiseAbs().maxCoeff());
    // S, not the other sky: E as before, but for the order of the device's sums
    EXPECT_LT(((*e_again)[b] - (*e_gpu)[b]).cwiseAbs().maxCoeff(),
              1e-12 * (*e_gpu)[b].cwiseAbs().maxCoeff());
  }
}

// With a split sky (S, then -S_sun for the unreflected direct columns) and the direct sun's
// entries, the GPU's E and its tallies equal the CPU's: two-stage rows and one-stage [D | D_0]
// rows alike.
TEST(CudaBackendTest, SplitSkyAndDirectSunMatchCpu) {
  std::unique_ptr<DcBackend> gpu = Gpu();
  if (!gpu) GTEST_SKIP() << "no CUDA device";
  const int steps = 2000;
  auto [outdoor, sky, indoor] = RandomProduct(steps);
  Matrix split(kSplitSkyRows, steps);
  split << 1000 * sky, -300 * Matrix::Random(kDaylightBins, steps).cwiseAbs();
  std::vector<SunEntry> sun;
  for (int i = 0; i < 9; ++i) {
    for (int t = i; t < steps; t += 7) sun.push_back({i, t, 40.0 * t});
  }
  std::unique_ptr<DcBackend> cpu = MakeEmbreeBackend();
  const MetricOptions options;
  // Two-stage
  absl::StatusOr<std::unique_ptr<AnnualProduct>> on_cpu = cpu->MakeAnnualProduct(outdoor, split);
  absl::StatusOr<std::unique_ptr<AnnualProduct>> on_gpu = gpu->MakeAnnualProduct(outdoor, split);
  ASSERT_TRUE(on_cpu.ok() && on_gpu.ok()) << on_gpu.status();
  absl::StatusOr<std::vector<Matrix>> e_cpu = (*on_cpu)->ApplyToSky(indoor, split, sun);
  absl::StatusOr<std::vector<Matrix>> e_gpu = (*on_gpu)->ApplyToSky(indoor, split, sun);
  ASSERT_TRUE(e_cpu.ok() && e_gpu.ok()) << e_gpu.status();
  for (size_t b = 0; b < indoor.size(); ++b) {
    EXPECT_LT(((*e_gpu)[b] - (*e_cpu)[b]).cwiseAbs().maxCoeff(),
              1e-12 * (*e_cpu)[b].cwiseAbs().maxCoeff());
  }
  absl::StatusOr<std::vector<HourTally>> t_cpu = (*on_cpu)->Tally(indoor, options, sun);
  absl::StatusOr<std::vector<HourTally>> t_gpu = (*on_gpu)->Tally(indoor, options, sun);
  ASSERT_TRUE(t_cpu.ok() && t_gpu.ok()) << t_gpu.status();
  ExpectSameTallies(*t_gpu, *t_cpu);
  // One-stage rows [D | D_0] through the split sky alone
  std::vector<Matrix> dc;
  for (int b = 0; b < 8; ++b) dc.push_back(Matrix::Random(9, kSplitSkyRows).cwiseAbs());
  absl::StatusOr<std::unique_ptr<AnnualProduct>> sky_cpu = cpu->MakeSkyProduct(split);
  absl::StatusOr<std::unique_ptr<AnnualProduct>> sky_gpu = gpu->MakeSkyProduct(split);
  ASSERT_TRUE(sky_cpu.ok() && sky_gpu.ok()) << sky_gpu.status();
  absl::StatusOr<std::vector<HourTally>> s_cpu = (*sky_cpu)->Tally(dc, options, sun);
  absl::StatusOr<std::vector<HourTally>> s_gpu = (*sky_gpu)->Tally(dc, options, sun);
  ASSERT_TRUE(s_cpu.ok() && s_gpu.ok()) << s_gpu.status();
  ExpectSameTallies(*s_gpu, *s_cpu);
  // Entries out of range, or without a split sky, are refused on both
  const std::vector<SunEntry> bad = {{9, 0, 1.0}};
  EXPECT_EQ((*on_gpu)->Tally(indoor, options, bad).status().code(),
            absl::StatusCode::kInvalidArgument);
  absl::StatusOr<std::unique_ptr<AnnualProduct>> plain = gpu->MakeAnnualProduct(outdoor, sky);
  ASSERT_TRUE(plain.ok());
  EXPECT_EQ((*plain)->Tally(indoor, options, sun).status().code(),
            absl::StatusCode::kInvalidArgument);
}

// Tallies of E formed and reduced on the device equal the CPU's tallies of the same E.
TEST(CudaBackendTest, AnnualTallyMatchesCpu) {
  std::unique_ptr<DcBackend> gpu = Gpu();
  if (!gpu) GTEST_SKIP() << "no CUDA device";
  const int steps = 3000;
  auto [outdoor, sky, indoor] = RandomProduct(steps);
  const int batches = static_cast<int>(indoor.size());
  std::unique_ptr<DcBackend> cpu = MakeEmbreeBackend();
  absl::StatusOr<std::unique_ptr<AnnualProduct>> on_cpu = cpu->MakeAnnualProduct(outdoor, sky);
  absl::StatusOr<std::unique_ptr<AnnualProduct>> on_gpu = gpu->MakeAnnualProduct(outdoor, sky);
  ASSERT_TRUE(on_cpu.ok() && on_gpu.ok());
  absl::StatusOr<std::vector<Matrix>> e = (*on_gpu)->Apply(indoor);
  ASSERT_TRUE(e.ok()) << e.status();

  // Limits at quartiles of E, so every count is far from 0 and from all
  const MetricOptions options = QuartileLimits((*e)[0]);
  absl::StatusOr<std::vector<HourTally>> expected = TallyBatchVersions(*e, options);
  absl::StatusOr<std::vector<HourTally>> from_cpu = (*on_cpu)->Tally(indoor, options);
  absl::StatusOr<std::vector<HourTally>> from_gpu = (*on_gpu)->Tally(indoor, options);
  ASSERT_TRUE(expected.ok() && from_cpu.ok() && from_gpu.ok()) << from_gpu.status();
  ASSERT_EQ(from_gpu->size(), static_cast<size_t>(batches + 1));
  ExpectSameTallies(*from_gpu, *expected);
  ExpectSameTallies(*from_gpu, *from_cpu);
  EXPECT_GT((*from_gpu)[0].any_below, 0);
  EXPECT_GT((*from_gpu)[0].any_above, 0);
  EXPECT_GT((*from_gpu)[0].sensors[0].below, steps / 10);

  // A non-finite coefficient is an error, as on the CPU
  indoor[3](2, 7) = std::numeric_limits<double>::quiet_NaN();
  EXPECT_EQ((*on_gpu)->Tally(indoor, options).status().code(), absl::StatusCode::kInvalidArgument);
  EXPECT_EQ((*on_cpu)->Tally(indoor, options).status().code(), absl::StatusCode::kInvalidArgument);
}

// The product of the sky alone (a job's final check) on the GPU equals the CPU's, for the
// pilot's 32 batches and then the check's 8 through one product.
TEST(CudaBackendTest, SkyProductMatchesCpu) {
  std::unique_ptr<DcBackend> gpu = Gpu();
  if (!gpu) GTEST_SKIP() << "no CUDA device";
  std::srand(5);
  const Matrix sky = Matrix::Random(kDaylightBins, 2000).cwiseAbs();
  std::vector<Matrix> dc;
  for (int b = 0; b < 32; ++b) dc.push_back(Matrix::Random(9, kDaylightBins).cwiseAbs());
  std::unique_ptr<DcBackend> cpu = MakeEmbreeBackend();
  absl::StatusOr<std::unique_ptr<AnnualProduct>> on_cpu = cpu->MakeSkyProduct(sky);
  absl::StatusOr<std::unique_ptr<AnnualProduct>> on_gpu = gpu->MakeSkyProduct(sky);
  ASSERT_TRUE(on_cpu.ok() && on_gpu.ok()) << on_gpu.status();
  const MetricOptions options = QuartileLimits(dc[0] * sky);
  for (const size_t count : {32, 8}) {
    SCOPED_TRACE(count);
    const std::vector<Matrix> some(dc.begin(), dc.begin() + count);
    absl::StatusOr<std::vector<Matrix>> e = (*on_gpu)->Apply(some);
    ASSERT_TRUE(e.ok()) << e.status();
    ASSERT_EQ(e->size(), count);
    for (size_t b = 0; b < count; ++b) {
      const Matrix expected = dc[b] * sky;
      EXPECT_LT(((*e)[b] - expected).cwiseAbs().maxCoeff(), 1e-12 * expected.cwiseAbs().maxCoeff());
    }
    absl::StatusOr<std::vector<HourTally>> from_cpu = (*on_cpu)->Tally(some, options);
    absl::StatusOr<std::vector<HourTally>> from_gpu = (*on_gpu)->Tally(some, options);
    ASSERT_TRUE(from_cpu.ok() && from_gpu.ok()) << from_gpu.status();
    ExpectSameTallies(*from_gpu, *from_cpu);
  }
  EXPECT_EQ((*on_gpu)->Tally({dc[0]}, options).status().code(), absl::StatusCode::kInvalidArgument);
  EXPECT_EQ((*on_gpu)->Tally({dc[0], Matrix::Zero(9, 288)}, options).status().code(),
            absl::StatusCode::kInvalidArgument);
}

// The city office and its outdoor stage on the GPU, 500 000 paths in 4 batches.
struct CityOfficeOutdoor {
  Scene scene;
  OutdoorOptions options;
  absl::StatusOr<OutdoorResult> result;
};
CityOfficeOutdoor TraceCityOfficeOutdoor(DcBackend* gpu) {
  CityOfficeOutdoor city{LoadExample("city_office"), {}, absl::UnknownError("not traced")};
  city.options = OutdoorInParts(city.scene, 500'000, 4);
  city.result = ComputeOutdoorStage(city.scene, city.options, gpu);
  return city;
}

// A search's objective on the GPU, with I and E kept on the device, gives the tallies of
// the indoor stage and annual product taken in turn.
TEST(CudaBackendTest, DesignTalliesMatchTheStagesInTurn) {
  std::unique_ptr<DcBackend> gpu = Gpu();
  if (!gpu) GTEST_SKIP() << "no CUDA device";
  const CityOfficeOutdoor city = TraceCityOfficeOutdoor(gpu.get());
  const Scene& scene = city.scene;
  const OutdoorOptions& outdoor = city.options;
  const absl::StatusOr<OutdoorResult>& o = city.result;
  ASSERT_TRUE(o.ok()) << o.status();
  const Matrix sky = Matrix::Random(kDaylightBins, 500).cwiseAbs();
  const IndoorOptions indoor = IndoorPairedWith(outdoor, 40'000);
  absl::StatusOr<std::unique_ptr<DesignTallies>> on_device =
      gpu->MakeDesignTallies(scene, indoor, o->batches, sky);
  absl::StatusOr<std::unique_ptr<DesignTallies>> in_turn =
      gpu->DcBackend::StartDesignTallies(scene, indoor);
  ASSERT_TRUE(on_device.ok() && in_turn.ok()) << on_device.status();
  ASSERT_TRUE((*in_turn)->SetProduct(o->batches, sky).ok());
  // Limits at quartiles of E, so that sensors fall on either side of them
  absl::StatusOr<IndoorResult> i =
      ComputeIndoorStage(scene, DefaultDesign(scene), indoor, gpu.get());
  ASSERT_TRUE(i.ok());
  const MetricOptions options = QuartileLimits(i->coefficients * o->coefficients * sky);
  for (const double alpha : {0.0, 0.8}) {
    const BlindDesign design = *DesignWithOverrides(scene, {{"alpha", alpha}});
    absl::StatusOr<std::vector<HourTally>> a = (*on_device)->Tally(design, options);
    absl::StatusOr<std::vector<HourTally>> b = (*in_turn)->Tally(design, options);
    ASSERT_TRUE(a.ok() && b.ok()) << a.status() << b.status();
    ASSERT_EQ(a->size(), 5u);
    ASSERT_EQ(a->size(), b->size());
    for (size_t v = 0; v < a->size(); ++v) {
      EXPECT_EQ((*a)[v].hours, 500);
      EXPECT_EQ((*a)[v].all_in, (*b)[v].all_in);
      EXPECT_EQ((*a)[v].any_below, (*b)[v].any_below);
      EXPECT_EQ((*a)[v].any_above, (*b)[v].any_above);
      for (size_t i = 0; i < scene.sensors.size(); ++i) {
        const SensorHourTally &x = (*a)[v].sensors[i], &y = (*b)[v].sensors[i];
        EXPECT_EQ(x.below, y.below);
        EXPECT_EQ(x.above, y.above);
        EXPECT_EQ(x.da, y.da);
        // The kernel's sums differ in the order of their atomic additions only
        EXPECT_NEAR(x.sum, y.sum, 1e-9 * y.sum);
        EXPECT_NEAR(x.credit, y.credit, 1e-9 * y.credit);
      }
    }
    // Not a trivial case: sensors fall on either side of the limits
    if (alpha == 0.0) {
      EXPECT_GT((*a)[0].any_below, 0);
      EXPECT_GT((*a)[0].any_above, 0);
    }
  }
  // A design's I from the replay is its full trace's (the best design's hourly illuminance);
  // rounds after it still end as one call
  const BlindDesign tilted = *DesignWithOverrides(scene, {{"alpha", 0.8}});
  absl::StatusOr<IndoorResult> traced = ComputeIndoorStage(scene, tilted, indoor, gpu.get());
  ASSERT_TRUE(traced.ok()) << traced.status();
  ExpectIndoorBatchesAreTheTrace(**on_device, tilted, *traced);
  ExpectIndoorBatchesAreTheTrace(**in_turn, tilted, *traced);
  // Its E through another sky, formed where the replay's sums lie, is the product of its I
  const Matrix other_sky = Matrix::Random(kDaylightBins, 7).cwiseAbs();
  absl::StatusOr<std::vector<Matrix>> from_sums =
      (*on_device)->DesignIlluminance(tilted, other_sky);
  absl::StatusOr<std::vector<Matrix>> replayed = (*on_device)->IndoorBatches(tilted);
  ASSERT_TRUE(from_sums.ok() && replayed.ok()) << from_sums.status() << replayed.status();
  absl::StatusOr<std::vector<Matrix>> from_host =
      (*on_device)->Product()->ApplyToSky(*replayed, other_sky);
  ASSERT_TRUE(from_host.ok()) << from_host.status();
  ASSERT_EQ(from_sums->size(), from_host->size());
  for (size_t b = 0; b < from_sums->size(); ++b) {
    ASSERT_EQ((*from_sums)[b].rows(), static_cast<Eigen::Index>(scene.sensors.size()));
    ASSERT_EQ((*from_sums)[b].cols(), 7);
    EXPECT_GT((*from_host)[b].maxCoeff(), 0);
    EXPECT_LE(((*from_sums)[b] - (*from_host)[b]).cwiseAbs().maxCoeff(),
              1e-12 * (*from_host)[b].maxCoeff());
  }
  // Several designs replayed in one launch, each E through the product's own S, are each
  // design's E replayed alone through a copy of S (uploaded for the call); a design the
  // replay refuses gets its refusal and leaves the others
  BlindDesign without_blind = tilted;
  without_blind.has_blind = false;
  const std::vector<BlindDesign> several = {*DesignWithOverrides(scene, {{"alpha", 0.0}}), tilted,
                                            without_blind,
                                            *DesignWithOverrides(scene, {{"alpha", 1.2}})};
  std::vector<absl::StatusOr<std::vector<Matrix>>> together =
      (*on_device)->DesignsIlluminance(several);
  ASSERT_EQ(together.size(), several.size());
  EXPECT_EQ(together[2].status().code(), absl::StatusCode::kInvalidArgument);
  const Matrix sky_copy = sky;
  for (const size_t k : {0, 1, 3}) {
    ASSERT_TRUE(together[k].ok()) << together[k].status();
    absl::StatusOr<std::vector<Matrix>> alone =
        (*on_device)->DesignIlluminance(several[k], sky_copy);
    ASSERT_TRUE(alone.ok()) << alone.status();
    ASSERT_EQ(together[k]->size(), alone->size());
    for (size_t b = 0; b < alone->size(); ++b) {
      ASSERT_EQ((*together[k])[b].cols(), sky.cols());
      EXPECT_GT((*alone)[b].maxCoeff(), 0);
      EXPECT_LE(((*together[k])[b] - (*alone)[b]).cwiseAbs().maxCoeff(),
                1e-9 * (*alone)[b].maxCoeff());
    }
  }
  // Without a blind there is nothing to replay: the design is traced in full, and its I is
  // still the indoor stage's (the outdoor stage never sees the blind, so O stays)
  Scene bare = scene;
  bare.blind().reset();
  absl::StatusOr<std::unique_ptr<DesignTallies>> in_full =
      gpu->MakeDesignTallies(bare, indoor, o->batches, sky);
  ASSERT_TRUE(in_full.ok()) << in_full.status();
  absl::StatusOr<IndoorResult> bare_traced =
      ComputeIndoorStage(bare, BlindDesign{}, indoor, gpu.get());
  ASSERT_TRUE(bare_traced.ok()) << bare_traced.status();
  ExpectIndoorBatchesAreTheTrace(**in_full, BlindDesign{}, *bare_traced);
  // In rounds (racing), each round replays only the parts it adds
  ExpectRoundsEndAsOneCall(**on_device, *DesignWithOverrides(scene, {{"alpha", 0.2}}),
                           *DesignWithOverrides(scene, {{"alpha", 1.0}, {"width", 0.05}}), options);
  // Several designs in one launch, each as alone
  EXPECT_GT((*on_device)->DesignsAtOnce(), 1);
  BlindDesign wide = DefaultDesign(scene);
  wide.slat_width_m = 0.3;
  ExpectTogetherAsAlone(**on_device,
                        {*DesignWithOverrides(scene, {{"alpha", 0.2}}),
                         *DesignWithOverrides(scene, {{"alpha", 0.5}, {"width", 0.05}}),
                         *DesignWithOverrides(scene, {{"alpha", 1.2}})},
                        wide, options);
  EXPECT_FALSE((*in_turn)->TracesInParts());
  EXPECT_EQ((*in_turn)->Tally(DefaultDesign(scene), options, 2).status().code(),
            absl::StatusCode::kUnimplemented);
}

// Glare counted where the replay's E lies is the host's count of the same E (CountGlare of
// DesignsIlluminance), design by design and version by version, for designs replayed
// together with their own beams at the eyes; the steps re-uploaded with a new product. The
// sky is scaled to eye illuminances around 3000 lx, so that steps fall on either side of the
// eye limit (4106 lx at DGP 0.4), with and without the beam. (E's entries may differ from
// the host's in their last bits, from the order of the product's atomic additions; a count
// would differ only for a value within those bits of a limit.)
TEST(CudaBackendTest, GlareCountsOnTheDeviceAreTheHostsCounts) {
  std::unique_ptr<DcBackend> gpu = Gpu();
  if (!gpu) GTEST_SKIP() << "no CUDA device";
  const CityOfficeOutdoor city = TraceCityOfficeOutdoor(gpu.get());
  ASSERT_TRUE(city.result.ok()) << city.result.status();
  const Scene& scene = city.scene;
  const int steps = 400;
  std::srand(7);
  const auto uniform = [] { return static_cast<double>(std::rand()) / RAND_MAX; };
  // Steps from dim to bright (a factor of 100), so that each sensor's E crosses the limit
  Matrix unit_sky = Matrix::Random(kDaylightBins, steps).cwiseAbs();
  for (int c = 0; c < steps; ++c) unit_sky.col(c) *= std::exp(std::log(100.0) * uniform());
  absl::StatusOr<std::unique_ptr<DesignTallies>> tallies = gpu->MakeDesignTallies(
      scene, IndoorPairedWith(city.options, 20'000), city.result->batches, unit_sky);
  ASSERT_TRUE(tallies.ok()) << tallies.status();
  const std::vector<BlindDesign> designs = {*DesignWithOverrides(scene, {{"alpha", 0.0}}),
                                            *DesignWithOverrides(scene, {{"alpha", 0.6}}),
                                            *DesignWithOverrides(scene, {{"alpha", 1.2}})};
  absl::StatusOr<std::vector<Matrix>> unit = (*tallies)->DesignIlluminance(designs[0], unit_sky);
  ASSERT_TRUE(unit.ok()) << unit.status();
  std::vector<double> values((*unit)[0].data(), (*unit)[0].data() + (*unit)[0].size());
  std::nth_element(values.begin(), values.begin() + values.size() / 2, values.end());
  ASSERT_GT(values[values.size() / 2], 0);
  const Matrix sky = unit_sky * (3000 / values[values.size() / 2]);

  const int views = static_cast<int>(scene.sensors.size());
  GlareSteps glare;
  glare.threshold = 0.4;
  for (int c = 0; c < steps; ++c) glare.occupied.push_back(uniform() < 0.8);
  glare.sun_factor = Matrix::Zero(views, steps);
  std::vector<std::vector<SunEntry>> sun(designs.size());
  for (int i = 0; i < views; ++i) {
    for (int c = i % 5; c < steps; c += 5) {
      glare.sun_factor(i, c) = 1e3 + 2e4 * uniform();
      for (size_t k = 0; k < designs.size(); ++k) {
        sun[k].push_back({i, c, 3000 * uniform() * static_cast<double>(k + 1) / 3});
      }
    }
  }
  EXPECT_EQ((*tallies)->GlareDesigns(designs, sun)[0].status().code(),
            absl::StatusCode::kFailedPrecondition);
  ASSERT_TRUE((*tallies)->SetGlareSteps(glare).ok());
  ASSERT_TRUE((*tallies)->SetProduct(city.result->batches, sky).ok());  // the steps go with it
  std::vector<absl::StatusOr<GlareCounts>> on_device = (*tallies)->GlareDesigns(designs, sun);
  std::vector<absl::StatusOr<std::vector<Matrix>>> e = (*tallies)->DesignsIlluminance(designs);
  ASSERT_EQ(on_device.size(), designs.size());
  int64_t sunless_glare = 0, sunny_glare = 0, versions_differ = 0, glare_steps = 0;
  const int occupied =
      static_cast<int>(std::count(glare.occupied.begin(), glare.occupied.end(), true));
  for (size_t k = 0; k < designs.size(); ++k) {
    ASSERT_TRUE(on_device[k].ok() && e[k].ok()) << on_device[k].status() << e[k].status();
    absl::StatusOr<GlareCounts> on_host = CountGlare(*e[k], sun[k], glare);
    ASSERT_TRUE(on_host.ok()) << on_host.status();
    ASSERT_EQ(on_device[k]->view_steps.size(), 5u);
    EXPECT_EQ(on_device[k]->view_steps, on_host->view_steps) << "design " << k;
    EXPECT_EQ(on_device[k]->any_steps, on_host->any_steps) << "design " << k;
    for (size_t v = 1; v < 5; ++v) {
      versions_differ += on_host->view_steps[v] != on_host->view_steps[0];
    }
    // The same with the beams dropped: the steps decided by Ev alone
    absl::StatusOr<GlareCounts> sunless = CountGlare(*e[k], {}, glare);
    ASSERT_TRUE(sunless.ok());
    for (int i = 0; i < views; ++i) {
      sunless_glare += sunless->view_steps[0][i];
      sunny_glare += on_host->view_steps[0][i] - sunless->view_steps[0][i];
      glare_steps += on_host->view_steps[0][i];
    }
  }
  // Not a trivial case: Ev alone and the beam both make glare, a quarter of the steps or
  // more are not glare, and the leave-one-out versions see other counts than the mean
  EXPECT_GT(sunless_glare, 0);
  EXPECT_GT(sunny_glare, 0);
  EXPECT_LT(glare_steps, static_cast<int64_t>(designs.size()) * views * occupied * 3 / 4);
  EXPECT_GT(versions_differ, 0);
}

// The outdoor stage's O_b stay on the GPU for its annual products: a product made from them
// there equals one uploaded from the host's copy, and a copy said to lie on another device
// is not taken.
TEST(CudaBackendTest, OutdoorBatchesOnTheDeviceMakeTheHostsProduct) {
  std::unique_ptr<DcBackend> gpu = Gpu();
  if (!gpu) GTEST_SKIP() << "no CUDA device";
  const Scene scene = LoadExample("city_office");
  const OutdoorOptions outdoor = OutdoorInParts(scene, 200'000, 3);
  absl::StatusOr<OutdoorResult> o = ComputeOutdoorStage(scene, outdoor, gpu.get());
  ASSERT_TRUE(o.ok()) << o.status();
  ASSERT_NE(o->batches_on_device.data, nullptr);
  EXPECT_EQ(o->batches_on_device.device, 0);
  const Matrix sky = Matrix::Random(kDaylightBins, 300).cwiseAbs();
  const IndoorOptions indoor = IndoorPairedWith(outdoor, 6'000);
  // Not a device's memory: the product would fail to copy from it
  const DeviceMatrices elsewhere{
      std::shared_ptr<const double>(reinterpret_cast<const double*>(16), [](const double*) {}),
      o->batches_on_device.device + 1};
  std::vector<std::unique_ptr<DesignTallies>> tallies;
  for (const DeviceMatrices* on_device :
       std::vector<const DeviceMatrices*>{&o->batches_on_device, &elsewhere}) {
    absl::StatusOr<std::unique_ptr<DesignTallies>> made = gpu->StartDesignTallies(scene, indoor);
    ASSERT_TRUE(made.ok()) << made.status();
    ASSERT_TRUE((*made)->SetProduct(o->batches, sky, *on_device).ok());
    tallies.push_back(*std::move(made));
  }
  absl::StatusOr<std::unique_ptr<AnnualProduct>> from_host =
      gpu->MakeAnnualProduct(o->batches, sky);
  ASSERT_TRUE(from_host.ok()) << from_host.status();
  const BlindDesign design = *DesignWithOverrides(scene, {{"alpha", 0.6}});
  absl::StatusOr<std::vector<Matrix>> i = tallies[0]->IndoorBatches(design);
  ASSERT_TRUE(i.ok()) << i.status();
  absl::StatusOr<std::vector<Matrix>> expected = (*from_host)->Apply(*i);
  ASSERT_TRUE(expected.ok()) << expected.status();
  for (const auto& t : tallies) {
    absl::StatusOr<std::vector<Matrix>> e = t->Product()->Apply(*i);
    ASSERT_TRUE(e.ok()) << e.status();
    ASSERT_EQ(e->size(), expected->size());
    for (size_t b = 0; b < e->size(); ++b) {
      EXPECT_GT((*expected)[b].maxCoeff(), 0);
      EXPECT_LE(((*e)[b] - (*expected)[b]).cwiseAbs().maxCoeff(),
                1e-12 * (*expected)[b].maxCoeff());
    }
  }
}

// The GPU's replay is the full trace: for designs across the ranges, I equals the indoor
// stage traced in full on the GPU with the same seed, up to the order of the sums (and the
// rare path whose float rounding differs between the two scenes' BVHs).
void ExpectGpuReplayIsTheTrace(DcBackend* gpu, const Scene& scene, const IndoorOptions& options) {
  absl::StatusOr<std::unique_ptr<IndoorStages>> stages = gpu->MakeIndoorStages(scene, options);
  ASSERT_TRUE(stages.ok()) << stages.status();
  ExpectReplayIsTheTrace(scene, options, **stages, gpu);
}

TEST(CudaBackendTest, ReplayEqualsTheIndoorStage) {
  std::unique_ptr<DcBackend> gpu = Gpu();
  if (!gpu) GTEST_SKIP() << "no CUDA device";
  IndoorOptions options;
  options.paths_per_sensor = 20'000;
  options.parts = {2, 2};
  ExpectGpuReplayIsTheTrace(gpu.get(), LoadExample("city_office"), options);
}

// The same with the corner office's two blinds: each record meets the blind whose envelope
// it enters, and a resumed path both blinds' slats.
TEST(CudaBackendTest, ReplayOfTwoBlindsEqualsTheIndoorStage) {
  std::unique_ptr<DcBackend> gpu = Gpu();
  if (!gpu) GTEST_SKIP() << "no CUDA device";
  IndoorOptions options;
  options.paths_per_sensor = 10'000;
  ExpectGpuReplayIsTheTrace(gpu.get(), LoadExample("corner_office"), options);
}

// A bright room (every opaque surface of reflectance 0.9) makes many more window
// connections per path than the city office, more than the room RecordIndoor first makes
// for them (kCrossingsPerPath): its records are traced again with room for all, and the
// replay is still the full trace.
TEST(CudaBackendTest, ReplayOfABrightRoomIsTheIndoorStage) {
  std::unique_ptr<DcBackend> gpu = Gpu();
  if (!gpu) GTEST_SKIP() << "no CUDA device";
  Scene bright = LoadExample("city_office");
  for (Material& m : bright.materials) {
    if (m.transmittance < 0) m.reflectance = 0.9;
  }
  IndoorOptions options;
  options.paths_per_sensor = 10'000;
  options.parts = {2, 2};
  absl::StatusOr<std::unique_ptr<IndoorStages>> stages = gpu->MakeIndoorStages(bright, options);
  ASSERT_TRUE(stages.ok()) << stages.status();
  const BlindDesign design = *DesignWithOverrides(bright, {{"alpha", 0.7}, {"width", 0.1}});
  absl::StatusOr<IndoorResult> traced = ComputeIndoorStage(bright, design, options, gpu.get());
  absl::StatusOr<IndoorResult> replayed = (*stages)->Compute(design);
  ASSERT_TRUE(traced.ok() && replayed.ok()) << traced.status() << replayed.status();
  EXPECT_NE(replayed->backend.find("replay"), std::string::npos) << replayed->backend;
  std::printf("bright room: replay against full trace %.3g relative L1 difference\n",
              ExpectReplayEqualsTrace(*traced, *replayed));
}

// Slats whose outer faces are dark: the replay gives those faces their own material, as the
// full trace's mesh does (GenerateBlind), so it is still the indoor stage, and the room gets
// less light off the slats' upper faces than with light slats.
TEST(CudaBackendTest, ReplayOfSlatsWithDarkOuterFacesIsTheIndoorStage) {
  std::unique_ptr<DcBackend> gpu = Gpu();
  if (!gpu) GTEST_SKIP() << "no CUDA device";
  const Scene light = LoadExample("city_office");
  Scene scene = light;
  scene.materials.push_back({"dark outer faces", 0.05, -1});
  scene.blind()->outer_material = static_cast<uint32_t>(scene.materials.size() - 1);
  IndoorOptions options;
  options.paths_per_sensor = 10'000;
  options.parts = {2, 2};
  absl::StatusOr<std::unique_ptr<IndoorStages>> stages = gpu->MakeIndoorStages(scene, options);
  ASSERT_TRUE(stages.ok()) << stages.status();
  for (const double alpha : {0.0, 0.7, 1.2}) {
    absl::StatusOr<BlindDesign> design =
        DesignWithOverrides(scene, {{"alpha", alpha}, {"spacing", 0.02}});
    ASSERT_TRUE(design.ok()) << design.status();
    absl::StatusOr<IndoorResult> traced = ComputeIndoorStage(scene, *design, options, gpu.get());
    absl::StatusOr<IndoorResult> replayed = (*stages)->Compute(*design);
    ASSERT_TRUE(traced.ok() && replayed.ok()) << traced.status() << replayed.status();
    EXPECT_NE(replayed->backend.find("replay"), std::string::npos) << replayed->backend;
    absl::StatusOr<IndoorResult> lighter = ComputeIndoorStage(light, *design, options, gpu.get());
    ASSERT_TRUE(lighter.ok()) << lighter.status();
    const double ratio = replayed->coefficients.sum() / lighter->coefficients.sum();
    if (alpha > 1) {
      EXPECT_LT(ratio, 0.98);
    }
    std::printf(
        "dark outer faces, alpha %.1f: replay against full trace %.3g relative L1, %.3f of the "
        "light slats' I\n",
        alpha, ExpectReplayEqualsTrace(*traced, *replayed), ratio);
  }
}

// A design's finish on the GPU's replay: its slats take the finish's materials, as the full
// trace's mesh of the design does (GenerateBlind), and as the replay of a scene whose blind is
// of those materials; designs of two finishes traced in one launch are each traced as alone.
TEST(CudaBackendTest, ReplayOfADesignFinishIsTheIndoorStage) {
  std::unique_ptr<DcBackend> gpu = Gpu();
  if (!gpu) GTEST_SKIP() << "no CUDA device";
  Scene scene = LoadExample("city_office");
  scene.materials.push_back({"dark", 0.05, -1});
  const uint32_t dark = static_cast<uint32_t>(scene.materials.size() - 1);
  Scene dark_scene = scene;
  dark_scene.blind()->material = dark;
  IndoorOptions options;
  options.paths_per_sensor = 10'000;
  options.parts = {2, 2};
  absl::StatusOr<std::unique_ptr<IndoorStages>> stages = gpu->MakeIndoorStages(scene, options);
  absl::StatusOr<std::unique_ptr<IndoorStages>> dark_stages =
      gpu->MakeIndoorStages(dark_scene, options);
  ASSERT_TRUE(stages.ok() && dark_stages.ok()) << stages.status() << dark_stages.status();
  absl::StatusOr<BlindDesign> plain =
      DesignWithOverrides(scene, {{"alpha", 0.8}, {"spacing", 0.02}});
  ASSERT_TRUE(plain.ok()) << plain.status();
  BlindDesign finished = *plain;
  finished.finish = SlatFinish{dark, dark};
  absl::StatusOr<IndoorResult> traced = ComputeIndoorStage(scene, finished, options, gpu.get());
  absl::StatusOr<IndoorResult> replayed = (*stages)->Compute(finished);
  absl::StatusOr<IndoorResult> of_scene = (*dark_stages)->Compute(*plain);
  absl::StatusOr<IndoorResult> light = (*stages)->Compute(*plain);
  ASSERT_TRUE(traced.ok() && replayed.ok() && of_scene.ok() && light.ok());
  EXPECT_NE(replayed->backend.find("replay"), std::string::npos) << replayed->backend;
  std::printf(
      "dark finish: replay against full trace %.3g relative L1, against the dark "
      "scene's replay %.3g\n",
      ExpectReplayEqualsTrace(*traced, *replayed), ExpectReplayEqualsTrace(*of_scene, *replayed));
  EXPECT_LT(replayed->coefficients.sum(), 0.98 * light->coefficients.sum());
}

// The stiff scenes of the one-stage tests, on the GPU: finite, and matching the CPU.
TEST(CudaBackendTest, StiffScenesStayFiniteAndMatch) {
  std::unique_ptr<DcBackend> gpu = Gpu();
  if (!gpu) GTEST_SKIP() << "no CUDA device";
  // A white lightwell (reflectance 0.99 everywhere, 1000 bounces), far from the origin
  Scene white = LoadExample("lightwell");
  for (Material& m : white.materials) m.reflectance = 0.99;
  for (Vec3d& v : white.fixed.vertices) v += Vec3d{1e4, 1e4, 0};
  for (Sensor& s : white.sensors) s.position += Vec3d{1e4, 1e4, 0};
  OneStageOptions options;
  options.paths_per_sensor = 200'000;
  options.max_bounces = 1000;
  options.weight_windows = false;
  absl::StatusOr<OneStageResult> cpu = ComputeOneStage(white, DefaultDesign(white), options);
  absl::StatusOr<OneStageResult> cuda =
      ComputeOneStage(white, DefaultDesign(white), options, gpu.get());
  ASSERT_TRUE(cpu.ok() && cuda.ok());
  EXPECT_EQ(cuda->coefficients.col(0).sum(), 0.0);  // nothing below the horizon
  ExpectParity(cpu->coefficients, cpu->standard_error, cuda->coefficients, cuda->standard_error,
               "white lightwell at (1e4, 1e4)");
  // A closed blind with touching slats
  const Scene office = LoadExample("city_office");
  const BlindDesign closed = *DesignWithOverrides(office, {{"alpha", 0}, {"spacing", 0}});
  options.max_bounces = 10;
  cpu = ComputeOneStage(office, closed, options);
  cuda = ComputeOneStage(office, closed, options, gpu.get());
  ASSERT_TRUE(cpu.ok() && cuda.ok());
  ExpectParity(cpu->coefficients, cpu->standard_error, cuda->coefficients, cuda->standard_error,
               "closed blind");
}

}  // namespace
}  // namespace fenestra
