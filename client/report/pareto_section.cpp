// The report's section on a Pareto search (job.proto, ParetoResult): the evaluated designs in
// the plane of the first two objectives, the front with its error bars, the hypervolume per
// generation and the front as a table.
#include <fmt/format.h>

#include <algorithm>
#include <string>
#include <vector>

#include "client/report/sections.h"
#include "client/report/svg.h"

namespace fenestra {
namespace {

constexpr double kWidth = 540, kHeight = 360, kLeft = 72, kTop = 52, kRight = 20, kBottom = 62;

// "sDA [%]", "METRIC_SOLAR_GAIN [kWh]": an objective's axis label.
std::string ObjectiveLabel(const v1::Objective& o) {
  const bool gain =
      o.metric() == v1::METRIC_SOLAR_GAIN || o.metric() == v1::METRIC_COOLING_SOLAR_GAIN;
  std::string name = v1::Metric_Name(o.metric());
  if (name.rfind("METRIC_", 0) == 0) name = name.substr(7);
  std::transform(name.begin(), name.end(), name.begin(), [](char c) {
    return c == '_' ? ' ' : static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  });
  return fmt::format("{} [{}] ({})", name, gain ? "kWh" : "%",
                     o.goal() == v1::GOAL_MINIMIZE ? "lower is better" : "higher is better");
}

std::string FrontPlot(const v1::JobResult& r) {
  const auto& objectives = r.job().pareto().objectives();
  std::vector<double> xs, ys;
  for (const v1::Evaluation& e : r.history()) {
    if (e.objectives_size() < 2) continue;
    xs.push_back(e.objectives(0).value());
    ys.push_back(e.objectives(1).value());
  }
  Axis x{ObjectiveLabel(objectives[0])}, y{ObjectiveLabel(objectives[1])};
  PaddedRange(xs, 0.05, &x.lo, &x.hi);
  PaddedRange(ys, 0.05, &y.lo, &y.hi);
  Svg svg("plot-pareto-front", "pareto-plot", kWidth, kHeight,
          "The evaluated designs and the Pareto front");
  Chart chart(svg, kLeft, kTop, kWidth - kLeft - kRight, kHeight - kTop - kBottom, x, y);
  chart.DrawAxes(6, 5);
  svg.BeginGroup("evaluations");
  for (size_t i = 0; i < xs.size(); ++i)
    Marker(svg, chart.X(xs[i]), chart.Y(ys[i]), false, "point");
  svg.EndGroup();
  svg.BeginGroup("front");
  Points line;
  for (const v1::FrontMember& m : r.pareto().front()) {
    const double fx = m.objectives(0).value(), fy = m.objectives(1).value();
    chart.ErrorBar(fx, fy, m.objectives(1).standard_error(), "errorbar improved");
    svg.Line(chart.X(fx - m.objectives(0).standard_error()), chart.Y(fy),
             chart.X(fx + m.objectives(0).standard_error()), chart.Y(fy), "errorbar improved");
    Marker(svg, chart.X(fx), chart.Y(fy), true, "point improved front-member");
    line.push_back({chart.X(fx), chart.Y(fy)});
  }
  svg.Polyline(line, "best-line");
  svg.EndGroup();
  Legend(svg, 12, 18, {{"point", "evaluated design"}, {"improved", "front member ± 1 SE"}});
  return svg.Finish();
}

std::string HypervolumePlot(const v1::ParetoResult& p) {
  std::vector<double> gens, values(p.hypervolume().begin(), p.hypervolume().end());
  for (int g = 0; g < p.hypervolume_size(); ++g) gens.push_back(g);
  Axis x{"generation", 0, std::max(1.0, gens.empty() ? 1.0 : gens.back()), true}, y{"hypervolume"};
  PaddedRange(values, 0.05, &y.lo, &y.hi);
  Svg svg("plot-hypervolume", "pareto-plot", kWidth, 240, "Hypervolume per generation");
  Chart chart(svg, kLeft, 20, kWidth - kLeft - kRight, 240 - 20 - 50, x, y);
  chart.DrawAxes(6, 4);
  Points line;
  for (size_t g = 0; g < values.size(); ++g) line.push_back({chart.X(gens[g]), chart.Y(values[g])});
  svg.Polyline(line, "best-line");
  return svg.Finish();
}

std::string FrontTable(const v1::JobResult& r) {
  std::vector<std::string> header = {"step"};
  for (const v1::Objective& o : r.job().pareto().objectives()) header.push_back(ObjectiveLabel(o));
  for (const v1::DesignVariable& v : r.job().variables()) header.push_back(v.name());
  std::vector<std::vector<std::string>> rows;
  for (const v1::FrontMember& m : r.pareto().front()) {
    std::vector<std::string> row = {std::to_string(m.evaluation())};
    for (const v1::Estimate& o : m.objectives())
      row.push_back(WithError(o.value(), o.standard_error()));
    for (const v1::DesignVariable& v : r.job().variables()) {
      const auto it = m.design().find(v.name());
      row.push_back(it == m.design().end() ? "" : fmt::format("{:.4g}", it->second));
    }
    rows.push_back(std::move(row));
  }
  return HtmlTable("pareto-front-table", header, rows);
}

}  // namespace

std::string ParetoSection(const ReportData& data) {
  const v1::JobResult& r = data.result;
  if (!r.has_pareto()) return "";
  const v1::ParetoResult& p = r.pareto();
  std::string body = Note(fmt::format(
      "NSGA-II over {} generations of {} designs. The front holds the {} evaluated designs that "
      "no other beats in every objective by more than {:g} combined standard errors: each is "
      "drawn with its error bars (± 1 standard error in each objective), and members whose "
      "bars overlap are not told apart by the Monte Carlo estimate. More paths per sensor "
      "narrow the bars and thin the front. The best design of the rest of this report is the "
      "front's best in the first objective.",
      p.generations(), r.job().pareto().population(), p.front_size(),
      r.job().pareto().dominance_standard_errors()));
  if (r.job().pareto().objectives_size() > 2) {
    body += Note("Three objectives: the figure shows the first two; the table has all three.");
  }
  body += "<div class=\"figures\">" + FrontPlot(r) + HypervolumePlot(p) + "</div>\n";
  body += FrontTable(r);
  return Section("pareto", "The Pareto front", body);
}

}  // namespace fenestra
