// The summary (best design, its metrics with ASE and the LEED points, the objective's
// constraints) and the settings, timings and versions.
#include <fmt/format.h>
#include <fmt/ranges.h>

#include <algorithm>

#include "client/report/sections.h"
#include "client/report/svg.h"
#include "core/optimize/job.h"

namespace fenestra {
namespace {

using Rows = std::vector<std::vector<std::string>>;

std::string GoalText(const v1::Objective& objective) {
  switch (objective.goal()) {
    case v1::GOAL_MINIMIZE:
      return "minimize";
    case v1::GOAL_TARGET:
      return fmt::format("reach {:g} % (stop within {:g} %)", objective.target(),
                         objective.target_tolerance());
    default:
      return "maximize";
  }
}

std::string BestDesignTable(const ReportData& data) {
  Rows rows;
  for (const v1::DesignVariable& v : data.result.job().variables()) {
    const auto best = data.result.best_design().find(v.name());
    const bool free = !v.fixed() && v.upper() > v.lower();
    rows.push_back({v.name(),
                    best == data.result.best_design().end() ? "-" : DesignValue(v, best->second),
                    free ? fmt::format("[{:g}, {:g}]", v.lower(), v.upper()) : "fixed",
                    DesignValue(v, v.start())});
  }
  return HtmlTable("best-design-table", {"variable", "best", "range searched", "start"}, rows);
}

std::string BestMetricsTable(const ReportData& data) {
  const v1::Metrics& m = data.result.best_metrics();
  const v1::MetricSettings& s = data.result.job().metrics();
  const std::string udi = fmt::format("UDI {:g}–{:g} lx", s.udi_lower_lux(), s.udi_upper_lux());
  auto row = [](const std::string& name, const v1::Estimate& e) -> std::vector<std::string> {
    return {name, WithError(e.value(), e.standard_error())};
  };
  Rows rows = {row(udi + ", mean over sensors", m.udi()),
               row("UDI fell short (below the range)", m.udi_fell_short()),
               row("UDI exceeded (above the range)", m.udi_exceeded()),
               row(udi + ", all sensors at once", m.udi_all_sensors()),
               row(fmt::format("DA{:g}", s.da_threshold_lux()), m.da()),
               row(fmt::format("cDA{:g}", s.da_threshold_lux()), m.cda()),
               row(MetricName(v1::METRIC_SDA, s), m.sda())};
  if (m.has_ase()) {
    rows.push_back(
        row(MetricName(v1::METRIC_ASE, s) + " (% of sensors; direct sun, exact)", m.ase()));
  }
  if (data.operated_blind && m.has_blind_in_place()) {
    rows.push_back(row("blind in place (% of analysed hours)", m.blind_in_place()));
  }
  return HtmlTable("best-metrics-table", {"metric, best design", "value ± SE [%]"}, rows);
}

// "LEED v4.1 daylight option 1: 2 points; ASE at most 10%: yes", for results with ASE.
std::string LeedLine(const ReportData& data) {
  const v1::Metrics& m = data.result.best_metrics();
  if (!m.has_ase()) return "";
  const std::string text =
      fmt::format("LEED v4.1 daylight option 1: {} point{}; ASE at most 10%: {}", m.leed_points(),
                  m.leed_points() == 1 ? "" : "s", m.ase().value() <= 10 ? "yes" : "no");
  return fmt::format(
      "<p class=\"lead\" id=\"leed\">{}</p>\n"
      "<p class=\"note\">{}</p>\n",
      EscapeXml(text),
      EscapeXml(fmt::format(
          "Points from {} (1 at 40 %, 2 at 55 %, 3 at 75 % of the sensors); LEED asks {} to be "
          "at most 10 % besides{}.",
          MetricName(v1::METRIC_SDA, data.result.job().metrics()),
          MetricName(v1::METRIC_ASE, data.result.job().metrics()),
          data.operated_blind ? " (ASE with the window bare, the operated blind retracted)" : "")));
}

// The objective's constraints at the best design, for jobs with constraints.
std::string ConstraintsTable(const ReportData& data) {
  Rows rows;
  int broken = 0, unknown = 0;
  for (const ConstraintRow& c : data.constraints) {
    const bool known = c.estimate.has_value();
    broken += known && !c.holds;
    unknown += !known;
    rows.push_back(
        {MetricName(c.constraint.metric(), data.result.job().metrics()),
         c.constraint.bound() == v1::Constraint::AT_LEAST ? "at least" : "at most",
         fmt::format("{:g}", c.constraint.value()),
         known ? WithError(c.estimate->value(), c.estimate->standard_error()) : "not recorded",
         known ? (c.holds ? "yes" : "no") : "-"});
  }
  std::string verdict = broken == 0 ? "The best design keeps every constraint"
                                    : fmt::format("The best design breaks {} of the {} constraints",
                                                  broken, data.constraints.size());
  if (data.constraints.size() == 1) {
    verdict = broken == 0 ? "The best design keeps its constraint"
                          : "The best design breaks its constraint";
  }
  if (unknown > 0) verdict = "The result does not hold every constrained metric";
  return "<div><h3>Constraints</h3>" +
         HtmlTable("constraints-table",
                   {"metric", "bound", "value [%]", "best design ± SE [%]", "holds"}, rows) +
         Note(fmt::format("{}. A constraint holds unless its metric is beyond the bound by more "
                          "than {:g} of its standard errors.",
                          verdict, data.constraint_standard_errors)) +
         "</div>";
}

Rows JobRows(const ReportData& data) {
  const v1::Job& job = data.result.job();
  const v1::Budget& b = job.budget();
  return {
      {"name", job.name()},
      {"objective", fmt::format("{} {} [%]", GoalText(job.objective()), data.metric_name)},
      {"budget", fmt::format("{} evaluations{}", b.max_evaluations(),
                             b.max_seconds() > 0 ? fmt::format(", {:g} s", b.max_seconds()) : "")},
      {"evaluations", fmt::format("{} ({} in the history, repeats included)",
                                  data.result.evaluations(), data.result.history_size())},
      {"stopped", data.result.stop_reason()}};
}

Rows SamplingRows(const ReportData& data) {
  const v1::Sampling& s = data.result.job().sampling();
  std::string parts = "-";
  if (data.scene) {
    std::vector<std::string> each;
    for (const SceneWindow& w : data.scene->windows) {
      const WindowParts p = SamplingWindowParts(s, w.window);
      each.push_back(data.scene->windows.size() == 1
                         ? fmt::format("{} × {}", p.columns, p.rows)
                         : fmt::format("{} {} × {}", w.name, p.columns, p.rows));
    }
    parts = fmt::format("{}{}", fmt::join(each, ", "),
                        s.window_columns() == 0 || s.window_rows() == 0 ? " (automatic)" : "");
  }
  auto bounces = [](int b) {
    return b < 0 ? std::string("unlimited (roulette)") : fmt::format("{}", b);
  };
  return {{"outdoor paths", fmt::format("{}", s.outdoor_paths())},
          {"outdoor bounces", bounces(s.outdoor_bounces())},
          {"indoor paths per sensor", fmt::format("{}", s.indoor_paths_per_sensor())},
          {"indoor bounces", bounces(s.indoor_bounces())},
          {"batches (standard errors)", fmt::format("{}", s.batches())},
          {"seed", fmt::format("{}", s.seed())},
          {"direction cells", fmt::format("{}", s.basis_cells())},
          {"window parts", parts},
          {"backend", fmt::format("{} (asked: {})", data.result.backend(), s.backend())}};
}

Rows MetricRows(const ReportData& data) {
  const v1::MetricSettings& m = data.result.job().metrics();
  Rows rows = {{"UDI range",
                fmt::format("{:g}–{:g} lx, limits included", m.udi_lower_lux(), m.udi_upper_lux())},
               {"DA threshold", fmt::format("{:g} lx", m.da_threshold_lux())},
               {"sDA share of hours", fmt::format("{:g} %", m.sda_time_fraction_percent())},
               {"occupied hours", fmt::format("{:g}–{:g} h local standard time",
                                              m.occupied_start_h(), m.occupied_end_h())},
               {"hours counted", m.all_hours() ? "all 8760" : "occupied"}};
  if (data.result.best_metrics().has_ase()) {
    rows.push_back(
        {"ASE", fmt::format("more than {:g} lx of direct sun in at least {} analysed hours",
                            data.ase_threshold_lux, data.ase_min_hours)});
  }
  if (data.operated_blind) {
    rows.push_back(
        {"blind operation",
         fmt::format("automated (sun): in place in the hours in which more than {:g} % of the "
                     "sensors get more than {:g} lx of direct sun through the bare window",
                     m.operation_sensor_percent() > 0 ? m.operation_sensor_percent() : 2,
                     m.operation_threshold_lux() > 0 ? m.operation_threshold_lux() : 1000)});
  }
  return rows;
}

Rows SiteRows(const ReportData& data) {
  Rows rows = {{"weather", data.result.weather_location().empty()
                               ? "not recorded"
                               : data.result.weather_location()}};
  if (data.scene) {
    const Site& s = data.scene->site;
    rows.push_back(
        {"latitude, longitude", fmt::format("{:.2f}°, {:.2f}°", s.latitude_deg, s.longitude_deg)});
    rows.push_back({"time zone", fmt::format("UTC{:+g} h", s.time_zone_h)});
    rows.push_back({"ground reflectance", fmt::format("{:.2f}", s.ground_reflectance)});
    rows.push_back(
        {"scene", fmt::format("{} ({} triangles, {} sensors)", data.scene->name,
                              data.scene->fixed.TriangleCount(), data.scene->sensors.size())});
  }
  return rows;
}

Rows TimingRows(const ReportData& data) {
  const v1::Timings& t = data.result.timings();
  const int n = data.result.evaluations();
  return {{"sky matrix", fmt::format("{:.2f} s", t.sky_seconds())},
          {"outdoor matrix", t.outdoor_seconds() > 0 ? fmt::format("{:.2f} s", t.outdoor_seconds())
                                                     : "from the cache"},
          {"evaluations", fmt::format("{:.2f} s ({:.3f} s each)", t.evaluation_seconds(),
                                      n > 0 ? t.evaluation_seconds() / n : 0.0)},
          {"best design's hourly illuminance", fmt::format("{:.2f} s", t.best_hourly_seconds())},
          {"whole job", fmt::format("{:.2f} s", t.total_seconds())},
          {"outdoor matrix error",
           fmt::format("{:.2f} % (mean relative SE)",
                       100 * data.result.outdoor_mean_relative_standard_error())}};
}

std::string KeyValueTable(std::string_view id, std::string_view title, const Rows& rows) {
  return "<div>" + fmt::format("<h3>{}</h3>", EscapeXml(title)) +
         HtmlTable(id, {"setting", "value"}, rows, /*align_numbers=*/false) + "</div>";
}

}  // namespace

std::string SummarySection(const ReportData& data) {
  std::string body = "<div class=\"tables\">";
  body += "<div><h3>Best design</h3>" + BestDesignTable(data) + "</div>";
  body += "<div><h3>Its annual metrics</h3>" + BestMetricsTable(data) + "</div>";
  if (!data.constraints.empty()) body += ConstraintsTable(data);
  body += "</div>\n" + LeedLine(data);
  return Section("summary", "Summary", body);
}

std::string SettingsSection(const ReportData& data) {
  Rows versions;  // by name: a map's order is not kept
  for (const auto& [name, version] : data.result.versions()) versions.push_back({name, version});
  std::sort(versions.begin(), versions.end());
  std::string body = "<div class=\"tables\">";
  body += KeyValueTable("job-table", "Job", JobRows(data));
  body += KeyValueTable("sampling-table", "Sampling", SamplingRows(data));
  body += KeyValueTable("metric-settings-table", "Metrics", MetricRows(data));
  body += KeyValueTable("site-table", "Site", SiteRows(data));
  body += KeyValueTable("timings-table", "Timings", TimingRows(data));
  body += versions.empty() ? "<div><h3>Versions</h3>" +
                                 NotRecorded("Versions", "the result predates them") + "</div>"
                           : KeyValueTable("versions-table", "Versions", versions);
  body += "</div>\n<h3>Final one-stage check</h3>\n";
  if (data.final_check) {
    Rows rows;
    for (const auto& [quantity, value] : *data.final_check) rows.push_back({quantity, value});
    body += HtmlTable("final-check-table", {"quantity", "value"}, rows);
  } else {
    body += NotRecorded("The final one-stage check of the best design",
                        "this result does not hold one");
  }
  return Section("settings", "Settings, timings and versions", body);
}

}  // namespace fenestra
