#include "core/metrics/glare.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <vector>

namespace fenestra {
namespace {

// DGPs by hand: 6.22e-5 Ev + 0.184.
TEST(GlareTest, SimplifiedDgpIsTheLinearFormOfEv) {
  EXPECT_DOUBLE_EQ(SimplifiedDgp(0), 0.184);
  EXPECT_DOUBLE_EQ(SimplifiedDgp(2000), 0.3084);
  EXPECT_DOUBLE_EQ(SimplifiedDgp(5000), 0.495);
  // The Ev at the 0.40 threshold: (0.40 - 0.184) / 6.22e-5 = 3472.67 lx
  EXPECT_NEAR(SimplifiedDgp(3472.668810289389), 0.40, 1e-12);
}

// The position index by hand from Guth's formula (above the line of sight) and Iwata's
// (below), for an eye looking north with +z up.
TEST(GlareTest, PositionIndexAboveAndBelowTheLineOfSight) {
  const Vec3d north{0, 1, 0}, up{0, 0, 1};
  const double s30 = 0.5, c30 = std::sqrt(3.0) / 2;
  EXPECT_NEAR(PositionIndex(north, up, north), 1.0, 1e-12);
  // 30 degrees straight above (tau 0): exp((35.2 - 1.22) 1e-3 30 + 21e-5 30^2)
  EXPECT_NEAR(PositionIndex(north, up, {0, c30, s30}), std::exp(33.98e-3 * 30 + 21e-5 * 900), 1e-9);
  // 30 degrees to the side (tau 90): exp((35.2 - 28.7001 - 1.22 e^-20) 1e-3 30 +
  // (21 + 24.0003 - 24.0003) 1e-5 900)
  EXPECT_NEAR(PositionIndex(north, up, {s30, c30, 0}),
              std::exp((35.2 - 0.31889 * 90 - 1.22 * std::exp(-20.0)) * 30e-3 +
                       (21 + 0.26667 * 90 - 0.002963 * 8100) * 900e-5),
              1e-9);
  // 30 degrees below (tau 180, Iwata): beta = atan(tan 30 sqrt(1.3225)) = 33.58 degrees
  const double beta =
      std::atan(std::tan(std::numbers::pi / 6) * std::sqrt(1.3225)) * 180 / std::numbers::pi;
  EXPECT_NEAR(beta, 33.58, 0.01);
  EXPECT_NEAR(PositionIndex(north, up, {0, c30, -s30}),
              std::exp(6.49e-3 * beta + 21e-5 * beta * beta), 1e-9);
  // Far off the line of sight the index stops at 16
  EXPECT_EQ(PositionIndex(north, up, {0.9, 0.1, 0.4}), 16.0);
}

// The DGP by hand: Ev alone, then the sun in view 30 degrees above the line of sight (position
// index 3.348), its beam through a blind of 2000 lx normal illuminance giving the eye plane
// 2000 cos 30 lx of Ev = 4000 lx: L = 2000 / 6.805e-5 = 2.94e7 cd/m2, L^2 w / P^2 / Ev^1.87 =
// 963.3, DGP = 0.2348 + 0.092 log10(964.3) + 0.159 = 0.6683.
TEST(GlareTest, DgpWithTheSunAsGlareSource) {
  EXPECT_DOUBLE_EQ(Dgp(2000, {}), 5.87e-5 * 2000 + 0.159);
  const double c30 = std::sqrt(3.0) / 2;
  const Vec3d north{0, 1, 0}, up{0, 0, 1}, sun{0, c30, 0.5};
  EXPECT_NEAR(DgpWithSun(4000, 2000 * c30, north, up, sun), 0.66835, 1e-5);
  // At 3000 lx of Ev the same sun: far above 0.45
  EXPECT_GT(DgpWithSun(3000, 3000 * c30, north, up, sun), 0.45);
  // No beam, or the sun behind the eye: Ev alone
  EXPECT_DOUBLE_EQ(DgpWithSun(3000, 0, north, up, sun), Dgp(3000, {}));
  EXPECT_DOUBLE_EQ(DgpWithSun(3000, 100, north, up, {0, -1, 0}), Dgp(3000, {}));
  // A dark eye with the sun's beam stays finite
  EXPECT_TRUE(std::isfinite(DgpWithSun(0, 0, north, up, sun)));
  // The DGP stops at 1
  EXPECT_EQ(DgpWithSun(1e5, 9e4, north, up, sun), 1.0);
}

TEST(GlareTest, ComfortClassesChangeAtTheirLimits) {
  EXPECT_EQ(ClassOfDgp(0.3499), GlareClass::kImperceptible);
  EXPECT_EQ(ClassOfDgp(0.35), GlareClass::kPerceptible);
  EXPECT_EQ(ClassOfDgp(0.40), GlareClass::kDisturbing);
  EXPECT_EQ(ClassOfDgp(0.45), GlareClass::kIntolerable);
  EXPECT_EQ(GlareClassName(GlareClass::kDisturbing), "disturbing");
}

// 100 occupied hours at the DGPs of 1000, 3000 and 6000 lx (0.2462, 0.3706, 0.5572), 20
// unoccupied ones at 10000 lx's that count for nothing.
struct Hours {
  std::vector<double> dgp;
  std::vector<bool> occupied;
  void Add(int n, double lux, bool occupied_hour) {
    dgp.insert(dgp.end(), n, std::min(1.0, SimplifiedDgp(lux)));
    occupied.insert(occupied.end(), n, occupied_hour);
  }
};

TEST(GlareTest, AutonomyClassesAndEn17037OfAConstructedYear) {
  Hours h;
  h.Add(90, 1000, true);
  h.Add(6, 3000, true);
  h.Add(20, 10000, false);
  h.Add(4, 6000, true);
  absl::StatusOr<ViewGlare> g = GlareOfView(h.dgp, h.occupied);
  ASSERT_TRUE(g.ok()) << g.status();
  EXPECT_EQ(g->occupied_hours, 100);
  EXPECT_DOUBLE_EQ(g->autonomy_percent, 96.0);
  EXPECT_EQ(g->class_hours, (std::array<int, 4>{90, 6, 0, 4}));
  EXPECT_NEAR(g->mean_dgp, (90 * 0.2462 + 6 * 0.3706 + 4 * 0.5572) / 100, 1e-12);
  // 5 of the 100 hours may exceed the class limit: the 4 brightest do, the 96th is 0.3706
  EXPECT_NEAR(g->dgp_95, 0.3706, 1e-12);
  EXPECT_EQ(g->en17037, En17037Glare::kMedium);
  EXPECT_EQ(g->sunlit_hours, 0);

  // Two more bright hours in place of dim ones: 6 exceed, more than 5% of the hours
  Hours more;
  more.Add(88, 1000, true);
  more.Add(6, 3000, true);
  more.Add(6, 6000, true);
  g = GlareOfView(more.dgp, more.occupied, 0.45);
  ASSERT_TRUE(g.ok()) << g.status();
  EXPECT_NEAR(g->dgp_95, 0.5572, 1e-12);
  EXPECT_EQ(g->en17037, En17037Glare::kNone);
  EXPECT_DOUBLE_EQ(g->autonomy_percent, 94.0);  // threshold 0.45
}

TEST(GlareTest, SunlitHoursAreTheOccupiedOnesTheBeamReaches) {
  const std::vector<double> dgp = {0.2, 1.0, 1.0, 0.19};
  const std::vector<bool> occupied = {true, true, false, true};
  const std::vector<bool> sun = {false, true, true, false};
  absl::StatusOr<ViewGlare> g = GlareOfView(dgp, occupied, kDefaultGlareThreshold, sun);
  ASSERT_TRUE(g.ok()) << g.status();
  EXPECT_EQ(g->sunlit_hours, 1);
  EXPECT_EQ(g->occupied_hours, 3);
}

TEST(GlareTest, BadInputIsRefusedAndNoOccupiedHourGivesZeros) {
  const std::vector<double> dgp = {0.2, 0.3};
  EXPECT_FALSE(GlareOfView(dgp, {true}).ok());
  EXPECT_FALSE(GlareOfView(dgp, {true, true}, 1.5).ok());
  EXPECT_FALSE(GlareOfView(std::vector<double>{-0.1, 0}, {true, true}).ok());
  EXPECT_FALSE(GlareOfView(std::vector<double>{1.2, 0}, {true, true}).ok());
  EXPECT_FALSE(GlareOfView(std::vector<double>{NAN, 0}, {true, true}).ok());
  EXPECT_FALSE(GlareOfView(dgp, {true, true}, 0.4, {true}).ok());
  absl::StatusOr<ViewGlare> none = GlareOfView(dgp, {false, false});
  ASSERT_TRUE(none.ok());
  EXPECT_EQ(none->occupied_hours, 0);
  EXPECT_EQ(none->autonomy_percent, 0);
}

}  // namespace
}  // namespace fenestra
