#include "client/report/html_report.h"

#include <fmt/format.h>

#include <algorithm>
#include <cctype>

#include "absl/strings/str_join.h"
#include "client/report/report_data.h"
#include "client/report/sections.h"
#include "client/report/svg.h"
#include "core/common/atomic_file.h"
#include "core/common/status_macros.h"

namespace fenestra {
namespace {

// Screen and print: white paper, dark text; colours carry meaning only with a legend.
constexpr char kStyle[] = R"css(
:root { color-scheme: light; }
body { margin: 0; background: #fff; color: #1a1a1a; font: 15px/1.45 system-ui, -apple-system,
  "Segoe UI", Roboto, "Helvetica Neue", Arial, sans-serif; }
main { max-width: 1140px; margin: 0 auto; padding: 24px 28px 48px; }
h1 { font-size: 26px; margin: 0 0 4px; }
h2 { font-size: 20px; margin: 34px 0 8px; padding-bottom: 4px; border-bottom: 2px solid #d0d7de; }
h3 { font-size: 16px; margin: 16px 0 6px; }
.lead { font-size: 16px; margin: 6px 0; }
.meta, .note, figcaption, footer { color: #444; }
.note { max-width: 80ch; margin: 4px 0 10px; }
.not-recorded { color: #8a4b00; font-style: italic; }
.figures { display: flex; flex-wrap: wrap; gap: 14px 28px; align-items: flex-start; }
.tables { display: flex; flex-wrap: wrap; gap: 0 32px; align-items: flex-start; }
figure { margin: 0; }
figcaption { font-size: 13px; max-width: 62ch; margin-top: 2px; }
svg.figure { display: block; max-width: 100%; height: auto; background: #fff; }
table { border-collapse: collapse; font-size: 14px; margin: 6px 0 12px; }
th, td { border-bottom: 1px solid #d8dee4; padding: 3px 10px; text-align: left; vertical-align: top; }
th { background: #f3f5f7; font-weight: 600; }
td.num { text-align: right; font-variant-numeric: tabular-nums; }
footer { margin-top: 36px; font-size: 13px; border-top: 1px solid #d0d7de; padding-top: 8px; }
.grid { stroke: #e6e9ed; stroke-width: 1; }
.frame { fill: none; stroke: #6e7781; stroke-width: 1; }
.tick { stroke: #6e7781; stroke-width: 1; }
.tick-label { font-size: 11px; fill: #333; }
.axis-label { font-size: 12.5px; fill: #1a1a1a; }
.legend-text { font-size: 12px; fill: #1a1a1a; }
.point { fill: #0072b2; stroke: #fff; stroke-width: 0.8; }
.point.improved { fill: #d55e00; }
.point.cached { fill: #fff; stroke: #0072b2; stroke-width: 1.2; }
.errorbar { stroke: #0072b2; stroke-width: 1.1; opacity: 0.6; }
.errorbar.improved { stroke: #d55e00; opacity: 0.85; }
.best-line { fill: none; stroke: #d55e00; stroke-width: 2; }
.recorded-line { fill: none; stroke: #009e73; stroke-width: 2; stroke-dasharray: 6 3; }
.target-line { stroke: #6a3d9a; stroke-width: 1.5; stroke-dasharray: 5 4; }
.plan-floor { fill: #f1efe9; stroke: #f1efe9; stroke-width: 0.5; }
.plan-wall { stroke: #3d3d3d; stroke-width: 3; stroke-linecap: square; }
.plan-window { fill: #bfe0f5; stroke: #0072b2; stroke-width: 1.5; }
.plan-label { font-size: 12px; fill: #1a1a1a; }
.north-arrow { fill: #1a1a1a; }
.sensor { stroke: #1a1a1a; stroke-width: 1.2; }
.map-sensor { fill: none; stroke: #d55e00; stroke-width: 2; }
.marked-sensor { fill: none; stroke: #b2182b; stroke-width: 1.6; }
.sensor-name { font-size: 10.5px; fill: #555; }
.sensor-value { font-size: 11px; font-weight: 600; fill: #1a1a1a; }
.colorbar, .swatch { stroke: #6e7781; stroke-width: 0.8; }
.map-cell { shape-rendering: crispEdges; }
.occupancy { fill: none; stroke: #1a1a1a; stroke-width: 1.5; stroke-dasharray: 5 3; }
.wall { stroke: #555; stroke-width: 1; }
.window-face { stroke: #0072b2; stroke-width: 2; stroke-dasharray: 4 3; }
.slat { fill: #9a9a9a; stroke: #1a1a1a; stroke-width: 0.8; }
.dim-line { stroke: #333; stroke-width: 0.9; }
.dim-extension { stroke: #333; stroke-width: 0.6; }
.dim-text { font-size: 11.5px; fill: #1a1a1a; }
.reference-line { stroke: #888; stroke-width: 0.8; stroke-dasharray: 3 3; }
.angle-arc { fill: none; stroke: #d55e00; stroke-width: 1.5; }
.point.evaluated { fill: #b3b3b3; stroke: none; }
.pareto-best { fill: none; stroke: #1a1a1a; stroke-width: 1.6; }
.pareto-label { font-size: 13px; font-weight: 700; fill: #1a1a1a; }
.better { stroke: #444; stroke-width: 1.3; }
.better-head { fill: #444; }
.better-label { font-size: 11.5px; font-style: italic; fill: #444; }
.view-point { fill: #cc79a7; stroke: #1a1a1a; stroke-width: 1; }
.view-arrow { stroke: #a0406f; stroke-width: 2; }
.view-arrow-head { fill: #a0406f; }
.view-name { font-size: 10.5px; fill: #7a2a55; }
@page { size: A4; margin: 14mm; }
@media print {
  body { font-size: 10pt; }
  main { max-width: none; padding: 0; }
  h2 { break-after: avoid; }
  figure, table, svg.figure { break-inside: avoid; }
  * { -webkit-print-color-adjust: exact; print-color-adjust: exact; }
}
)css";

std::string Header(const ReportData& data) {
  const v1::JobResult& r = data.result;
  std::vector<std::string> design;
  for (const v1::DesignVariable& v : r.job().variables()) {
    const auto best = r.best_design().find(v.name());
    if (best != r.best_design().end())
      design.push_back(v.name() + " " + DesignValue(v, best->second));
  }
  std::string html =
      fmt::format("<header>\n<h1>Fenestra report: {}</h1>\n",
                  EscapeXml(r.job().name().empty() ? "optimization job" : r.job().name()));
  html +=
      fmt::format("<p class=\"lead\">Best design: {} — {} {} %</p>\n",
                  EscapeXml(absl::StrJoin(design, ", ")), EscapeXml(data.metric_name),
                  EscapeXml(WithError(r.best_value().value(), r.best_value().standard_error())));
  html += fmt::format(
      "<p class=\"meta\">{} evaluations, stopped: {}; {:.1f} s on {}; weather: {}; result: {}</p>\n"
      "</header>\n",
      r.evaluations(), EscapeXml(r.stop_reason()), r.timings().total_seconds(),
      EscapeXml(r.backend()),
      EscapeXml(r.weather_location().empty() ? "not recorded" : r.weather_location()),
      EscapeXml(data.source));
  return html;
}

std::string Page(const ReportData& data) {
  std::string html = fmt::format(
      "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n"
      "<meta http-equiv=\"Content-Security-Policy\" content=\"default-src 'none'; style-src "
      "'unsafe-inline'\">\n<meta name=\"viewport\" content=\"width=device-width, "
      "initial-scale=1\">\n"
      "<title>Fenestra report: {}</title>\n<style>{}</style>\n</head>\n<body>\n<main>\n",
      EscapeXml(data.result.job().name()), kStyle);
  html += Header(data);
  for (auto section :
       {SummarySection, SearchSection, ParetoSection, DesignSpaceSection, FloorPlanSection,
        TemporalMapSection, GlareSection, BlindSection, SettingsSection}) {
    html += section(data);
  }
  const auto version = data.result.versions().find("fenestra");
  html += fmt::format(
      "<footer>Made by fenestra {} from {}. Every value is a Monte Carlo estimate ± one standard "
      "error.</footer>\n</main>\n</body>\n</html>\n",
      EscapeXml(version == data.result.versions().end() ? "" : version->second),
      EscapeXml(data.source));
  return html;
}

// A cell that holds a number is aligned right.
bool IsNumber(std::string_view cell) {
  return !cell.empty() && (std::isdigit(static_cast<unsigned char>(cell[0])) ||
                           ((cell[0] == '-' || cell[0] == '+') && cell.size() > 1 &&
                            std::isdigit(static_cast<unsigned char>(cell[1]))));
}

}  // namespace

std::string NotRecorded(std::string_view what, std::string_view why) {
  return fmt::format("<p class=\"not-recorded\">{}: not recorded ({}).</p>\n", EscapeXml(what),
                     EscapeXml(why));
}

std::string WithError(double value, double standard_error, int decimals) {
  return fmt::format("{:.{}f} ± {:.{}f}", value, decimals, standard_error, decimals);
}

std::string HtmlTable(std::string_view id, const std::vector<std::string>& header,
                      const std::vector<std::vector<std::string>>& rows, bool align_numbers) {
  std::string html = id.empty() ? "<table>" : fmt::format("<table id=\"{}\">", EscapeXml(id));
  html += "\n<thead><tr>";
  for (const std::string& h : header) html += "<th>" + EscapeXml(h) + "</th>";
  html += "</tr></thead>\n<tbody>\n";
  for (const std::vector<std::string>& row : rows) {
    html += "<tr>";
    for (const std::string& cell : row) {
      html += (align_numbers && IsNumber(cell) ? "<td class=\"num\">" : "<td>") + EscapeXml(cell) +
              "</td>";
    }
    html += "</tr>\n";
  }
  return html + "</tbody></table>\n";
}

std::string Section(std::string_view id, std::string_view heading, std::string_view body) {
  return fmt::format("<section id=\"{}\">\n<h2>{}</h2>\n{}</section>\n", EscapeXml(id),
                     EscapeXml(heading), body);
}

std::string Note(std::string_view text) {
  return fmt::format("<p class=\"note\">{}</p>\n", EscapeXml(text));
}

std::string_view ReportStyleSheet() { return kStyle; }

absl::StatusOr<std::string> RenderReport(const v1::JobResult& result,
                                         const ReportOptions& options) {
  FENESTRA_ASSIGN_OR_RETURN(data, GatherReportData(result, options.source, options.sensor));
  return Page(data);
}

absl::Status WriteReport(const v1::JobResult& result, const ReportOptions& options,
                         const std::string& path) {
  FENESTRA_ASSIGN_OR_RETURN(html, RenderReport(result, options));
  return WriteFileAtomically(path, [&](std::ostream& out) {
    out << html;
    return absl::OkStatus();
  });
}

}  // namespace fenestra
