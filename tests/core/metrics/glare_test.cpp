#include "core/metrics/glare.h"

#include <gtest/gtest.h>

#include <cmath>
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

TEST(GlareTest, ComfortClassesChangeAtTheirLimits) {
  EXPECT_EQ(ClassOfDgp(0.3499), GlareClass::kImperceptible);
  EXPECT_EQ(ClassOfDgp(0.35), GlareClass::kPerceptible);
  EXPECT_EQ(ClassOfDgp(0.40), GlareClass::kDisturbing);
  EXPECT_EQ(ClassOfDgp(0.45), GlareClass::kIntolerable);
  EXPECT_EQ(GlareClassName(GlareClass::kDisturbing), "disturbing");
}

// 100 occupied hours at 1000, 3000 and 6000 lx (DGPs 0.2462, 0.3706, 0.5572), 20 unoccupied
// ones at 10000 lx that count for nothing.
struct Hours {
  std::vector<double> eye;
  std::vector<bool> occupied;
  void Add(int n, double lux, bool occupied_hour) {
    eye.insert(eye.end(), n, lux);
    occupied.insert(occupied.end(), n, occupied_hour);
  }
};

TEST(GlareTest, AutonomyClassesAndEn17037OfAConstructedYear) {
  Hours h;
  h.Add(90, 1000, true);
  h.Add(6, 3000, true);
  h.Add(20, 10000, false);
  h.Add(4, 6000, true);
  absl::StatusOr<ViewGlare> g = GlareOfView(h.eye, h.occupied);
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
  g = GlareOfView(more.eye, more.occupied, 0.45);
  ASSERT_TRUE(g.ok()) << g.status();
  EXPECT_NEAR(g->dgp_95, 0.5572, 1e-12);
  EXPECT_EQ(g->en17037, En17037Glare::kNone);
  EXPECT_DOUBLE_EQ(g->autonomy_percent, 94.0);  // threshold 0.45
}

TEST(GlareTest, SunlitHoursAreTheOccupiedOnesTheBeamReaches) {
  const std::vector<double> eye = {500, 8000, 8000, 200};
  const std::vector<bool> occupied = {true, true, false, true};
  const std::vector<double> sun = {0, 4000, 4000, 0};
  absl::StatusOr<ViewGlare> g = GlareOfView(eye, occupied, kDefaultGlareThreshold, sun);
  ASSERT_TRUE(g.ok()) << g.status();
  EXPECT_EQ(g->sunlit_hours, 1);
  EXPECT_EQ(g->occupied_hours, 3);
}

TEST(GlareTest, BadInputIsRefusedAndNoOccupiedHourGivesZeros) {
  const std::vector<double> eye = {500, 800};
  EXPECT_FALSE(GlareOfView(eye, {true}).ok());
  EXPECT_FALSE(GlareOfView(eye, {true, true}, 1.5).ok());
  EXPECT_FALSE(GlareOfView(std::vector<double>{-1, 0}, {true, true}).ok());
  EXPECT_FALSE(GlareOfView(std::vector<double>{NAN, 0}, {true, true}).ok());
  const std::vector<double> sun = {0};
  EXPECT_FALSE(GlareOfView(eye, {true, true}, 0.4, sun).ok());
  absl::StatusOr<ViewGlare> none = GlareOfView(eye, {false, false});
  ASSERT_TRUE(none.ok());
  EXPECT_EQ(none->occupied_hours, 0);
  EXPECT_EQ(none->autonomy_percent, 0);
}

}  // namespace
}  // namespace fenestra
