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

}  // namespace
}  // namespace fenestra
