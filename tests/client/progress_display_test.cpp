// The result's summary as `fenestra` prints it.
#include "client/progress_display.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

namespace fenestra {
namespace {

using ::testing::HasSubstr;
using ::testing::Not;

// Each constraint of the objective at the best design, with whether it holds.
TEST(ProgressDisplayTest, ResultShowsEachConstraint) {
  v1::JobResult result;
  (*result.mutable_best_design())["alpha"] = 0.5;
  EXPECT_THAT(FormatResult(result), Not(HasSubstr("at most")));
  v1::ConstraintResult& ase = *result.add_best_constraints();
  ase.mutable_constraint()->set_metric(v1::METRIC_ASE);
  ase.mutable_constraint()->set_bound(v1::Constraint::AT_MOST);
  ase.mutable_constraint()->set_value(10);
  ase.mutable_estimate()->set_value(4);
  ase.set_holds(true);
  v1::ConstraintResult& sda = *result.add_best_constraints();
  sda.mutable_constraint()->set_metric(v1::METRIC_SDA);
  sda.mutable_constraint()->set_bound(v1::Constraint::AT_LEAST);
  sda.mutable_constraint()->set_value(55);
  sda.mutable_estimate()->set_value(50.04);
  sda.mutable_estimate()->set_standard_error(2.46);
  const std::string text = FormatResult(result);
  EXPECT_THAT(text, HasSubstr("\nASE at most 10%: 4.0 +- 0.0 holds\n"));
  EXPECT_THAT(text, HasSubstr("\nsDA at least 55%: 50.0 +- 2.5 broken\n"));
}

// ASE with its thresholds and the LEED points; the hours with the blind in place only for a
// blind that is not always there.
TEST(ProgressDisplayTest, ResultShowsAseAndTheBlindsHours) {
  v1::JobResult result;
  EXPECT_THAT(FormatResult(result), Not(HasSubstr("ASE")));
  result.mutable_job()->mutable_metrics()->set_ase_threshold_lux(1000);
  result.mutable_job()->mutable_metrics()->set_ase_min_hours(250);
  v1::Metrics& m = *result.mutable_best_metrics();
  m.mutable_ase()->set_value(40);
  m.set_leed_points(3);
  m.mutable_blind_in_place()->set_value(100);
  EXPECT_THAT(FormatResult(result),
              HasSubstr("\nASE1000,250 40.00 ± 0.00 % of the sensors (LEED v4.1 daylight option 1: "
                        "3 points)\n"));
  m.mutable_blind_in_place()->set_value(39.23);
  EXPECT_THAT(FormatResult(result),
              HasSubstr("points), blind in place 39.23 ± 0.00 % of the hours\n"));
}

// The best finish by its materials' names, after the design's values.
TEST(ProgressDisplayTest, ResultNamesTheBestFinish) {
  v1::JobResult result;
  (*result.mutable_best_design())["alpha"] = 0.5;
  EXPECT_THAT(FormatResult(result), Not(HasSubstr("finish")));
  v1::DesignVariable& finish = *result.mutable_job()->add_variables();
  finish.set_name("finish");
  finish.add_finishes()->set_material("aluminium");
  v1::BlindFinish& two = *finish.add_finishes();
  two.set_material("white");
  two.set_outer_material("aluminium");
  (*result.mutable_best_design())["finish"] = 1;
  EXPECT_THAT(FormatResult(result),
              HasSubstr("best design: alpha=0.5 finish=1\nfinish: white / aluminium outer\n"));
  (*result.mutable_best_design())["finish"] = 0;
  EXPECT_THAT(FormatResult(result), HasSubstr("\nfinish: aluminium\n"));
}

}  // namespace
}  // namespace fenestra
