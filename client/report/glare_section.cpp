// The glare at the scene's view points at the best design (JobResult.best_glare): each view's
// figures in a table and, where the result holds its DGP per time step, a map of it by day
// and hour coloured by comfort class.
#include <fmt/format.h>

#include <array>
#include <cmath>
#include <string>
#include <vector>

#include "client/report/sections.h"
#include "client/report/svg.h"

namespace fenestra {
namespace {

// The comfort classes of DGP: their upper limits (the last class, intolerable, has none),
// names, and colours from light to dark (so they print in grey in the same order).
constexpr std::array<double, 3> kGlareLimits = {0.35, 0.40, 0.45};
constexpr std::array<const char*, 4> kGlareClasses = {"imperceptible", "perceptible", "disturbing",
                                                      "intolerable"};
constexpr std::array<const char*, 4> kGlareColors = {"#e5f5e0", "#fee391", "#fe9929", "#b2182b"};

int GlareClass(double dgp) {
  int c = 0;
  while (c < 3 && dgp >= kGlareLimits[c]) ++c;
  return c;
}

std::string GlareTable(const v1::JobResult& result) {
  std::vector<std::vector<std::string>> rows;
  for (const v1::ViewGlare& g : result.best_glare()) {
    std::string hours;
    for (int i = 0; i < g.class_hours_size(); ++i) {
      hours += (i > 0 ? " / " : "") + std::to_string(g.class_hours(i));
    }
    rows.push_back({g.view(), WithError(g.autonomy().value(), g.autonomy().standard_error()),
                    WithError(g.mean_dgp().value(), g.mean_dgp().standard_error(), 3),
                    fmt::format("{} ({:.3f})", g.en17037(), g.dgp_95()), hours,
                    std::to_string(g.sunlit_hours())});
  }
  return HtmlTable("glare-table",
                   {"view", "glare autonomy ± SE [%]", "mean DGP ± SE", "EN 17037 (DGP at 95%)",
                    "hours imperceptible / perceptible / disturbing / intolerable",
                    "hours with the sun in view"},
                   rows) +
         Note(
             "Over the analysed hours, the blind in place: per hour the daylight glare "
             "probability with the sun as glare source where its beam reaches the eye; glare "
             "autonomy is the share of hours below 0.40.");
}

// Why the DGP of `g` cannot be mapped; empty when it can.
std::string Unmapped(const ReportData& data, const v1::ViewGlare& g) {
  if (!data.result.has_best_hourly()) return "the result holds no hourly time steps to place it";
  const int steps = data.result.best_hourly().month_size();
  if (g.dgp_size() != steps) {
    return fmt::format("it holds {} values for the {} time steps of the hourly illuminance",
                       g.dgp_size(), steps);
  }
  for (const float dgp : g.dgp()) {
    if (!std::isfinite(dgp) || dgp < 0) return "its values must be finite and >= 0";
  }
  return "";
}

// The map of the DGP at one view (the `index`th of best_glare), with the analysed hours of
// each class in its caption.
std::string GlareMap(const ReportData& data, const v1::ViewGlare& g, int index) {
  const std::vector<double> dgp(g.dgp().begin(), g.dgp().end());
  const bool all_hours = data.result.job().metrics().all_hours();
  std::array<int, 4> hours = {0, 0, 0, 0};
  int analysed = 0;
  for (size_t j = 0; j < dgp.size(); ++j) {
    if (!all_hours && !data.occupied[j]) continue;
    ++analysed;
    ++hours[GlareClass(dgp[j])];
  }
  std::vector<std::pair<std::string, std::string>> legend;
  for (int c = 0; c < 4; ++c) {
    legend.push_back({fmt::format("swatch:{}", kGlareColors[c]), kGlareClasses[c]});
  }
  const std::string caption = fmt::format(
      "Daylight glare probability at {} by day and hour, best design, the blind in place (dark "
      "hours at 0.159, the DGP of no light). Of its {} analysed hours: {} imperceptible (DGP "
      "below {:.2f}), {} perceptible (below {:.2f}), {} disturbing (below {:.2f}), {} "
      "intolerable.",
      g.view(), analysed, hours[0], kGlareLimits[0], hours[1], kGlareLimits[1], hours[2],
      kGlareLimits[2], hours[3]);
  return DayHourMap(
      data, dgp, fmt::format("plot-glare-map-{}", index),
      "Daylight glare probability at " + g.view() + " by day and hour, coloured by comfort class",
      [](double value) { return std::string_view(kGlareColors[GlareClass(value)]); },
      std::move(legend), caption);
}

}  // namespace

std::string GlareSection(const ReportData& data) {
  const v1::JobResult& r = data.result;
  if (r.best_glare_size() == 0) return "";
  std::string maps;
  for (int i = 0; i < r.best_glare_size(); ++i) {
    const v1::ViewGlare& g = r.best_glare(i);
    if (g.dgp_size() == 0) continue;
    const std::string why = Unmapped(data, g);
    maps += why.empty() ? GlareMap(data, g, i)
                        : NotRecorded("The DGP by day and hour at " + g.view(), why);
  }
  std::string body = GlareTable(r);
  if (!maps.empty()) body += "<h3>The daylight glare probability by day and hour</h3>\n" + maps;
  return Section("glare", "Glare at the view points", body);
}

}  // namespace fenestra
