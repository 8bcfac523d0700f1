#pragma once

// The report's sections, each an HTML fragment (a <section> with its heading, figures and
// tables) made from the gathered data; html_report.cpp puts them on the page. Figures carry
// element ids ("plot-...") and the class "figure", so tests and readers can find them.
#include <functional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "client/report/report_data.h"

namespace fenestra {

std::string SummarySection(const ReportData& data);
std::string SearchSection(const ReportData& data);
// Empty for a result without a Pareto search.
std::string ParetoSection(const ReportData& data);
std::string DesignSpaceSection(const ReportData& data);
std::string FloorPlanSection(const ReportData& data);
std::string TemporalMapSection(const ReportData& data);
// Empty for a result without glare at view points (JobResult.best_glare).
std::string GlareSection(const ReportData& data);
std::string BlindSection(const ReportData& data);
std::string SettingsSection(const ReportData& data);

// Helpers the sections share.

// The blind at `design` in section, to scale, as figure `id` (blind_section.cpp); `what` names
// the design in its title and caption, e.g. "the best design".
std::string BlindSectionFigure(const Scene& scene, const BlindDesign& design, std::string_view id,
                               std::string_view what);

// A temporal map (temporal_map.cpp) of one value per time step of the result's best_hourly
// (`values`, in its columns' order): every day (x) by hour (y), each cell coloured by
// color_of(the mean of its steps), the occupied hours outlined, `legend` (Legend's entries)
// with the occupancy after it, and `caption`. The result must hold best_hourly.
std::string DayHourMap(const ReportData& data, const std::vector<double>& values,
                       std::string_view id, std::string_view title,
                       const std::function<std::string_view(double)>& color_of,
                       std::vector<std::pair<std::string, std::string>> legend,
                       std::string_view caption);

// <p class="not-recorded">: `what` is not recorded, and why.
std::string NotRecorded(std::string_view what, std::string_view why);

// "50.43 ± 1.72" with `decimals` decimals.
std::string WithError(double value, double standard_error, int decimals = 2);

// A table: a header row and rows of cells (text, escaped here); `id` may be empty. With
// `align_numbers`, cells that start with a number are aligned right.
std::string HtmlTable(std::string_view id, const std::vector<std::string>& header,
                      const std::vector<std::vector<std::string>>& rows, bool align_numbers = true);

// <section id="id"><h2>heading</h2> ... </section> around `body` (already HTML).
std::string Section(std::string_view id, std::string_view heading, std::string_view body);

// A paragraph of text (escaped here) with the class "note".
std::string Note(std::string_view text);

}  // namespace fenestra
