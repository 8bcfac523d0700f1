// The search: each evaluation's value ± SE against evaluation number and time, the best so
// far, its error against time; and the design space: value against each free variable.
#include <fmt/format.h>

#include <algorithm>

#include "client/report/sections.h"
#include "client/report/svg.h"

namespace fenestra {
namespace {

// Figure sizes [px]: the chart area sits inside margins for the legend, ticks and labels.
constexpr double kWideWidth = 540, kWideHeight = 330;
constexpr double kSmallWidth = 350, kSmallHeight = 260;
constexpr double kSearchLeft = 72, kSearchTop = 52, kSearchRight = 20,
                 kSearchBottom = 62;  // two legend rows fit

// The value axis: every value ± error (and the target, when there is one), padded.
Axis ValueAxis(const ReportData& data) {
  std::vector<double> ends;
  for (const SearchPoint& p : data.search) {
    ends.push_back(p.value - p.standard_error);
    ends.push_back(p.value + p.standard_error);
  }
  if (data.result.job().objective().goal() == v1::GOAL_TARGET) {
    ends.push_back(data.result.job().objective().target());
  }
  Axis axis{data.metric_label};
  PaddedRange(ends, 0.06, &axis.lo, &axis.hi);
  return axis;
}

double TotalSeconds(const ReportData& data) {
  return data.search.empty() ? 0 : data.search.back().seconds;
}

Axis TimeAxis(const ReportData& data) {
  const double total = TotalSeconds(data);
  return {"evaluation time, cumulative [s]", 0, total > 0 ? 1.03 * total : 1};
}

// Points, error bars, the best-so-far line and the target of one value chart; `x_of` maps
// an evaluation to its x value.
template <typename XOf>
void DrawValues(Svg& svg, Chart& chart, const ReportData& data, XOf x_of, double x_end) {
  chart.DrawAxes();
  const v1::Objective& objective = data.result.job().objective();
  if (objective.goal() == v1::GOAL_TARGET) {
    svg.Line(chart.left(), chart.Y(objective.target()), chart.left() + chart.width(),
             chart.Y(objective.target()), "target-line");
  }
  svg.BeginGroup("evaluations");
  Points best;
  for (const SearchPoint& p : data.search) {
    chart.ErrorBar(x_of(p), p.value, p.standard_error,
                   p.improved ? "errorbar improved" : "errorbar");
    if (p.improved) best.emplace_back(x_of(p), p.value);
  }
  chart.StepLine(best, x_end, "best-line");
  for (const SearchPoint& p : data.search) {
    Marker(svg, chart.X(x_of(p)), chart.Y(p.value), p.improved,
           p.improved ? "point improved" : (p.cached ? "point cached" : "point"));
  }
  svg.EndGroup();
  std::vector<std::pair<std::string, std::string>> legend = {
      {"point", "evaluation ± SE"}, {"improved", "improvement"}, {"line:best-line", "best so far"}};
  if (std::any_of(data.search.begin(), data.search.end(),
                  [](const SearchPoint& p) { return p.cached; })) {
    legend.push_back({"cached", "repeat (cached)"});
  }
  if (objective.goal() == v1::GOAL_TARGET) {
    legend.push_back({"line:target-line", fmt::format("target {:g} %", objective.target())});
  }
  Legend(svg, 12, 18, legend);
}

std::string ValueByEvaluation(const ReportData& data) {
  Svg svg("plot-value-vs-evaluation", "search-plot", kWideWidth, kWideHeight,
          "Objective of every evaluation against its number");
  const double n = static_cast<double>(data.search.size());
  Chart chart(svg, kSearchLeft, kSearchTop, kWideWidth - kSearchLeft - kSearchRight,
              kWideHeight - kSearchTop - kSearchBottom, {"evaluation [number]", 0.5, n + 0.5, true},
              ValueAxis(data));
  DrawValues(
      svg, chart, data, [](const SearchPoint& p) { return double(p.number); }, n + 0.5);
  return svg.Finish();
}

std::string ValueByTime(const ReportData& data) {
  Svg svg("plot-value-vs-time", "search-plot", kWideWidth, kWideHeight,
          "Objective of every evaluation against the time spent");
  const Axis time = TimeAxis(data);
  Chart chart(svg, kSearchLeft, kSearchTop, kWideWidth - kSearchLeft - kSearchRight,
              kWideHeight - kSearchTop - kSearchBottom, time, ValueAxis(data));
  DrawValues(
      svg, chart, data, [](const SearchPoint& p) { return p.seconds; }, time.hi);
  return svg.Finish();
}

std::string ErrorByTime(const ReportData& data) {
  Svg svg("plot-error-vs-time", "search-plot", kWideWidth, kWideHeight,
          "Standard error of the best design against the time spent");
  std::vector<double> errors = {0};
  for (const ErrorPoint& e : data.best_error) errors.push_back(e.standard_error);
  if (data.recorded_error) {
    for (const ErrorPoint& e : *data.recorded_error) errors.push_back(e.standard_error);
  }
  const double top = *std::max_element(errors.begin(), errors.end());
  const Axis time = TimeAxis(data);
  Chart chart(svg, kSearchLeft, kSearchTop, kWideWidth - kSearchLeft - kSearchRight,
              kWideHeight - kSearchTop - kSearchBottom, time,
              {"standard error of the best [% points]", 0, top > 0 ? 1.15 * top : 1});
  chart.DrawAxes();
  Points steps;
  for (size_t i = 0; i < data.best_error.size(); ++i) {
    if (data.search[i].improved || i == 0) {
      steps.emplace_back(data.best_error[i].seconds, data.best_error[i].standard_error);
    }
  }
  chart.StepLine(steps, time.hi, "best-line");
  for (const auto& [x, y] : steps) Marker(svg, chart.X(x), chart.Y(y), true, "point improved");
  std::vector<std::pair<std::string, std::string>> legend = {
      {"line:best-line", "from the evaluations (best so far)"}};
  if (data.recorded_error) {
    Points recorded;
    for (const ErrorPoint& e : *data.recorded_error)
      recorded.emplace_back(chart.X(e.seconds), chart.Y(e.standard_error));
    svg.Polyline(recorded, "recorded-line");
    legend.push_back({"line:recorded-line", "recorded by the job"});
  }
  Legend(svg, 12, 18, legend);
  return svg.Finish();
}

std::string DesignVariablePlot(const ReportData& data, const FreeVariable& variable) {
  Svg svg("plot-design-" + variable.name, "design-plot", kSmallWidth, kSmallHeight,
          fmt::format("Objective against {}", variable.label));
  const double pad = 0.03 * (variable.upper - variable.lower);
  Chart chart(svg, kSearchLeft, 20, kSmallWidth - kSearchLeft - kSearchRight,
              kSmallHeight - 20 - kSearchBottom,
              {variable.label, variable.lower - pad, variable.upper + pad}, ValueAxis(data));
  chart.DrawAxes(5, 5);
  svg.BeginGroup("evaluations");
  for (const SearchPoint& p : data.search) {
    const auto x = p.design.find(variable.name);
    if (x == p.design.end()) continue;
    chart.ErrorBar(x->second, p.value, p.standard_error,
                   p.improved ? "errorbar improved" : "errorbar");
    Marker(svg, chart.X(x->second), chart.Y(p.value), p.improved,
           p.improved ? "point improved" : "point");
  }
  svg.EndGroup();
  return svg.Finish();
}

}  // namespace

std::string SearchSection(const ReportData& data) {
  if (data.search.empty()) {
    return Section("search", "The search", NotRecorded("Evaluations", "the result holds none"));
  }
  std::string body = Note(fmt::format(
      "{} designs proposed, {} of them evaluated (a repeat comes from the cache). Each point is a "
      "design's {} ± its Monte Carlo standard error; diamonds mark the evaluations that improved "
      "on the best design, the line is the best so far. Time is the evaluations' own time, added "
      "up.",
      data.search.size(), data.result.evaluations(), data.metric_name));
  body += "<div class=\"figures\">" + ValueByEvaluation(data) + ValueByTime(data) + "</div>\n";
  body += "<h3>Error against time</h3>\n<div class=\"figures\">" + ErrorByTime(data) + "</div>\n";
  if (!data.recorded_error) {
    body += NotRecorded("The job's own record of its error against time",
                        "this result does not hold one; the figure shows the error of the best "
                        "design computed from the evaluations");
  }
  return Section("search", "The search", body);
}

std::string DesignSpaceSection(const ReportData& data) {
  if (data.free_variables.empty()) {
    return Section("design-space", "The design space explored",
                   NotRecorded("Free design variables", "the job had none"));
  }
  std::string body = Note(
      "Every evaluation's value against each free design variable, over the range the search "
      "could explore; diamonds mark improvements.");
  body += "<div class=\"figures\">";
  for (const FreeVariable& v : data.free_variables) body += DesignVariablePlot(data, v);
  return Section("design-space", "The design space explored", body + "</div>\n");
}

}  // namespace fenestra
