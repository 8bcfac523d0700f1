#include "client/report/report_data.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <array>
#include <cmath>

#include "client/report/html_report.h"
#include "client/report/sections.h"
#include "tests/client/report/direct_sun_result.h"
#include "tests/quick_job.h"

namespace fenestra {

// The quick job's result as a Pareto search's: sDA maximized against glare hours minimized
// (with `three`, the solar gain minimized too, 1000 kWh + 10 x the glare hours), a history of
// ten steps (nine designs and the third again, from the cache), five designs on the front,
// listed in the order of the history, their UDI, and three generations' hypervolume. By sDA,
// best first, the front runs (90, 30), (85, 12), (80, 6), (70, 4), (50, 3): A is the first,
// the best design (tilt 0.3), B the last (0.5), C (80, 6) (0.8) nearest the ideal corner.
// Used by html_report_test.cpp too.
v1::JobResult WithParetoFront(v1::JobResult r, bool three) {
  v1::ParetoSearch& search = *r.mutable_job()->mutable_pareto();
  const auto add = [&](v1::Metric metric, v1::Goal goal) {
    v1::Objective& o = *search.add_objectives();
    o.set_metric(metric);
    o.set_goal(goal);
  };
  add(v1::METRIC_SDA, v1::GOAL_MAXIMIZE);
  add(v1::METRIC_GLARE_HOURS, v1::GOAL_MINIMIZE);
  if (three) add(v1::METRIC_SOLAR_GAIN, v1::GOAL_MINIMIZE);
  search.set_population(4);
  search.set_dominance_standard_errors(1.5);
  const std::vector<std::array<double, 3>> designs = {// sDA, glare hours, on the front
                                                      {70, 4, 1},  {60, 20, 0}, {90, 30, 1},
                                                      {75, 15, 0}, {50, 3, 1},  {40, 10, 0},
                                                      {85, 12, 1}, {80, 6, 1},  {65, 25, 0}};
  r.clear_history();
  (*r.mutable_best_design())["alpha"] = 0.3;
  for (int i = 0; i <= static_cast<int>(designs.size()); ++i) {
    const bool repeat = i == static_cast<int>(designs.size());
    const int d = repeat ? 2 : i;
    v1::Evaluation& e = *r.add_history();
    e.set_index(i);
    *e.mutable_design() = r.best_design();
    (*e.mutable_design())["alpha"] = 0.1 * (d + 1);
    e.mutable_value()->set_value(designs[d][0]);
    e.mutable_value()->set_standard_error(0.8);
    e.set_seconds(repeat ? 0 : 0.5);
    e.set_cached(repeat);
    e.set_generation(i / 4);
    std::vector<double> objectives = {designs[d][0], designs[d][1]};
    if (three) objectives.push_back(1000 + 10 * designs[d][1]);
    for (const double v : objectives) {
      e.add_objectives()->set_value(v);
      e.mutable_objectives()->rbegin()->set_standard_error(0.8);
    }
  }
  v1::ParetoResult& p = *r.mutable_pareto();
  for (int i = 0; i < static_cast<int>(designs.size()); ++i) {
    if (!designs[i][2]) continue;
    v1::FrontMember& m = *p.add_front();
    m.set_evaluation(i);
    *m.mutable_design() = r.history(i).design();
    *m.mutable_objectives() = r.history(i).objectives();
    m.mutable_metrics()->mutable_udi()->set_value(40 + i);
    m.mutable_metrics()->mutable_udi()->set_standard_error(1);
  }
  for (const double h : {300.0, 650.0, 700.0}) p.add_hypervolume(h);
  for (const double v : {40.0, 30.0, 1300.0}) {
    if (p.reference_size() < search.objectives_size()) p.add_reference(v);
  }
  p.set_generations(3);
  return r;
}

// The quick job's result with three view points in its scene and their glare: "desk <1>"
// facing north with its DGP at every step (intolerable, 0.5, from 12 to 14 h in June;
// disturbing, 0.42, in July; perceptible, 0.37, in August; 0.159 otherwise), "screen"
// facing east with its DGP (0.5 from 12 to 14 h in December), and "v3" (unnamed) facing
// west with 10 values only. Used by html_report_test.cpp too.
v1::JobResult WithGlareAtViews(v1::JobResult r) {
  v1::Scene& scene = *r.mutable_job()->mutable_scene();
  const std::vector<std::array<double, 4>> views = {
      {-0.5, -2, 0, 1}, {0.5, -4, 1, 0}, {-0.5, -4, -1, 0}};  // x, y, direction x, y
  const std::vector<std::string> names = {"desk <1>", "screen", ""};
  for (size_t k = 0; k < views.size(); ++k) {
    v1::ViewPoint& v = *scene.add_views();
    v.set_name(names[k]);
    v.mutable_position()->set_x(views[k][0]);
    v.mutable_position()->set_y(views[k][1]);
    v.mutable_position()->set_z(7.2);
    v.mutable_direction()->set_x(views[k][2]);
    v.mutable_direction()->set_y(views[k][3]);
  }
  const v1::HourlyIlluminance& h = r.best_hourly();
  for (const std::string name : {"desk <1>", "screen", "v3"}) {
    v1::ViewGlare& g = *r.add_best_glare();
    g.set_view(name);
    g.mutable_autonomy()->set_value(95);
    g.mutable_mean_dgp()->set_value(0.2);
    g.set_en17037("medium");
    g.set_analysed_hours(3650);
    const int steps = name == "v3" ? 10 : h.month_size();
    for (int j = 0; j < steps; ++j) {
      const bool noon = h.hour(j) > 12 && h.hour(j) < 14;
      const int month = h.month(j);
      float dgp = 0.159f;
      if (name == "screen" && noon && month == 12) dgp = 0.5f;
      if (name == "desk <1>" && noon && month >= 6 && month <= 8) {
        dgp = month == 6 ? 0.5f : month == 7 ? 0.42f : 0.37f;
      }
      g.add_dgp(dgp);
    }
  }
  return r;
}

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

// A Pareto search's front: the evaluated designs in grey (the repeat from the cache left out),
// the members with their error bars in both objectives, the ring around the best design, the
// letters A, B, C, the "better" arrows, the hypervolume, the table and the chosen members'
// blinds; the third objective is said to be left out of the figure.
TEST(ReportDataTest, TheParetoFrontShowsItsMembersAndTheChosenOnes) {
  const std::string page = Page(WithParetoFront(QuickJobResult(), false));
  const std::string front = Figure(page, "plot-pareto-front");
  ASSERT_FALSE(front.empty());
  EXPECT_EQ(Count(front, "front-member"), 5);
  EXPECT_EQ(Count(front, "class=\"point evaluated\""), 9 + 1);  // the legend's sample too
  EXPECT_EQ(Count(front, "class=\"errorbar improved\""), 5 * 6);
  EXPECT_EQ(Count(front, "class=\"pareto-best\""), 1 + 1);
  EXPECT_EQ(Count(front, "class=\"pareto-label\""), 3);
  for (const char* label : {">A</text>", ">B</text>", ">C</text>", ">sDA300/50% [%]</text>",
                            ">glare hours [%]</text>"}) {
    EXPECT_EQ(Count(front, label), 1) << label;
  }
  EXPECT_EQ(Count(front, ">better</text>"), 2);
  EXPECT_THAT(page, HasSubstr("Chosen: A evaluation 3, B evaluation 5, C evaluation 8."));
  EXPECT_THAT(page, HasSubstr("by more than 1.5 combined standard errors"));
  EXPECT_THAT(page, Not(HasSubstr("Three objectives")));
  // The hypervolume, one point per generation
  EXPECT_EQ(Count(Figure(page, "plot-hypervolume"), "class=\"point\""), 3);
  EXPECT_THAT(page, HasSubstr("hypervolume [% × %]"));
  // The table, best first by sDA: the members' tilt, objectives and UDI
  EXPECT_THAT(page, HasSubstr("<tr><td>A, best</td><td class=\"num\">3</td><td class=\"num\">"
                              "0.3000 rad (17.2°)</td><td class=\"num\">90.00 ± 0.80</td>"
                              "<td class=\"num\">30.00 ± 0.80</td><td class=\"num\">"
                              "42.00 ± 1.00</td></tr>"));
  EXPECT_THAT(page, HasSubstr("<tr><td>C</td><td class=\"num\">8</td>"));
  EXPECT_THAT(page, HasSubstr("<tr><td></td><td class=\"num\">7</td>"));
  EXPECT_THAT(page, HasSubstr("<th>UDI 100–3000 lx [%]</th>"));
  const size_t table = page.find("id=\"pareto-front-table\"");
  ASSERT_NE(table, std::string::npos);
  EXPECT_EQ(Count(page.substr(table, page.find("</table>", table) - table), "<tr>"), 1 + 5);
  // The blinds of A, B and C
  EXPECT_THAT(page, HasSubstr("<h3>The blind at A, B and C</h3>"));
  for (const char* id : {"plot-pareto-blind-a", "plot-pareto-blind-b", "plot-pareto-blind-c"}) {
    EXPECT_THAT(Figure(page, id), HasSubstr("class=\"slat\"")) << id;
  }
  EXPECT_THAT(page, HasSubstr("Section through the window at front member C (evaluation 8)"));

  // A long front's table: one member in every 3, and C
  v1::JobResult r = WithParetoFront(QuickJobResult(), false);
  const v1::ParetoResult five = r.pareto();
  for (int copy = 1; copy < 20; ++copy) {
    for (const v1::FrontMember& m : five.front()) *r.mutable_pareto()->add_front() = m;
  }
  EXPECT_THAT(Page(r), HasSubstr("35 of the 100 members shown: one in every 3 by sDA300/50%, and "
                                 "the chosen ones and the best design."));

  const std::string three = Page(WithParetoFront(QuickJobResult(), true));
  EXPECT_THAT(three, HasSubstr("Three objectives: the figure plots the first two (sDA300/50% "
                               "across, glare hours up); the table holds solar gain as well."));
  EXPECT_THAT(three, HasSubstr("hypervolume [% × % × kWh]"));
  EXPECT_THAT(three, HasSubstr("<th>solar gain [kWh] (lower is better)</th>"));
  EXPECT_EQ(Count(Figure(three, "plot-pareto-front"), "front-member"), 5);
  EXPECT_THAT(Page(QuickJobResult()), Not(HasSubstr("plot-pareto-front")));
}

// The DGP of each view that holds it per time step is a map by day and hour coloured by
// comfort class, in the glare section with the glare table; a view without it has no map, one
// whose values do not match the time steps says so.
TEST(ReportDataTest, TheDgpIsMappedPerView) {
  const std::string page = Page(WithGlareAtViews(QuickJobResult()));
  const size_t section = page.find("<section id=\"glare\">");
  ASSERT_NE(section, std::string::npos);
  EXPECT_GT(page.find("id=\"glare-table\""), section);
  EXPECT_LT(page.find("id=\"glare-table\""), page.find("<section id=\"blind\">"));
  const std::string desk = Figure(page, "plot-glare-map-0");
  ASSERT_FALSE(desk.empty());
  for (const char* color : {"#e5f5e0", "#fee391", "#fe9929", "#b2182b"}) {
    EXPECT_THAT(desk, HasSubstr(std::string("class=\"map-cell\" fill=\"") + color)) << color;
  }
  for (const char* name : {">imperceptible<", ">perceptible<", ">disturbing<", ">intolerable<"}) {
    EXPECT_THAT(desk, HasSubstr(name));
  }
  EXPECT_THAT(page, HasSubstr("Daylight glare probability at desk &lt;1&gt; by day and hour, best "
                              "design, the blind in place (dark hours at 0.159, the DGP of no "
                              "light). Of its 3650 analysed hours: 3466 imperceptible (DGP below "
                              "0.35), 62 perceptible (below 0.40), 62 disturbing (below 0.45), 60 "
                              "intolerable."));
  const std::string screen = Figure(page, "plot-glare-map-1");
  ASSERT_FALSE(screen.empty());
  EXPECT_THAT(screen, HasSubstr("class=\"map-cell\" fill=\"#b2182b\""));
  EXPECT_THAT(screen, Not(HasSubstr("class=\"map-cell\" fill=\"#fee391\"")));
  EXPECT_THAT(page, Not(HasSubstr("plot-glare-map-2")));
  EXPECT_THAT(page, HasSubstr("The DGP by day and hour at v3: not recorded (it holds 10 values "
                              "for the 8760 time steps of the hourly illuminance)."));
  EXPECT_THAT(Page(QuickJobResult()), Not(HasSubstr("<section id=\"glare\">")));
}

// The view points on each floor plan: a dot, an arrow along the view direction and the name
TEST(ReportDataTest, TheViewsAreDrawnOnThePlan) {
  const std::string page = Page(WithGlareAtViews(QuickJobResult()));
  for (const char* id : {"plot-floor-udi", "plot-floor-da"}) {
    const std::string plan = Figure(page, id);
    ASSERT_FALSE(plan.empty()) << id;
    EXPECT_EQ(Count(plan, "class=\"view-point\""), 3) << id;
    EXPECT_EQ(Count(plan, "class=\"view-arrow\""), 3) << id;
    EXPECT_EQ(Count(plan, "class=\"view-arrow-head\""), 3) << id;
    for (const char* name : {">desk &lt;1&gt;</text>", ">screen</text>", ">v3</text>"}) {
      EXPECT_EQ(Count(plan, name), 1) << id << " " << name;
    }
    // The desk looks north: its name above its dot, the screen's right of it, v3's left of it
    EXPECT_THAT(plan, HasSubstr("text-anchor=\"middle\" class=\"view-name\">desk"));
    EXPECT_THAT(plan, HasSubstr("text-anchor=\"start\" class=\"view-name\">screen"));
    EXPECT_THAT(plan, HasSubstr("text-anchor=\"end\" class=\"view-name\">v3"));
  }
  EXPECT_THAT(page, HasSubstr("the arrows mark the view points and where they look"));
  // A name that fits nowhere on the plan is a tag there, named in the caption
  v1::JobResult r = WithGlareAtViews(QuickJobResult());
  v1::ViewPoint& far = *r.mutable_job()->mutable_scene()->add_views();
  far.set_name("a view point whose name is longer than the whole floor plan is wide");
  far.mutable_position()->set_z(7.2);
  far.mutable_direction()->set_y(1);
  const std::string tagged = Page(r);
  EXPECT_EQ(Count(Figure(tagged, "plot-floor-udi"), "class=\"view-name\">V4</text>"), 1);
  EXPECT_THAT(tagged, HasSubstr("where they look (V4 = a view point whose name is longer than "
                                "the whole floor plan is wide)</figcaption>"));
  EXPECT_THAT(Figure(Page(QuickJobResult()), "plot-floor-udi"), Not(HasSubstr("view-point")));
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
