#include "client/report/report_data.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>

#include "client/report/html_report.h"
#include "tests/quick_job.h"

namespace fenestra {
namespace {

using ::testing::HasSubstr;
using ::testing::Not;

absl::Status Gather(const v1::JobResult& result, const std::string& sensor = "") {
  return GatherReportData(result, "r.json", sensor).status();
}

TEST(ReportDataTest, TheMapShowsTheWorstSensorUnlessAnotherIsNamed) {
  const v1::JobResult& result = QuickJobResult();
  absl::StatusOr<ReportData> data = GatherReportData(result, "r.json", "");
  ASSERT_TRUE(data.ok()) << data.status();
  int worst = 0;
  for (int i = 0; i < result.best_metrics().sensor_udi_size(); ++i) {
    if (result.best_metrics().sensor_udi(i).value() <
        result.best_metrics().sensor_udi(worst).value()) {
      worst = i;
    }
  }
  EXPECT_EQ(data->map_sensor, worst);
  EXPECT_EQ(GatherReportData(result, "r.json", "S3")->map_sensor, 2);
  EXPECT_EQ(GatherReportData(result, "r.json", "4")->map_sensor, 4);
  for (const std::string bad : {"S10", "9", "-1", "S"}) {
    const absl::Status status = Gather(result, bad);
    EXPECT_EQ(status.code(), absl::StatusCode::kInvalidArgument) << bad;
    EXPECT_THAT(status.message(), HasSubstr("--sensor: no sensor '" + bad + "'"));
    EXPECT_THAT(status.message(), HasSubstr("S1, S2, S3"));
  }
  // The search's series: cumulative time, the best's error after each evaluation
  ASSERT_EQ(data->search.size(), static_cast<size_t>(result.history_size()));
  double seconds = 0, best_error = 0;
  for (int i = 0; i < result.history_size(); ++i) {
    seconds += result.history(i).seconds();
    if (result.history(i).improved()) best_error = result.history(i).value().standard_error();
    EXPECT_DOUBLE_EQ(data->search[i].seconds, seconds);
    EXPECT_DOUBLE_EQ(data->best_error[i].standard_error, best_error);
  }
  EXPECT_EQ(data->metric_label, "UDI 100–3000 lx [%]");
  ASSERT_EQ(data->free_variables.size(), 1u);
  EXPECT_EQ(data->free_variables[0].name, "alpha");
  // The job's own record of its error against time and its final check
  ASSERT_TRUE(data->recorded_error.has_value());
  ASSERT_EQ(data->recorded_error->size(), static_cast<size_t>(result.best_over_time_size()));
  EXPECT_DOUBLE_EQ(data->recorded_error->back().standard_error,
                   result.best_over_time(result.best_over_time_size() - 1).value().standard_error());
  ASSERT_TRUE(data->final_check.has_value());
  EXPECT_EQ(data->final_check->size(), 6u);
}

TEST(ReportDataTest, InconsistentResultsAreRefusedNamingTheField) {
  const v1::JobResult& good = QuickJobResult();
  v1::JobResult r = good;
  r.mutable_best_hourly()->mutable_illuminance_lux()->RemoveLast();
  EXPECT_THAT(Gather(r).message(), HasSubstr("r.json: best_hourly: needs 78840 values"));
  r = good;
  r.mutable_best_hourly()->set_illuminance_lux(5, NAN);
  EXPECT_THAT(Gather(r).message(), HasSubstr("best_hourly.illuminance_lux"));
  r = good;
  r.mutable_best_hourly()->set_month(3, 13);
  EXPECT_THAT(Gather(r).message(), HasSubstr("best_hourly step 3"));
  r = good;
  r.mutable_history(1)->mutable_value()->set_standard_error(INFINITY);
  EXPECT_THAT(Gather(r).message(), HasSubstr("r.json: history[1]"));
  r = good;
  r.mutable_best_metrics()->mutable_sensor_udi()->RemoveLast();
  EXPECT_THAT(Gather(r).message(), HasSubstr("best_metrics"));
  r = good;
  (*r.mutable_best_design())["alpha"] = 7;
  EXPECT_THAT(Gather(r).message(), HasSubstr("best_design"));
  r = good;
  r.mutable_job()->mutable_scene()->mutable_window()->set_width_m(-1);
  EXPECT_THAT(Gather(r).message(), HasSubstr("window.width_m"));
}

// A result without its job or hourly illuminance still makes a page that says what is missing
TEST(ReportDataTest, WhatAResultLacksIsNotRecorded) {
  v1::JobResult r = QuickJobResult();
  r.clear_best_hourly();
  EXPECT_THAT(Gather(r, "S1").message(), HasSubstr("--sensor: the result holds no hourly"));
  absl::StatusOr<std::string> page = RenderReport(r, {"r.json", ""});
  ASSERT_TRUE(page.ok()) << page.status();
  EXPECT_THAT(*page, HasSubstr("Hourly illuminance: not recorded"));
  EXPECT_THAT(*page, HasSubstr("id=\"plot-floor-udi\""));
  r.clear_job();
  r.clear_versions();
  page = RenderReport(r, {"r.json", ""});
  ASSERT_TRUE(page.ok()) << page.status();
  EXPECT_THAT(*page, HasSubstr("The scene: not recorded"));
  EXPECT_THAT(*page, HasSubstr("Versions: not recorded"));
  EXPECT_THAT(*page, HasSubstr("id=\"plot-value-vs-evaluation\""));
  EXPECT_THAT(*page, Not(HasSubstr("id=\"plot-floor-udi\"")));
}

// Names from the job and the scene are text on the page, never markup
TEST(ReportDataTest, NamesAreEscaped) {
  v1::JobResult r = QuickJobResult();
  r.mutable_job()->set_name("<script>alert(1)</script>");
  r.mutable_job()->mutable_scene()->mutable_sensors(0)->set_name("S1 & <b>");
  absl::StatusOr<std::string> page = RenderReport(r, {"r.json", "S1 & <b>"});
  ASSERT_TRUE(page.ok()) << page.status();
  EXPECT_THAT(*page, Not(HasSubstr("<script>")));
  EXPECT_THAT(*page, Not(HasSubstr("<b>")));
  EXPECT_THAT(*page, HasSubstr("&lt;script&gt;alert(1)&lt;/script&gt;"));
  EXPECT_THAT(*page, HasSubstr("Illuminance at S1 &amp; &lt;b&gt;"));
}

}  // namespace
}  // namespace fenestra
