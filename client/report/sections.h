#pragma once

// The report's sections, each an HTML fragment (a <section> with its heading, figures and
// tables) made from the gathered data; html_report.cpp puts them on the page. Figures carry
// element ids ("plot-...") and the class "figure", so tests and readers can find them.
#include <string>
#include <string_view>
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
std::string BlindSection(const ReportData& data);
std::string SettingsSection(const ReportData& data);

// Helpers the sections share.

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
