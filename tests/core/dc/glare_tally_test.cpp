// The glare counts of E's batches (glare_tally.h) on a case counted by hand: steps decided
// by Ev alone, steps with the sun's beam at the eye, unoccupied steps, and the jackknife
// versions that leave a batch out.
#include "core/dc/glare_tally.h"

#include <gtest/gtest.h>

#include <vector>

#include "core/metrics/glare.h"

namespace fenestra {
namespace {

// Two views, four steps (the last unoccupied), three batches; the eye limit of 0.4 is
// 4105.6 lx.
struct Case {
  std::vector<Matrix> batches;
  GlareSteps steps;
};

Case HandCase() {
  Case c;
  c.steps.threshold = 0.4;
  c.steps.occupied = {true, true, true, false};
  c.steps.sun_factor = Matrix::Zero(2, 4);
  c.steps.sun_factor(1, 2) = 1e4;  // the sun in front of view 1 at step 2
  // Per batch, view 0: step 0 at 5000 in every batch (glare in every version); step 1 at
  // 3000, 3000, 9000 (mean 5000: glare; without batch 2 it is 3000: none; without 0 or 1,
  // 6000: glare); step 3 bright but unoccupied. View 1: 1000 everywhere.
  for (const double third : {3000.0, 3000.0, 9000.0}) {
    Matrix e(2, 4);
    e << 5000, third, 100, 1e5,  //
        1000, 1000, 1000, 1e5;
    c.batches.push_back(e);
  }
  return c;
}

TEST(GlareTallyTest, CountsAreTheHandCountsPerVersion) {
  const Case c = HandCase();
  ASSERT_NEAR(EyeLuxAtDgp(0.4), 4105.6, 0.1);
  // The beam at view 1, step 2: 2000 lx through a factor of 1e4 is glare (DGP 0.71 at Ev
  // 3000), 20 lx is not (0.31 at Ev 1020)
  ASSERT_GT(DgpWithSunFactor(3000, 2000, 1e4), 0.4);
  ASSERT_LT(DgpWithSunFactor(1020, 20, 1e4), 0.4);
  for (const double beam : {2000.0, 20.0}) {
    const std::vector<SunEntry> sun = {{1, 2, beam}};
    absl::StatusOr<GlareCounts> counts = CountGlare(c.batches, sun, c.steps);
    ASSERT_TRUE(counts.ok()) << counts.status();
    ASSERT_EQ(counts->view_steps.size(), 4u);
    const int sunny = beam > 100 ? 1 : 0;
    // Version 0 and those without batch 0 or 1: view 0 at steps 0 and 1; without batch 2,
    // step 0 alone
    const std::vector<int64_t> view0 = {2, 2, 2, 1};
    for (size_t v = 0; v < 4; ++v) {
      EXPECT_EQ(counts->view_steps[v][0], view0[v]) << "version " << v;
      EXPECT_EQ(counts->view_steps[v][1], sunny) << "version " << v;
      EXPECT_EQ(counts->any_steps[v], view0[v] + sunny) << "version " << v;
    }
  }
}

TEST(GlareTallyTest, BadInputIsRefused) {
  const Case c = HandCase();
  EXPECT_EQ(CountGlare({c.batches[0]}, {}, c.steps).status().code(),
            absl::StatusCode::kInvalidArgument);
  const std::vector<SunEntry> outside = {{2, 0, 100.0}};
  EXPECT_EQ(CountGlare(c.batches, outside, c.steps).status().code(),
            absl::StatusCode::kInvalidArgument);
  GlareSteps wrong = c.steps;
  wrong.occupied.pop_back();
  EXPECT_EQ(CountGlare(c.batches, {}, wrong).status().code(), absl::StatusCode::kInvalidArgument);
  wrong = c.steps;
  wrong.threshold = 1.0;
  EXPECT_EQ(CountGlare(c.batches, {}, wrong).status().code(), absl::StatusCode::kInvalidArgument);
  std::vector<Matrix> uneven = c.batches;
  uneven[1] = Matrix::Zero(2, 3);
  EXPECT_EQ(CountGlare(uneven, {}, c.steps).status().code(), absl::StatusCode::kInvalidArgument);
}

}  // namespace
}  // namespace fenestra
