#include "core/dc/two_stage.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <numbers>

#include "core/dc/one_stage.h"
#include "tests/example_scene.h"

namespace fenestra {
namespace {

struct RowSums {
  Eigen::VectorXd value, standard_error;
};

RowSums SkySums(const TwoStageResult& two_stage) {
  return {two_stage.sky_sum, two_stage.sky_sum_standard_error};
}

struct Comparison {
  TwoStageResult coarse, fine;
  OneStageResult one_stage;
};

// One-stage D and two-stage D (288 and 1152 cells, the window in `parts`) of `scene` at
// `design`.
Comparison Compare(const Scene& scene, const BlindDesign& design, int64_t one_stage_paths,
                   int64_t outdoor_paths, int64_t indoor_paths, int bounces, WindowParts parts) {
  Comparison c;
  OneStageOptions one;
  one.paths_per_sensor = one_stage_paths;
  one.max_bounces = bounces;
  one.seed = 11;
  absl::StatusOr<OneStageResult> reference = ComputeOneStage(scene, design, one);
  EXPECT_TRUE(reference.ok()) << reference.status();
  c.one_stage = *reference;
  for (int cells : {288, 1152}) {
    OutdoorOptions outdoor;
    outdoor.paths = outdoor_paths;
    outdoor.max_bounces = bounces;
    outdoor.basis_cells = cells;
    outdoor.parts = parts;
    outdoor.seed = 12;
    IndoorOptions indoor;
    indoor.paths_per_sensor = indoor_paths;
    indoor.max_bounces = bounces;
    indoor.basis_cells = cells;
    indoor.parts = parts;
    indoor.seed = 13;
    indoor.batches = 16;
    absl::StatusOr<OutdoorResult> o = ComputeOutdoorStage(scene, outdoor);
    EXPECT_TRUE(o.ok()) << o.status();
    absl::StatusOr<IndoorResult> i = ComputeIndoorStage(scene, design, indoor);
    EXPECT_TRUE(i.ok()) << i.status();
    absl::StatusOr<TwoStageResult> d = CombineStages(*i, *o);
    EXPECT_TRUE(d.ok()) << d.status();
    (cells == 288 ? c.coarse : c.fine) = *d;
  }
  return c;
}

// Per sensor, two-stage and one-stage sky sums agree within 3 combined standard errors plus
// the basis bias. The bias of a piecewise-constant direction basis scales with the cells'
// angular size, which halves from 288 to 1152 cells; so the measured difference between
// the two bases, d = b_288 - b_1152 = b_288 / 2, gives b_288 = 2 d and b_1152 = d.
void ExpectAgreement(const Comparison& c, const std::string& name) {
  const RowSums coarse = SkySums(c.coarse), fine = SkySums(c.fine);
  for (int i = 0; i < coarse.value.size(); ++i) {
    const double one = c.one_stage.sky_sum(i), one_se = c.one_stage.sky_sum_standard_error(i);
    const double difference = std::abs(coarse.value(i) - fine.value(i));
    std::printf(
        "%s sensor %d: one-stage %.5e ± %.2e, two-stage 288 %.5e ± %.2e, 1152 %.5e ± "
        "%.2e, basis difference %.2e (± %.2e)\n",
        name.c_str(), i + 1, one, one_se, coarse.value(i), coarse.standard_error(i), fine.value(i),
        fine.standard_error(i), difference,
        std::hypot(coarse.standard_error(i), fine.standard_error(i)));
    // The bases must agree closely, or the bias term would hide any error
    EXPECT_LT(difference, 0.05 * one) << name << " sensor " << i + 1;
    for (const auto& [two, bias] :
         {std::pair{&coarse, 2 * difference}, std::pair{&fine, difference}}) {
      const double se = std::hypot(one_se, two->standard_error(i));
      EXPECT_LE(std::abs(two->value(i) - one), 3 * se + bias) << name << " sensor " << i + 1;
    }
  }
}

TEST(TwoStageTest, LightwellAgreesWithOneStage) {
  const Scene scene = LoadExample("lightwell");
  const Comparison c = Compare(scene, DefaultDesign(scene), 1'000'000, 2'000'000, 1'000'000, 29,
                               AutomaticWindowParts(scene.window));
  ExpectAgreement(c, "lightwell");
  // Nothing reaches the ground bin: the well has no view below the horizon
  EXPECT_EQ(c.coarse.coefficients.col(0).cwiseAbs().maxCoeff(), 0.0);
}

TEST(TwoStageTest, CityOfficeAgreesWithOneStage) {
  const Scene scene = LoadExample("city_office");
  absl::StatusOr<BlindDesign> design =
      DesignWithOverrides(scene, {{"alpha", 0.8}, {"spacing", 0.05}});
  ASSERT_TRUE(design.ok()) << design.status();
  const Comparison c = Compare(scene, *design, 1'000'000, 2'000'000, 1'000'000, 10,
                               AutomaticWindowParts(scene.window));
  ExpectAgreement(c, "city office");
  // The street and the city reflect light from below the horizon into the window
  EXPECT_GT(c.coarse.coefficients.col(0).sum(), 0.0);
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

// The indoor stage does not depend on anything outdoors: enclosing the outside in a
// closed box changes O but not I (bitwise, same seed).
TEST(TwoStageTest, IndoorStageIgnoresOutdoorGeometry) {
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
  EXPECT_EQ(a->coefficients, b->coefficients);
  OutdoorOptions outdoor;
  outdoor.paths = 288 * 100;
  absl::StatusOr<OutdoorResult> open = ComputeOutdoorStage(scene, outdoor);
  absl::StatusOr<OutdoorResult> closed = ComputeOutdoorStage(enclosed, outdoor);
  ASSERT_TRUE(open.ok() && closed.ok());
  EXPECT_GT(open->coefficients.sum(), 0);
  EXPECT_EQ(closed->coefficients.sum(), 0);  // no sky is visible from the window
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
// same contributions, so I summed over the parts is I of the whole window.
TEST(TwoStageTest, IndoorPartsSumToTheWholeWindow) {
  const Scene scene = LoadExample("city_office");
  IndoorOptions whole;
  whole.paths_per_sensor = 20'000;
  IndoorOptions split = whole;
  split.parts = {3, 2};
  absl::StatusOr<IndoorResult> a = ComputeIndoorStage(scene, DefaultDesign(scene), whole);
  absl::StatusOr<IndoorResult> b = ComputeIndoorStage(scene, DefaultDesign(scene), split);
  ASSERT_TRUE(a.ok() && b.ok());
  ASSERT_EQ(b->coefficients.cols(), 6 * 288);
  Matrix summed = Matrix::Zero(a->coefficients.rows(), 288);
  for (int part = 0; part < 6; ++part) summed += b->coefficients.middleCols(part * 288, 288);
  EXPECT_LT((summed - a->coefficients).cwiseAbs().maxCoeff(),
            1e-12 * a->coefficients.cwiseAbs().maxCoeff());
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
  IndoorOptions indoor;
  indoor.batches = 1;
  EXPECT_EQ(ComputeIndoorStage(scene, DefaultDesign(scene), indoor).status().code(),
            absl::StatusCode::kInvalidArgument);
}

}  // namespace
}  // namespace fenestra
