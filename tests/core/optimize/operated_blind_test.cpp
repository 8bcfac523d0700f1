#include "core/optimize/operated_blind.h"

#include <gtest/gtest.h>

#include <vector>

#include "core/metrics/annual_metrics.h"
#include "core/metrics/metric_errors.h"
#include "core/optimize/job.h"

namespace fenestra {
namespace {

// 50 sensors x 4 hours of bare-window direct sun: hour 0 none, hour 1 one sensor above 1000 lx
// (2%: not more than 2%), hour 2 two sensors (4%), hour 3 one sensor at exactly 1000 lx and
// two at 999 (none above).
Matrix BareDirect() {
  Matrix e = Matrix::Zero(50, 4);
  e(7, 1) = 5000;
  e(3, 2) = 1200, e(40, 2) = 30000;
  e(0, 3) = 1000, e(1, 3) = 999, e(2, 3) = 999;
  return e;
}

// IES LM-83's rule, counted by hand: the blind is in place where more than 2% of the sensors
// get more than 1000 lx of direct sun through the bare window.
TEST(OperatedBlindTest, TheRuleClosesTheHoursWithMoreThanTwoPercentSunlit) {
  const MetricOptions options;
  EXPECT_EQ(BlindInPlace(BareDirect(), options), (std::vector<bool>{false, false, true, false}));
  MetricOptions stricter = options;
  stricter.operation_sensor_percent = 1;  // then one sensor of 50 (2%) is enough
  EXPECT_EQ(BlindInPlace(BareDirect(), stricter), (std::vector<bool>{false, true, true, false}));
  stricter.operation_threshold_lux = 998;  // and the 999 lx sensors count
  EXPECT_EQ(BlindInPlace(BareDirect(), stricter), (std::vector<bool>{false, true, true, true}));
}

// ASE by hand: 3 sensors, 300 analysed hours of which the direct sun exceeds 1000 lx at sensor 0
// in 260, at sensor 1 in 249 and at sensor 2 in none: one sensor of three reaches 250 hours.
TEST(OperatedBlindTest, AseCountsTheSensorsWithTheirSunlitHours) {
  Matrix direct = Matrix::Zero(3, 300);
  direct.row(0).head(260).setConstant(1500);
  direct.row(1).head(249).setConstant(80000);
  direct(1, 299) = 1000;  // not above
  const MetricOptions options;
  EXPECT_EQ(SunlitHours(direct, options), (std::vector<int64_t>{260, 249, 0}));
  HourTally tally = TallyHours(Matrix::Constant(3, 300, 500), options);
  tally.sunlit = SunlitHours(direct, options);
  const AnnualMetrics m = MetricsFromTally(tally, 300, options);
  ASSERT_TRUE(m.has_ase);
  EXPECT_NEAR(m.scene.ase_percent, 100.0 / 3, 1e-12);
  EXPECT_EQ(m.sensors[0].ase_hours, 260);
  MetricOptions fewer = options;
  fewer.ase_min_hours = 249;
  EXPECT_NEAR(MetricsFromTally(tally, 300, fewer).scene.ase_percent, 200.0 / 3, 1e-12);
}

// Operated sDA by hand: 2 sensors, 10 analysed hours. The blind is in place in hours 0-3, where
// the design gives 200 lx at both sensors; in the other 6 hours the bare window gives sensor 0
// 400 lx and sensor 1 100 lx. DA300: sensor 0 in 6 of 10 hours (60%), sensor 1 in none; sDA
// (DA >= 50%) 50%; the blind in place 40% of the hours. The tallies of the closed hours plus
// those of the open ones equal the tally of the mixed illuminance.
TEST(OperatedBlindTest, OperatedSdaAddsTheBareWindowsOpenHours) {
  const MetricOptions options;
  const Matrix closed = Matrix::Constant(2, 4, 200);
  Matrix open(2, 6);
  open.row(0).setConstant(400);
  open.row(1).setConstant(100);
  BlindOperation op;
  op.closed = {0, 1, 2, 3};
  op.bare_sunlit = {0, 0};
  op.open.assign(3, TallyHours(open, options));  // the mean and two leave-one-out versions
  const std::vector<HourTally> design(3, TallyHours(closed, options));
  absl::StatusOr<std::vector<HourTally>> year = WithOpenHours(design, op);
  ASSERT_TRUE(year.ok()) << year.status();
  Matrix mixed(2, 10);
  mixed << closed, open;
  const HourTally expected = TallyHours(mixed, options);
  const HourTally& got = (*year)[0];
  EXPECT_EQ(got.hours, expected.hours);
  EXPECT_EQ(got.all_in, expected.all_in);
  EXPECT_EQ(got.any_below, expected.any_below);
  for (int i = 0; i < 2; ++i) {
    EXPECT_EQ(got.sensors[i].da, expected.sensors[i].da);
    EXPECT_DOUBLE_EQ(got.sensors[i].sum, expected.sensors[i].sum);
  }
  absl::StatusOr<AnnualMetricsEstimate> metrics = AnnualMetricsFromTallies(*year, 10, options);
  ASSERT_TRUE(metrics.ok()) << metrics.status();
  EXPECT_DOUBLE_EQ(metrics->value.sensors[0].da_percent, 60);
  EXPECT_DOUBLE_EQ(metrics->value.sensors[1].da_percent, 0);
  EXPECT_DOUBLE_EQ(metrics->value.scene.sda_percent, 50);
  EXPECT_DOUBLE_EQ(metrics->value.scene.blind_in_place_percent, 40);
  EXPECT_DOUBLE_EQ(metrics->value.scene.ase_percent, 0);
  // Versions that do not pair are refused
  EXPECT_FALSE(WithOpenHours(std::vector<HourTally>(2, design[0]), op).ok());
}

}  // namespace
}  // namespace fenestra

namespace fenestra {
namespace {

// The sunny office with its blind operated by LM-83's rule, two designs of its quick job: the
// share of occupied hours with the blind in place is that of the steps the hourly output marks,
// exact; ASE is exact; the final check agrees with the two-stage value and counts the same
// hours in place and the same ASE.
TEST(OperatedBlindJobTest, TheBlindIsInPlaceInTheRulesHoursOnly) {
  absl::StatusOr<v1::Job> job =
      ReadJobFile(FENESTRA_SOURCE_DIR "/examples/sunny_office/leed_quick.json");
  ASSERT_TRUE(job.ok()) << job.status();
  job->mutable_budget()->set_max_evaluations(2);
  job->mutable_sampling()->set_backend("cpu");
  absl::StatusOr<PreparedJob> prepared =
      PrepareJob(*job, FENESTRA_SOURCE_DIR "/examples/sunny_office");
  ASSERT_TRUE(prepared.ok()) << prepared.status();
  absl::StatusOr<v1::JobResult> result = RunJob(*prepared, nullptr);
  ASSERT_TRUE(result.ok()) << result.status();
  const v1::Metrics& m = result->best_metrics();
  // Phoenix's sun closes the blind in a good share of the occupied hours, not all
  EXPECT_GT(m.blind_in_place().value(), 20);
  EXPECT_LT(m.blind_in_place().value(), 80);
  EXPECT_EQ(m.blind_in_place().standard_error(), 0);
  EXPECT_EQ(m.ase().standard_error(), 0);
  // Per step: the hours in place are those the occupied share counts
  const v1::HourlyIlluminance& h = result->best_hourly();
  ASSERT_EQ(h.blind_in_place_size(), h.hour_size());
  int occupied = 0, in_place = 0;
  for (int t = 0; t < h.hour_size(); ++t) {
    const bool counted = h.hour(t) >= 8 && h.hour(t) < 18;
    occupied += counted;
    in_place += counted && h.blind_in_place(t);
  }
  EXPECT_NEAR(m.blind_in_place().value(), 100.0 * in_place / occupied, 1e-9);
  // The one-stage check counts the same hours in place and the same (bare window's) ASE
  ASSERT_TRUE(result->has_final_check());
  EXPECT_FALSE(result->final_check().disagrees())
      << result->final_check().one_stage().value() << " against " << result->best_value().value();
  EXPECT_EQ(result->final_check().one_stage_metrics().blind_in_place().value(),
            m.blind_in_place().value());
  EXPECT_EQ(result->final_check().one_stage_metrics().ase().value(), m.ase().value());
}

}  // namespace
}  // namespace fenestra
