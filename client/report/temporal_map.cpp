// The temporal maps, every day of the year (x) by hour of the day (y), the occupied hours
// outlined: the best design's illuminance at one sensor, coloured by the UDI bands; where the
// result holds them, the direct sun at the most sunlit sensor and the hours an operated
// blind is in place; and such a map for other sections (DayHourMap).
#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cmath>

#include "client/report/sections.h"
#include "client/report/svg.h"

namespace fenestra {
namespace {

constexpr double kDayWidth = 2, kHourHeight = 11;  // [px]
constexpr double kMapLeft = 64, kMapTop = 20, kMapRight = 20, kMapBottom = 84;

enum Band { kDark, kBelow, kInRange, kAbove };
constexpr std::array<const char*, 4> kBandColors = {"#eeeeee", "#56b4e9", "#009e73", "#d55e00"};
constexpr std::array<const char*, 12> kMonths = {"Jan", "Feb", "Mar", "Apr", "May", "Jun",
                                                 "Jul", "Aug", "Sep", "Oct", "Nov", "Dec"};

// A per-step quantity per day and hour of the day (the mean of the steps in it, 0 where
// none), and where each month begins.
struct DayHourGrid {
  int days = 0;
  std::vector<double> value;        // days x 24, day-major
  std::vector<int> month_start;     // day index where each month present begins
  std::vector<int> month_of_start;  // its month, 1-12
};

// The grid of value_of(step).
template <typename ValueOf>
DayHourGrid GridOf(const v1::HourlyIlluminance& h, ValueOf value_of) {
  const int steps = h.month_size();
  std::vector<int> day_of(steps);
  DayHourGrid grid;
  for (int j = 0; j < steps; ++j) {
    if (j == 0 || h.day(j) != h.day(j - 1) || h.month(j) != h.month(j - 1)) {
      if (j == 0 || h.month(j) != h.month(j - 1)) {
        grid.month_start.push_back(grid.days);
        grid.month_of_start.push_back(h.month(j));
      }
      ++grid.days;
    }
    day_of[j] = grid.days - 1;
  }
  std::vector<double> sum(static_cast<size_t>(grid.days) * 24, 0);
  std::vector<int> count(sum.size(), 0);
  for (int j = 0; j < steps; ++j) {
    const int hour = std::clamp(static_cast<int>(std::floor(h.hour(j))), 0, 23);
    const size_t cell = static_cast<size_t>(day_of[j]) * 24 + hour;
    sum[cell] += value_of(j);
    ++count[cell];
  }
  grid.value.resize(sum.size());
  for (size_t c = 0; c < sum.size(); ++c) grid.value[c] = count[c] > 0 ? sum[c] / count[c] : 0;
  return grid;
}

Band BandOf(double lux, const v1::MetricSettings& m) {
  if (lux <= 0) return kDark;
  if (lux < m.udi_lower_lux()) return kBelow;
  return lux <= m.udi_upper_lux() ? kInRange : kAbove;
}

// The cells, coloured by color_of(value), as one rectangle per run of days of the same
// colour within each hour.
template <typename ColorOf>
void DrawCells(Svg& svg, const DayHourGrid& grid, ColorOf color_of) {
  svg.BeginGroup("map-cells");
  for (int hour = 0; hour < 24; ++hour) {
    int start = 0;
    for (int day = 1; day <= grid.days; ++day) {
      const std::string_view color = color_of(grid.value[static_cast<size_t>(start) * 24 + hour]);
      if (day < grid.days && color_of(grid.value[static_cast<size_t>(day) * 24 + hour]) == color) {
        continue;
      }
      svg.Rect(kMapLeft + start * kDayWidth, kMapTop + hour * kHourHeight,
               (day - start) * kDayWidth, kHourHeight, "map-cell", color);
      start = day;
    }
  }
  svg.EndGroup();
}

void DrawAxes(Svg& svg, const DayHourGrid& grid) {
  const double width = grid.days * kDayWidth, bottom = kMapTop + 24 * kHourHeight;
  svg.BeginGroup("axes");
  svg.Rect(kMapLeft, kMapTop, width, 24 * kHourHeight, "frame");
  for (size_t i = 0; i < grid.month_start.size(); ++i) {
    const double x = kMapLeft + grid.month_start[i] * kDayWidth;
    const double next = i + 1 < grid.month_start.size()
                            ? kMapLeft + grid.month_start[i + 1] * kDayWidth
                            : kMapLeft + width;
    svg.Line(x, bottom, x, bottom + 6, "tick");
    svg.Text((x + next) / 2, bottom + 17, kMonths[grid.month_of_start[i] - 1], "tick-label",
             Anchor::kMiddle);
  }
  for (int hour = 0; hour <= 24; hour += 3) {
    const double y = kMapTop + hour * kHourHeight;
    svg.Line(kMapLeft - 5, y, kMapLeft, y, "tick");
    svg.Text(kMapLeft - 8, y + 4, fmt::format("{}", hour), "tick-label", Anchor::kEnd);
  }
  svg.Text(kMapLeft + width / 2, bottom + 36, "day of the year [month]", "axis-label",
           Anchor::kMiddle);
  svg.Text(kMapLeft - 40, kMapTop + 12 * kHourHeight, "local standard time [h]", "axis-label",
           Anchor::kMiddle, -90);
  svg.EndGroup();
}

// The occupied hours: one band, or two when the schedule wraps past midnight.
void DrawOccupancy(Svg& svg, const DayHourGrid& grid, const v1::MetricSettings& m) {
  const double width = grid.days * kDayWidth;
  const double start = m.occupied_start_h(), end = m.occupied_end_h();
  auto band = [&](double from, double to) {
    svg.Rect(kMapLeft, kMapTop + from * kHourHeight, width, (to - from) * kHourHeight, "occupancy");
  };
  svg.BeginGroup("occupied-hours");
  if (start < end) {
    band(start, end);
  } else {
    band(start, 24);
    band(0, end);
  }
  svg.EndGroup();
}

using LegendEntries = std::vector<std::pair<std::string, std::string>>;

// One map's figure: its cells coloured by color_of(value), the occupied hours, the axes, the
// legend (`legend`, then the occupancy) and the caption.
template <typename ColorOf>
std::string MapFigure(const ReportData& data, const DayHourGrid& grid, std::string_view id,
                      std::string_view title, ColorOf color_of, LegendEntries legend,
                      std::string_view caption) {
  const v1::MetricSettings& m = data.result.job().metrics();
  Svg svg(id, "map-plot", kMapLeft + grid.days * kDayWidth + kMapRight,
          kMapTop + 24 * kHourHeight + kMapBottom, title);
  DrawCells(svg, grid, color_of);
  DrawOccupancy(svg, grid, m);
  DrawAxes(svg, grid);
  legend.push_back({"outline:occupancy",
                    fmt::format("occupied {:g}–{:g} h", m.occupied_start_h(), m.occupied_end_h())});
  Legend(svg, kMapLeft, kMapTop + 24 * kHourHeight + 66, legend);
  return "<figure class=\"plot wide\">" + svg.Finish() + "<figcaption>" + EscapeXml(caption) +
         "</figcaption></figure>\n";
}

// Occupied hours below, in and above the range.
std::array<int, 4> OccupiedBands(const ReportData& data, int sensor) {
  const v1::HourlyIlluminance& h = data.result.best_hourly();
  const int steps = h.month_size();
  std::array<int, 4> counts = {0, 0, 0, 0};
  for (int j = 0; j < steps; ++j) {
    if (data.occupied[j])
      ++counts[BandOf(h.illuminance_lux(sensor * steps + j), data.result.job().metrics())];
  }
  return counts;
}

std::string IlluminanceMap(const ReportData& data) {
  const v1::MetricSettings& m = data.result.job().metrics();
  const v1::HourlyIlluminance& h = data.result.best_hourly();
  const int sensor = data.map_sensor, steps = h.month_size();
  const DayHourGrid grid = GridOf(h, [&](int j) { return h.illuminance_lux(sensor * steps + j); });
  const std::string name = data.scene->sensors[sensor].name;
  const std::array<int, 4> bands = OccupiedBands(data, sensor);
  const int occupied = bands[0] + bands[1] + bands[2] + bands[3];
  const v1::Estimate& udi = data.result.best_metrics().sensor_udi(sensor);
  const bool worst = sensor == WorstSensorByUdi(data.result.best_metrics());
  const std::string caption = fmt::format(
      "Illuminance at {} ({}UDI {}), best design. Of its {} occupied hours: {} in range, {} below "
      "(of which {} without daylight), {} above.",
      name, worst ? "the sensor with the lowest UDI, " : "",
      WithError(udi.value(), udi.standard_error(), 1) + " %", occupied, bands[kInRange],
      bands[kBelow] + bands[kDark], bands[kDark], bands[kAbove]);
  return MapFigure(
      data, grid, "plot-temporal-map",
      "Illuminance at " + name + " by day and hour, coloured by the UDI bands",
      [&](double lux) { return std::string_view(kBandColors[BandOf(lux, m)]); },
      {{fmt::format("swatch:{}", kBandColors[kDark]), "no daylight"},
       {fmt::format("swatch:{}", kBandColors[kBelow]), fmt::format("< {:g} lx", m.udi_lower_lux())},
       {fmt::format("swatch:{}", kBandColors[kInRange]),
        fmt::format("{:g}–{:g} lx", m.udi_lower_lux(), m.udi_upper_lux())},
       {fmt::format("swatch:{}", kBandColors[kAbove]),
        fmt::format("> {:g} lx", m.udi_upper_lux())}},
      caption);
}

// The direct sun at the most sunlit sensor: none, then up to a tenth, a third and all of
// ASE's threshold, and above it.
constexpr std::array<const char*, 5> kSunColors = {"#eeeeee", "#fed976", "#fd8d3c", "#e31a1c",
                                                   "#800026"};
constexpr std::array<double, 3> kSunBands = {0.1, 0.3, 1};  // of the threshold

bool Analysed(const ReportData& data, int step) {
  return data.result.job().metrics().all_hours() || data.occupied[step];
}

std::string DirectSunMap(const ReportData& data) {
  const v1::HourlyIlluminance& h = data.result.best_hourly();
  const int sensors = h.sensors_size(), steps = h.month_size();
  const double threshold = data.ase_threshold_lux;
  std::vector<double> most(steps, 0);
  int analysed = 0, above = 0;
  for (int j = 0; j < steps; ++j) {
    for (int i = 0; i < sensors; ++i)
      most[j] = std::max<double>(most[j], h.direct_sun_lux(i * steps + j));
    if (!Analysed(data, j)) continue;
    ++analysed;
    above += most[j] > threshold;
  }
  const auto color_of = [&](double lux) {
    if (lux <= 0) return std::string_view(kSunColors[0]);
    int band = 1;
    while (band < 4 && lux > kSunBands[band - 1] * threshold) ++band;
    return std::string_view(kSunColors[band]);
  };
  const std::string caption = fmt::format(
      "Direct sun at the most sunlit sensor, by day and hour, best design{}. In {} of the {} "
      "analysed hours a sensor gets more than {:g} lx of it (ASE's threshold).",
      data.operated_blind ? " as operated (the blind in place or retracted by its rule)" : "",
      above, analysed, threshold);
  const double tenth = kSunBands[0] * threshold, third = kSunBands[1] * threshold;
  return MapFigure(
      data, GridOf(h, [&](int j) { return most[j]; }), "plot-direct-sun-map",
      "Direct sun at the most sunlit sensor by day and hour", color_of,
      {{fmt::format("swatch:{}", kSunColors[0]), "none"},
       {fmt::format("swatch:{}", kSunColors[1]), fmt::format("≤ {:g} lx", tenth)},
       {fmt::format("swatch:{}", kSunColors[2]), fmt::format("{:g}–{:g} lx", tenth, third)},
       {fmt::format("swatch:{}", kSunColors[3]), fmt::format("{:g}–{:g} lx", third, threshold)},
       {fmt::format("swatch:{}", kSunColors[4]), fmt::format("> {:g} lx", threshold)}},
      caption);
}

constexpr char kInPlaceColor[] = "#6e6e6e", kRetractedColor[] = "#d4e9f7";

std::string BlindMap(const ReportData& data) {
  const v1::HourlyIlluminance& h = data.result.best_hourly();
  int analysed = 0, in_place = 0, in_place_all = 0;
  for (int j = 0; j < h.month_size(); ++j) {
    in_place_all += h.blind_in_place(j);
    if (!Analysed(data, j)) continue;
    ++analysed;
    in_place += h.blind_in_place(j);
  }
  const DayHourGrid grid = GridOf(h, [&](int j) { return h.blind_in_place(j) ? 1.0 : 0.0; });
  const std::string caption = fmt::format(
      "When the blind is in place, by day and hour, best design: in {} of the {} analysed hours "
      "({:.1f} %), {} hours of the year in all; retracted, the window bare, otherwise.",
      in_place, analysed, analysed > 0 ? 100.0 * in_place / analysed : 0.0, in_place_all);
  return MapFigure(
      data, grid, "plot-blind-map", "When the blind is in place, by day and hour",
      [](double share) { return std::string_view(share >= 0.5 ? kInPlaceColor : kRetractedColor); },
      {{fmt::format("swatch:{}", kInPlaceColor), "blind in place"},
       {fmt::format("swatch:{}", kRetractedColor), "retracted (window bare)"}},
      caption);
}

}  // namespace

std::string DayHourMap(const ReportData& data, const std::vector<double>& values,
                       std::string_view id, std::string_view title,
                       const std::function<std::string_view(double)>& color_of,
                       std::vector<std::pair<std::string, std::string>> legend,
                       std::string_view caption) {
  const DayHourGrid grid = GridOf(data.result.best_hourly(), [&](int j) { return values[j]; });
  return MapFigure(data, grid, id, title, color_of, std::move(legend), caption);
}

std::string TemporalMapSection(const ReportData& data) {
  const std::string heading = "Temporal maps";
  if (data.map_sensor < 0) {
    return Section("temporal-map", heading,
                   NotRecorded("Hourly illuminance",
                               "the result does not hold it (the search was cancelled, the job had "
                               "too many sensors, or the result predates it)"));
  }
  const v1::HourlyIlluminance& h = data.result.best_hourly();
  std::string body = IlluminanceMap(data);
  if (h.direct_sun_lux_size() > 0 && h.sensors_size() > 0) body += DirectSunMap(data);
  if (std::find(h.blind_in_place().begin(), h.blind_in_place().end(), false) !=
      h.blind_in_place().end()) {
    body += BlindMap(data);
  }
  return Section("temporal-map", heading, body);
}

}  // namespace fenestra
