#include "client/report/report_data.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>

#include "client/report/html_report.h"
#include "client/report/sections.h"
#include "tests/client/report/direct_sun_result.h"
#include "tests/quick_job.h"

namespace fenestra {
namespace {

using ::testing::HasSubstr;
using ::testing::Not;

absl::Status Gather(const v1::JobResult& result, const std::string& sensor = "") {
  return GatherReportData(result, "r.json", sensor).status();
}

// The page of `result`; empty when it fails.
std::string Page(const v1::JobResult& result) {
  absl::StatusOr<std::string> page = RenderReport(result, {"r.json", ""});
  EXPECT_TRUE(page.ok()) << page.status();
  return page.value_or("");
}

// The markup of the figure with element id `id`; empty when there is none.
std::string Figure(const std::string& page, const std::string& id) {
  const size_t start = page.find("id=\"" + id + "\"");
  if (start == std::string::npos) return "";
  return page.substr(start, page.find("</svg>", start) - start);
}

// How often `what` occurs in `text`.
int Count(const std::string& text, const std::string& what) {
  int n = 0;
  for (size_t at = text.find(what); at != std::string::npos; at = text.find(what, at + 1)) ++n;
  return n;
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
  EXPECT_DOUBLE_EQ(
      data->recorded_error->back().standard_error,
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
  // The direct-sun fields
  const v1::JobResult sunny = WithDirectSun(good);
  ASSERT_TRUE(Gather(sunny).ok()) << Gather(sunny);
  r = sunny;
  r.mutable_best_hourly()->mutable_direct_sun_lux()->RemoveLast();
  EXPECT_THAT(Gather(r).message(), HasSubstr("best_hourly: direct_sun_lux needs 78840 values"));
  r = sunny;
  r.mutable_best_hourly()->mutable_blind_in_place()->RemoveLast();
  EXPECT_THAT(Gather(r).message(), HasSubstr("blind_in_place 8760, has 78840 and 8759"));
  r = sunny;
  r.mutable_best_hourly()->set_direct_sun_lux(7, -1);
  EXPECT_THAT(Gather(r).message(), HasSubstr("best_hourly.direct_sun_lux: values must be finite"));
  r = sunny;
  r.mutable_best_metrics()->add_sensor_sunlit_hours(3);
  EXPECT_THAT(Gather(r).message(), HasSubstr("best_metrics.sensor_sunlit_hours: holds 10 sensors"));
  r = sunny;
  r.mutable_best_metrics()->set_sensor_sunlit_hours(0, -4);
  EXPECT_THAT(Gather(r).message(), HasSubstr("best_metrics.sensor_sunlit_hours: must be >= 0"));
}

// ASE, LEED, the blind's hours, the constraints, the sunlit hours and the direct sun's map
TEST(ReportDataTest, TheDirectSunAndTheOperatedBlindAreShown) {
  const std::string page = Page(WithDirectSun(QuickJobResult()));
  EXPECT_THAT(page, HasSubstr("<tr><td>ASE1000,250 (% of sensors; direct sun, exact)</td>"
                              "<td class=\"num\">22.22 ± 0.00</td></tr>"));
  EXPECT_THAT(page, HasSubstr("<tr><td>blind in place (% of analysed hours)</td>"
                              "<td class=\"num\">9.86 ± 0.00</td></tr>"));
  EXPECT_THAT(page, HasSubstr(">LEED v4.1 daylight option 1: 1 point; ASE at most 10%: no</p>"));
  // The constraint, worked out from the metrics: the result has no best_constraints
  EXPECT_THAT(page, HasSubstr("<tr><td>ASE1000,250</td><td>at most</td><td class=\"num\">10</td>"
                              "<td class=\"num\">22.22 ± 0.00</td><td>no</td></tr>"));
  EXPECT_THAT(page, HasSubstr("The best design breaks its constraint."));
  EXPECT_THAT(page, HasSubstr("in place in the hours in which more than 2 % of the sensors get "
                              "more than 1000 lx of direct sun through the bare window"));

  // Each sensor's sunlit hours, the two ASE counts squared
  const std::string sunlit = Figure(page, "plot-floor-sunlit");
  ASSERT_FALSE(sunlit.empty());
  for (const char* label : {">400 h<", ">260 h<", ">249 h<", ">10 h<"}) {
    EXPECT_THAT(sunlit, HasSubstr(label));
  }
  EXPECT_EQ(Count(sunlit, "class=\"marked-sensor\""), 2);
  EXPECT_EQ(Count(Figure(page, "plot-floor-udi"), "class=\"marked-sensor\""), 0);
  EXPECT_THAT(page, HasSubstr("the squares mark the 2 sensors with at least 250 h"));
  EXPECT_THAT(page, HasSubstr("<th>sunlit hours (&gt; 1000 lx direct)</th>"));
  EXPECT_THAT(page, HasSubstr("<td class=\"num\">249</td></tr>"));

  // The most sunlit sensors get 1500 lx: above the threshold, no lesser band
  const std::string sun = Figure(page, "plot-direct-sun-map");
  ASSERT_FALSE(sun.empty());
  EXPECT_THAT(sun, HasSubstr("class=\"map-cell\" fill=\"#800026\""));
  EXPECT_THAT(sun, HasSubstr("class=\"map-cell\" fill=\"#eeeeee\""));
  for (const char* band : {"#fed976", "#fd8d3c", "#e31a1c"}) {
    EXPECT_EQ(Count(sun, std::string("class=\"map-cell\" fill=\"") + band), 0) << band;
  }
  EXPECT_THAT(page, HasSubstr("In 360 of the 3650 analysed hours a sensor gets more than 1000 lx"));
  const std::string blind = Figure(page, "plot-blind-map");
  ASSERT_FALSE(blind.empty());
  EXPECT_THAT(blind, HasSubstr("fill=\"#6e6e6e\""));
  EXPECT_THAT(page, HasSubstr("in 360 of the 3650 analysed hours (9.9 %), 360 hours of the year"));
}

// The result's own verdict on each constraint is shown as it is; without one, the page works
// it out within constraint_standard_errors of the metric's standard error
TEST(ReportDataTest, ConstraintsHoldWithinTheirStandardErrors) {
  v1::JobResult r = WithDirectSun(QuickJobResult());
  const v1::Estimate udi = r.best_metrics().udi();
  ASSERT_GT(udi.standard_error(), 0);
  v1::Constraint& at_least = *r.mutable_job()->mutable_objective()->add_constraints();
  at_least.set_metric(v1::METRIC_UDI);
  at_least.set_bound(v1::Constraint::AT_LEAST);
  at_least.set_value(udi.value() + 0.5 * udi.standard_error());
  const std::string udi_row =
      "<td class=\"num\">" + WithError(udi.value(), udi.standard_error()) + "</td><td>";
  EXPECT_THAT(Page(r), HasSubstr(udi_row + "yes</td></tr>"));
  r.mutable_job()->mutable_objective()->set_constraint_standard_errors(0.25);
  EXPECT_THAT(Page(r), HasSubstr(udi_row + "no</td></tr>"));
  EXPECT_THAT(Page(r), HasSubstr("The best design breaks 2 of the 2 constraints. A constraint "
                                 "holds unless its metric is beyond the bound by more than 0.25 "
                                 "of its standard errors."));

  // best_constraints, as the job decided them
  v1::ConstraintResult& c = *r.add_best_constraints();
  *c.mutable_constraint() = r.job().objective().constraints(0);
  c.mutable_estimate()->set_value(7.5);
  c.set_holds(true);
  const std::string page = Page(r);
  EXPECT_THAT(page, HasSubstr("<tr><td>ASE1000,250</td><td>at most</td><td class=\"num\">10</td>"
                              "<td class=\"num\">7.50 ± 0.00</td><td>yes</td></tr>"));
  EXPECT_THAT(page, HasSubstr("The best design keeps its constraint."));
  EXPECT_EQ(Count(page, "<td>at least</td>"), 0);
}

// The glare at the view points, where the result holds it, is a table of its own, the view's
// name escaped; a result without views has none.
TEST(ReportDataTest, TheGlareAtTheViewPointsIsATable) {
  v1::JobResult r = QuickJobResult();
  EXPECT_THAT(Page(r), Not(HasSubstr("glare-table")));
  v1::ViewGlare& g = *r.add_best_glare();
  g.set_view("desk <1>");
  g.mutable_autonomy()->set_value(93.25);
  g.mutable_autonomy()->set_standard_error(1.5);
  g.mutable_mean_dgp()->set_value(0.3125);
  g.mutable_mean_dgp()->set_standard_error(0.004);
  g.set_dgp_95(0.4125);
  g.set_en17037("minimum");
  for (const int hours : {3000, 400, 200, 50}) g.add_class_hours(hours);
  g.set_sunlit_hours(12);
  g.set_analysed_hours(3650);
  const std::string page = Page(r);
  EXPECT_THAT(page, HasSubstr("<tr><td>desk &lt;1&gt;</td><td class=\"num\">93.25 ± 1.50</td>"
                              "<td class=\"num\">0.312 ± 0.004</td><td>minimum (0.412)</td>"
                              "<td class=\"num\">3000 / 400 / 200 / 50</td>"
                              "<td class=\"num\">12</td></tr>"));
}

// A Pareto search's front is a figure (one diamond per member, every evaluated design a
// point), a hypervolume line and a table; a result without one has no such section.
TEST(ReportDataTest, TheParetoFrontIsDrawnWithItsMembers) {
  v1::JobResult r = QuickJobResult();
  EXPECT_THAT(Page(r), Not(HasSubstr("id=\"pareto\"")));
  v1::Job& job = *r.mutable_job();
  v1::Objective& sda = *job.mutable_pareto()->add_objectives();
  sda.set_metric(v1::METRIC_SDA);
  sda.set_goal(v1::GOAL_MAXIMIZE);
  v1::Objective& glare = *job.mutable_pareto()->add_objectives();
  glare.set_metric(v1::METRIC_GLARE_HOURS);
  glare.set_goal(v1::GOAL_MINIMIZE);
  job.mutable_pareto()->set_population(4);
  job.mutable_pareto()->set_dominance_standard_errors(1);
  for (int s = 0; s < r.history_size(); ++s) {
    v1::Evaluation& e = *r.mutable_history(s);
    for (const double v : {50.0 + 10 * s, 5.0 * s}) {
      v1::Estimate& o = *e.add_objectives();
      o.set_value(v);
      o.set_standard_error(0.5);
    }
  }
  v1::ParetoResult& p = *r.mutable_pareto();
  for (const int s : {3, 2, 1}) {
    v1::FrontMember& m = *p.add_front();
    m.set_evaluation(s);
    *m.mutable_objectives() = r.history(s).objectives();
    (*m.mutable_design())["alpha"] = 0.1 * s;
  }
  for (const double h : {10.0, 12.0, 12.5}) p.add_hypervolume(h);
  p.set_generations(3);
  const std::string page = Page(r);
  EXPECT_THAT(page, HasSubstr("id=\"pareto\""));
  EXPECT_EQ(Count(page, "front-member"), 3);
  EXPECT_THAT(page, HasSubstr("plot-hypervolume"));
  EXPECT_THAT(page, HasSubstr("glare hours [%] (lower is better)"));
  EXPECT_THAT(page, HasSubstr("<td class=\"num\">80.00 ± 0.50</td>"));
}

// A result from before the direct-sun fields renders without their sections
TEST(ReportDataTest, AResultWithoutTheDirectSunLeavesItsSectionsOut) {
  const v1::JobResult old = WithoutDirectSun(QuickJobResult());
  const std::string page = Page(old);
  ASSERT_THAT(page, HasSubstr("id=\"plot-temporal-map\""));
  ASSERT_THAT(page, HasSubstr("id=\"plot-floor-udi\""));
  for (const char* absent : {"ASE", "LEED", "blind in place", "constraints-table", "sunlit",
                             "plot-direct-sun-map", "plot-blind-map", "marked-sensor\""}) {
    EXPECT_THAT(page, Not(HasSubstr(absent))) << absent;
  }
  // A static blind, in place in every hour: no map of it, nor its share of the hours
  v1::JobResult r = WithDirectSun(QuickJobResult());
  r.mutable_job()->mutable_scene()->mutable_blind()->set_operation(v1::VenetianBlind::STATIC);
  r.mutable_best_metrics()->mutable_blind_in_place()->set_value(100);
  for (int j = 0; j < r.best_hourly().blind_in_place_size(); ++j) {
    r.mutable_best_hourly()->set_blind_in_place(j, true);
  }
  const std::string static_page = Page(r);
  EXPECT_THAT(static_page, HasSubstr("id=\"plot-direct-sun-map\""));
  EXPECT_THAT(static_page, Not(HasSubstr("plot-blind-map")));
  EXPECT_THAT(static_page, Not(HasSubstr("blind in place (% of analysed hours)")));
  EXPECT_THAT(static_page, Not(HasSubstr("with the window bare")));
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

// The best finish by its materials' names in the page's lead and design table, and its slats'
// materials in the blind's table; the finish among the free variables the value is plotted
// against.
TEST(ReportDataTest, TheBestFinishIsNamed) {
  const v1::JobResult& result = QuickFinishJobResult();
  ASSERT_EQ(result.best_design().at("finish"), 1);
  absl::StatusOr<ReportData> data = GatherReportData(result, "r.json", "");
  ASSERT_TRUE(data.ok()) << data.status();
  ASSERT_TRUE(data->best_design.finish);
  EXPECT_EQ(data->scene->materials[data->best_design.finish->material].name, "white");
  ASSERT_EQ(data->free_variables.size(), 1u);
  EXPECT_EQ(data->free_variables[0].label, "slat finish [index]");
  EXPECT_EQ(DesignValue(result.job().variables(4), 1), "1: white");
  EXPECT_EQ(DesignValue(result.job().variables(4), 0.5), "0.5");
  const std::string page = Page(result);
  EXPECT_THAT(page, HasSubstr("Best design: alpha 0.8000 rad (45.8°), width 0.1500 m, spacing "
                              "0.0000 m, thickness 0.0100 m, finish 1: white"));
  EXPECT_THAT(page, HasSubstr("<td>white (reflectance 0.8)</td>"));
  EXPECT_THAT(page, Not(HasSubstr("black (reflectance 0)")));
  // A best finish the job does not list is refused
  v1::JobResult bad = result;
  (*bad.mutable_best_design())["finish"] = 2;
  EXPECT_THAT(Gather(bad).message(), HasSubstr("best_design: finish 2 is not an index"));
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
