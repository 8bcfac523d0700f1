#include "core/dc/two_stage.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <numeric>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include "core/dc/backend_support.h"
#include "core/dc/one_stage.h"
#include "core/metrics/illuminance.h"
#include "core/metrics/metric_errors.h"
#include "core/metrics/occupancy.h"
#include "core/sky/epw.h"
#include "core/sky/sky_matrix.h"
#include "core/trace/embree_scene.h"
#include "core/trace/two_stage_cpu.h"
#include "tests/example_scene.h"

namespace fenestra {
namespace {

// One-stage and two-stage D of `scene` at `design` with their batches.
struct Comparison {
  OneStageResult one_stage;
  TwoStageResult two_stage;
  double one_stage_seconds = 0, two_stage_seconds = 0;
};

struct Sampling {
  int64_t one_stage_paths, outdoor_paths, indoor_paths;
  int bounces;  // < 0: unlimited (roulette)
  WindowParts parts;
  int cells = 288;
};

Comparison Compare(const Scene& scene, const BlindDesign& design, const Sampling& sampling) {
  Comparison c;
  OneStageOptions one;
  one.paths_per_sensor = sampling.one_stage_paths;
  one.max_bounces = sampling.bounces;
  one.seed = 11;
  one.batches = kDefaultBatches;
  absl::StatusOr<OneStageResult> reference = ComputeOneStage(scene, design, one);
  EXPECT_TRUE(reference.ok()) << reference.status();
  c.one_stage = *reference;
  c.one_stage_seconds = reference->wall_seconds;
  OutdoorOptions outdoor;
  outdoor.paths = sampling.outdoor_paths;
  outdoor.max_bounces = sampling.bounces;
  outdoor.basis_cells = sampling.cells;
  outdoor.parts = sampling.parts;
  outdoor.seed = 12;
  IndoorOptions indoor;
  indoor.paths_per_sensor = sampling.indoor_paths;
  indoor.max_bounces = sampling.bounces;
  indoor.basis_cells = sampling.cells;
  indoor.parts = sampling.parts;
  indoor.seed = 13;
  absl::StatusOr<OutdoorResult> o = ComputeOutdoorStage(scene, outdoor);
  EXPECT_TRUE(o.ok()) << o.status();
  absl::StatusOr<IndoorResult> i = ComputeIndoorStage(scene, design, indoor);
  EXPECT_TRUE(i.ok()) << i.status();
  absl::StatusOr<TwoStageResult> d = CombineStages(*i, *o);
  EXPECT_TRUE(d.ok()) << d.status();
  c.two_stage = *d;
  c.two_stage_seconds = o->wall_seconds + i->wall_seconds;
  return c;
}

// Per sensor, the two-stage sky sum lies within 3 combined standard errors plus 1% of the
// one-stage one.
void ExpectSkySumsAgree(const Comparison& c, const std::string& name) {
  for (int i = 0; i < c.one_stage.sky_sum.size(); ++i) {
    const double one = c.one_stage.sky_sum(i), two = c.two_stage.sky_sum(i);
    const double se =
        std::hypot(c.one_stage.sky_sum_standard_error(i), c.two_stage.sky_sum_standard_error(i));
    std::printf("%s sensor %d: one-stage %.5e ± %.2e, two-stage %.5e ± %.2e: %+.2f%% (%+.1f SE)\n",
                name.c_str(), i + 1, one, c.one_stage.sky_sum_standard_error(i), two,
                c.two_stage.sky_sum_standard_error(i), 100 * (two / one - 1), (two - one) / se);
    EXPECT_LE(std::abs(two - one), 3 * se + 0.01 * one) << name << " sensor " << i + 1;
  }
}

TEST(TwoStageTest, LightwellAgreesWithOneStage) {
  const Scene scene = LoadExample("lightwell");
  const Comparison c =
      Compare(scene, DefaultDesign(scene),
              {1'000'000, 2'000'000, 1'000'000, 29, AutomaticWindowParts(scene.window())});
  ExpectSkySumsAgree(c, "lightwell");
  // Nothing reaches the ground bin: the well has no view below the horizon
  EXPECT_EQ(c.two_stage.coefficients.col(0).cwiseAbs().maxCoeff(), 0.0);
}

// The annual sky of the city office's site and its analysed hours, for UDI.
struct AnnualSky {
  Matrix radiance;
  std::vector<int> columns;
  std::vector<bool> occupied;
};

const AnnualSky& CityOfficeSky() {
  static const AnnualSky sky = [] {
    AnnualSky s;
    absl::StatusOr<EpwData> weather =
        ReadEpw(FENESTRA_SOURCE_DIR "/examples/weather/URY_Montevideo.865800_IWEC.epw");
    EXPECT_TRUE(weather.ok()) << weather.status();
    absl::StatusOr<SkyMatrix> matrix = BuildSkyMatrix(*weather);
    EXPECT_TRUE(matrix.ok()) << matrix.status();
    std::vector<double> hours;
    for (const SkyStep& step : matrix->steps) hours.push_back(step.hour);
    s.occupied = *OccupiedSteps(hours);
    for (const int c : LitColumns(matrix->radiance)) {
      if (s.occupied[c]) s.columns.push_back(c);
    }
    s.radiance = matrix->radiance;
    return s;
  }();
  return sky;
}

// The scene's mean UDI [%] and its jackknife error from batches of D.
std::pair<double, double> Udi(const std::vector<Matrix>& batches) {
  const AnnualSky& sky = CityOfficeSky();
  absl::StatusOr<AnnualMetricsEstimate> m = AnnualMetricsWithErrors(
      batches, std::span<const Matrix>(&sky.radiance, 1), sky.columns, sky.occupied);
  EXPECT_TRUE(m.ok()) << m.status();
  return {m->value.scene.udi_mean_percent, m->standard_error.scene.udi_mean_percent};
}

// The hardest blind designs for the split at the window, bounces unlimited in both
// methods: open slats in the window plane (the four-variable optimum of the source
// publication, and thin slats with wide gaps), the perpendicular shelves, and the source's
// tilt. Every sensor's two-stage sky sum lies within 3 combined standard errors plus 1% of
// the one-stage one, and the scene's UDI within 0.5 percentage points plus 2 combined
// jackknife errors (at these path counts the UDI of either method is known to 0.1-0.4
// points).
struct HardDesign {
  const char* name;
  double alpha, width, spacing, thickness;
};

class HardDesignTest : public testing::TestWithParam<HardDesign> {};

TEST_P(HardDesignTest, AgreesWithOneStage) {
  const HardDesign h = GetParam();
  const Scene scene = LoadExample("city_office");
  absl::StatusOr<BlindDesign> design = DesignWithOverrides(
      scene,
      {{"alpha", h.alpha}, {"width", h.width}, {"spacing", h.spacing}, {"thickness", h.thickness}});
  ASSERT_TRUE(design.ok()) << design.status();
  const Comparison c = Compare(
      scene, *design, {200'000, 2'000'000, 200'000, -1, AutomaticWindowParts(scene.window())});
  ExpectSkySumsAgree(c, h.name);
  const auto [one, one_se] = Udi(c.one_stage.batch_coefficients);
  const auto [two, two_se] = Udi(c.two_stage.batches);
  std::printf("%s: UDI one-stage %.2f ± %.2f %%, two-stage %.2f ± %.2f %% (%.1f s and %.1f s)\n",
              h.name, one, one_se, two, two_se, c.one_stage_seconds, c.two_stage_seconds);
  EXPECT_LE(std::abs(two - one), 0.5 + 2 * std::hypot(one_se, two_se)) << h.name;
}

INSTANTIATE_TEST_SUITE_P(CityOffice, HardDesignTest,
                         testing::Values(HardDesign{"optimum", 0.0, 0.13, 0.07, 0.014},
                                         HardDesign{"thin_wide_gaps", 0.0, 0.05, 0.10, 0.01},
                                         HardDesign{"shelves", 1.5707963267948966, 0.15, 0.0, 0.02},
                                         HardDesign{"source_tilt", 0.58, 0.15, 0.05, 0.02}),
                         [](const testing::TestParamInfo<HardDesign>& info) {
                           return std::string(info.param.name);
                         });

// The standard errors are the whole error: over independent seeds of both stages, the
// sensors' sky sums scatter about their mean as their standard errors say. z = (x_k - mean)
// / (the rms of the K reported errors) x sqrt(K / (K - 1)) has unit variance when the
// errors are right; 8 seeds x 9 sensors give its standard deviation to about +-0.1 (and
// sensors share O's noise, so less), hence the band [0.6, 1.4]. Both sequences: with the
// Sobol draws the batches are independent randomizations, their scatter the error.
void ExpectSkySumErrorsMatchTheSpreadOverSeeds(Sequence sequence) {
  const Scene scene = LoadExample("city_office");
  absl::StatusOr<BlindDesign> design = DesignWithOverrides(
      scene, {{"alpha", 0.0}, {"width", 0.13}, {"spacing", 0.07}, {"thickness", 0.014}});
  ASSERT_TRUE(design.ok());
  constexpr int kSeeds = 8;
  std::vector<Eigen::VectorXd> sums, errors;
  for (int seed = 1; seed <= kSeeds; ++seed) {
    OutdoorOptions outdoor;
    outdoor.paths = 400'000;
    outdoor.max_bounces = -1;
    outdoor.parts = AutomaticWindowParts(scene.window());
    outdoor.seed = 100 + seed;
    outdoor.sequence = sequence;
    IndoorOptions indoor;
    indoor.paths_per_sensor = 20'000;
    indoor.max_bounces = -1;
    indoor.parts = outdoor.parts;
    indoor.seed = 200 + seed;
    indoor.sequence = sequence;
    absl::StatusOr<OutdoorResult> o = ComputeOutdoorStage(scene, outdoor);
    absl::StatusOr<IndoorResult> i = ComputeIndoorStage(scene, *design, indoor);
    ASSERT_TRUE(o.ok() && i.ok());
    absl::StatusOr<TwoStageResult> d = CombineStages(*i, *o);
    ASSERT_TRUE(d.ok());
    sums.push_back(d->sky_sum);
    errors.push_back(d->sky_sum_standard_error);
  }
  std::vector<double> z;
  for (Eigen::Index s = 0; s < sums[0].size(); ++s) {
    double mean = 0, mean_variance = 0;
    for (int k = 0; k < kSeeds; ++k) {
      mean += sums[k](s) / kSeeds;
      mean_variance += errors[k](s) * errors[k](s) / kSeeds;
    }
    for (int k = 0; k < kSeeds; ++k) {
      z.push_back((sums[k](s) - mean) / std::sqrt(mean_variance) *
                  std::sqrt(kSeeds / (kSeeds - 1.0)));
    }
  }
  double squares = 0;
  for (const double v : z) squares += v * v;
  const double sd = std::sqrt(squares / z.size());
  std::printf("sky sums over %d seeds: z-score standard deviation %.2f (%zu z-scores)\n", kSeeds,
              sd, z.size());
  EXPECT_GE(sd, 0.6);
  EXPECT_LE(sd, 1.4);
}

TEST(TwoStageTest, SkySumErrorsMatchTheSpreadOverSeeds) {
  ExpectSkySumErrorsMatchTheSpreadOverSeeds(Sequence::kPseudoRandom);
}

TEST(TwoStageTest, SkySumErrorsOfSobolDrawsMatchTheSpreadOverSeeds) {
  ExpectSkySumErrorsMatchTheSpreadOverSeeds(Sequence::kSobol);
}

TEST(TwoStageTest, StagesSeeOnlyTheirSide) {
  const Scene scene = LoadExample("city_office");
  OutdoorOptions outdoor;
  outdoor.paths = 288 * 200;
  absl::StatusOr<OutdoorResult> o = ComputeOutdoorStage(scene, outdoor);
  ASSERT_TRUE(o.ok()) << o.status();
  EXPECT_EQ(o->triangles, 16u + 7u * 12u);  // the block's exterior and the seven boxes
  IndoorOptions indoor;
  indoor.paths_per_sensor = 1000;
  const BlindDesign design = DefaultDesign(scene);
  absl::StatusOr<IndoorResult> i = ComputeIndoorStage(scene, design, indoor);
  ASSERT_TRUE(i.ok()) << i.status();
  EXPECT_EQ(i->triangles, 26u + 120u);  // room, reveals and 10 slats
}

// The outdoor surfaces only sort the indoor stage's light into columns: enclosing the
// outside in a closed box moves all of it from the direct columns into the window cells,
// the same light (same seed); and D, with no sky in view, is zero.
TEST(TwoStageTest, OutdoorGeometryOnlySortsTheIndoorLight) {
  Scene scene = LoadExample("lightwell");
  Scene enclosed = scene;
  TriangleMesh box;
  const Vec3d lo{-5, -10, -1}, hi{5, 10, 25};
  auto corner = [&](int i) {
    return Vec3d{(i & 1) ? hi.x : lo.x, (i & 2) ? hi.y : lo.y, (i & 4) ? hi.z : lo.z};
  };
  const int faces[6][4] = {{0, 2, 6, 4}, {1, 5, 7, 3}, {0, 4, 5, 1},
                           {2, 3, 7, 6}, {0, 1, 3, 2}, {4, 6, 7, 5}};
  box.part_names = {"enclosure"};
  for (const auto& f : faces) {
    box.Add(corner(f[0]), corner(f[1]), corner(f[2]), 0, Side::kOutdoor, 0);
    box.Add(corner(f[0]), corner(f[2]), corner(f[3]), 0, Side::kOutdoor, 0);
  }
  enclosed.fixed.Append(box);
  IndoorOptions indoor;
  indoor.paths_per_sensor = 20'000;
  absl::StatusOr<IndoorResult> a = ComputeIndoorStage(scene, DefaultDesign(scene), indoor);
  absl::StatusOr<IndoorResult> b = ComputeIndoorStage(enclosed, DefaultDesign(enclosed), indoor);
  ASSERT_TRUE(a.ok() && b.ok());
  const Eigen::Index cells = a->coefficients.cols() - kIndoorDirectColumns;
  EXPECT_GT(a->coefficients.rightCols(kIndoorDirectColumns).sum(), 0);
  EXPECT_EQ(b->coefficients.rightCols(kIndoorDirectColumns).sum(), 0);
  for (Eigen::Index s = 0; s < a->coefficients.rows(); ++s) {
    const double total = a->coefficients.row(s).sum();
    EXPECT_NEAR(b->coefficients.row(s).sum(), total, 1e-12 * total);
    EXPECT_NEAR(b->coefficients.row(s).head(cells).sum(), total, 1e-12 * total);
  }
  OutdoorOptions outdoor;
  outdoor.paths = 288 * 100;
  absl::StatusOr<OutdoorResult> open = ComputeOutdoorStage(scene, outdoor);
  absl::StatusOr<OutdoorResult> closed = ComputeOutdoorStage(enclosed, outdoor);
  ASSERT_TRUE(open.ok() && closed.ok());
  EXPECT_GT(open->sky_view.maxCoeff(), 0);
  EXPECT_EQ(closed->sky_view.maxCoeff(), 0);
  EXPECT_EQ(closed->coefficients.topRows(cells).sum(), 0);  // no sky is visible from the window
  absl::StatusOr<TwoStageResult> d = CombineStages(*b, *closed);
  ASSERT_TRUE(d.ok()) << d.status();
  EXPECT_EQ(d->coefficients.sum(), 0);
}

// The window cells whose views all meet a surface skip the outdoor test; the indoor stage's
// sums are the same with and without them, to the bit.
TEST(TwoStageTest, SkippedOutdoorTestsChangeNothing) {
  const Scene scene = LoadExample("city_office");
  absl::StatusOr<BlindDesign> design = DesignWithOverrides(scene, {{"alpha", 1.2}});
  ASSERT_TRUE(design.ok());
  absl::StatusOr<TraceGeometry> indoor = PrepareTraceGeometry(
      SelectSide(AssembleMesh(scene, *design), Side::kIndoor), scene.materials);
  absl::StatusOr<TraceGeometry> outdoor = OutdoorViewGeometry(scene);
  ASSERT_TRUE(indoor.ok() && outdoor.ok());
  absl::StatusOr<std::unique_ptr<EmbreeScene>> room = EmbreeScene::Build(*indoor);
  absl::StatusOr<std::unique_ptr<EmbreeScene>> city = EmbreeScene::Build(*outdoor);
  ASSERT_TRUE(room.ok() && city.ok());
  const HemisphereBasis basis = Beckers288();
  const std::vector<TraceWindow> window =
      LocalWindows(*indoor, scene, AutomaticWindowParts(scene.window()), basis);
  const std::vector<uint8_t> met = OutdoorMetCells(*indoor, *outdoor, window, basis);
  EXPECT_GT(std::count(met.begin(), met.end(), 1), 1000);  // the street and the buildings
  IndoorOptions options;
  options.max_bounces = -1;
  std::vector<IndoorTally> tallies;
  for (const uint8_t* skip : {static_cast<const uint8_t*>(nullptr), met.data()}) {
    const OutdoorView<EmbreeIntersector> view{(*city)->Intersector(),
                                              OutdoorOffset(*indoor, *outdoor), skip};
    tallies.push_back(TraceIndoorCpu((*room)->Intersector(), indoor->Surfaces(), view,
                                     LocalSensors(*indoor, scene.sensors), window, basis, 10'000, 8,
                                     1, IndoorPathSettings(options), 0));
  }
  EXPECT_EQ(tallies[0].sum, tallies[1].sum);
  EXPECT_GT(std::accumulate(tallies[0].sum.begin(), tallies[0].sum.end(), 0.0), 0);
}

// With no outdoor surfaces every view from the window reaches the sky: O's window cells are
// empty, and D is I's direct part, each sky bin exactly as one-stage paths would bin it.
TEST(TwoStageTest, WithoutOutdoorSurfacesAllLightIsDirect) {
  Scene scene = LoadExample("lightwell");
  scene.fixed = SelectSide(scene.fixed, Side::kIndoor);
  OutdoorOptions outdoor;
  outdoor.paths = 288 * 8 * 4;
  IndoorOptions indoor;
  indoor.paths_per_sensor = 20'000;
  absl::StatusOr<OutdoorResult> o = ComputeOutdoorStage(scene, outdoor);
  absl::StatusOr<IndoorResult> i = ComputeIndoorStage(scene, DefaultDesign(scene), indoor);
  ASSERT_TRUE(o.ok() && i.ok()) << o.status() << i.status();
  EXPECT_EQ(o->triangles, 0u);
  EXPECT_EQ(o->sky_view.minCoeff(), 1.0);
  const Eigen::Index cells = o->sky_view.size();
  EXPECT_EQ(o->coefficients.topRows(cells).cwiseAbs().maxCoeff(), 0.0);
  EXPECT_EQ(i->coefficients.leftCols(cells).cwiseAbs().maxCoeff(), 0.0);
  absl::StatusOr<TwoStageResult> d = CombineStages(*i, *o);
  ASSERT_TRUE(d.ok());
  // Both blocks of direct columns: light reflected in the room, then the sensor's own view
  const Matrix direct =
      i->coefficients.middleCols(cells, kDaylightBins) + i->coefficients.rightCols(kDaylightBins);
  EXPECT_LT((d->coefficients - direct).cwiseAbs().maxCoeff(), 1e-15);
  EXPECT_GT(d->sky_sum.minCoeff(), 0);
}

TEST(TwoStageTest, ClosedBlindBlocksMostDirectLight) {
  const Scene scene = LoadExample("city_office");
  IndoorOptions indoor;
  indoor.paths_per_sensor = 20'000;
  indoor.max_bounces = 0;  // the window seen directly from the sensors
  auto direct = [&](double alpha) {
    absl::StatusOr<BlindDesign> design =
        DesignWithOverrides(scene, {{"alpha", alpha}, {"spacing", 0}});
    EXPECT_TRUE(design.ok());
    absl::StatusOr<IndoorResult> i = ComputeIndoorStage(scene, *design, indoor);
    EXPECT_TRUE(i.ok()) << i.status();
    return i->coefficients.sum();
  };
  const double open = direct(std::numbers::pi / 2), closed = direct(0);
  // The closed slats cover the opening; only steep rays pass between the bottom slat and
  // the sill, or the top slat and the head (the blind hangs 8.5 cm behind the wall and is
  // no larger than the opening): 2.5% of the open blind's direct light
  std::printf("direct view of the window: open %.4e, closed %.4e\n", open, closed);
  EXPECT_GT(open, 0);
  EXPECT_LT(closed, 0.04 * open);
}

TEST(TwoStageTest, WindowPartsParseAndDefault) {
  absl::StatusOr<WindowParts> parts = ParseWindowParts("4x2");
  ASSERT_TRUE(parts.ok()) << parts.status();
  EXPECT_EQ(parts->columns, 4);
  EXPECT_EQ(parts->rows, 2);
  for (const std::string bad : {"0x1", "1x17", "4", "4x", "x2", "4x2x1", "-1x2", "ax2"}) {
    EXPECT_FALSE(ParseWindowParts(bad).ok()) << bad;
  }
  Window window;
  window.width_m = 2.0, window.height_m = 1.5;
  EXPECT_EQ(AutomaticWindowParts(window), (WindowParts{4, 3}));
  window.width_m = 0.3, window.height_m = 0.5;
  EXPECT_EQ(AutomaticWindowParts(window), (WindowParts{1, 1}));
  window.width_m = 12, window.height_m = 3.01;
  EXPECT_EQ(AutomaticWindowParts(window), (WindowParts{8, 7}));
}

// Splitting the window only re-bins the indoor stage: the same random numbers give the
// same contributions, so I summed over the parts is I of the whole window, and the direct
// columns are the same.
TEST(TwoStageTest, IndoorPartsSumToTheWholeWindow) {
  const Scene scene = LoadExample("city_office");
  IndoorOptions whole;
  whole.paths_per_sensor = 20'000;
  IndoorOptions split = whole;
  split.parts = {3, 2};
  absl::StatusOr<IndoorResult> a = ComputeIndoorStage(scene, DefaultDesign(scene), whole);
  absl::StatusOr<IndoorResult> b = ComputeIndoorStage(scene, DefaultDesign(scene), split);
  ASSERT_TRUE(a.ok() && b.ok());
  ASSERT_EQ(b->coefficients.cols(), 6 * 288 + kIndoorDirectColumns);
  Matrix summed = Matrix::Zero(a->coefficients.rows(), 288);
  for (int part = 0; part < 6; ++part) summed += b->coefficients.middleCols(part * 288, 288);
  const double largest = a->coefficients.cwiseAbs().maxCoeff();
  EXPECT_LT((summed - a->coefficients.leftCols(288)).cwiseAbs().maxCoeff(), 1e-12 * largest);
  EXPECT_LT((b->coefficients.rightCols(kIndoorDirectColumns) -
             a->coefficients.rightCols(kIndoorDirectColumns))
                .cwiseAbs()
                .maxCoeff(),
            1e-12 * largest);
  // Every part receives light
  for (int part = 0; part < 6; ++part)
    EXPECT_GT(b->coefficients.middleCols(part * 288, 288).sum(), 0);
  // D needs matching parts on both sides
  OutdoorOptions outdoor;
  outdoor.paths = 288 * 10;
  absl::StatusOr<OutdoorResult> o = ComputeOutdoorStage(scene, outdoor);
  ASSERT_TRUE(o.ok());
  EXPECT_TRUE(CombineStages(*a, *o).ok());
  EXPECT_EQ(CombineStages(*b, *o).status().code(), absl::StatusCode::kInvalidArgument);
}

TEST(TwoStageTest, RejectsBadOptions) {
  const Scene scene = LoadExample("lightwell");
  OutdoorOptions outdoor;
  outdoor.basis_cells = 100;
  EXPECT_EQ(ComputeOutdoorStage(scene, outdoor).status().code(),
            absl::StatusCode::kInvalidArgument);
  outdoor = {};
  outdoor.batches = 1;
  EXPECT_EQ(ComputeOutdoorStage(scene, outdoor).status().code(),
            absl::StatusCode::kInvalidArgument);
  outdoor = {};
  outdoor.paths = 288 * 8 - 1;  // fewer than one path per window cell and batch
  EXPECT_EQ(ComputeOutdoorStage(scene, outdoor).status().code(),
            absl::StatusCode::kInvalidArgument);
  IndoorOptions indoor;
  indoor.batches = 1;
  EXPECT_EQ(ComputeIndoorStage(scene, DefaultDesign(scene), indoor).status().code(),
            absl::StatusCode::kInvalidArgument);
  // The stages' batches pair up, so their counts must agree
  outdoor = {};
  outdoor.paths = 288 * 8;
  indoor = {};
  indoor.paths_per_sensor = 1000;
  indoor.batches = 4;
  absl::StatusOr<OutdoorResult> o = ComputeOutdoorStage(scene, outdoor);
  absl::StatusOr<IndoorResult> i = ComputeIndoorStage(scene, DefaultDesign(scene), indoor);
  ASSERT_TRUE(o.ok() && i.ok());
  absl::StatusOr<TwoStageResult> d = CombineStages(*i, *o);
  EXPECT_EQ(d.status().code(), absl::StatusCode::kInvalidArgument);
  EXPECT_NE(d.status().message().find("batches"), std::string::npos) << d.status();
}

}  // namespace
}  // namespace fenestra
