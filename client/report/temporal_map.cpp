// The temporal map: the best design's illuminance at one sensor for every day of the year
// (x) and hour of the day (y), coloured by the UDI bands, the occupied hours outlined.
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

// The sensor's illuminance per day and hour of the day (the mean of the steps in it), and
// where each month begins.
struct DayHourGrid {
  int days = 0;
  std::vector<double> lux;          // days x 24, day-major
  std::vector<int> month_start;     // day index where each month present begins
  std::vector<int> month_of_start;  // its month, 1-12
};

DayHourGrid GridOf(const v1::HourlyIlluminance& h, int sensor) {
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
    sum[cell] += h.illuminance_lux(sensor * steps + j);
    ++count[cell];
  }
  grid.lux.resize(sum.size());
  for (size_t c = 0; c < sum.size(); ++c) grid.lux[c] = count[c] > 0 ? sum[c] / count[c] : 0;
  return grid;
}

Band BandOf(double lux, const v1::MetricSettings& m) {
  if (lux <= 0) return kDark;
  if (lux < m.udi_lower_lux()) return kBelow;
  return lux <= m.udi_upper_lux() ? kInRange : kAbove;
}

// The cells, as one rectangle per run of days in the same band within each hour.
void DrawCells(Svg& svg, const DayHourGrid& grid, const v1::MetricSettings& m) {
  svg.BeginGroup("map-cells");
  for (int hour = 0; hour < 24; ++hour) {
    int start = 0;
    for (int day = 1; day <= grid.days; ++day) {
      const Band band = BandOf(grid.lux[static_cast<size_t>(start) * 24 + hour], m);
      if (day < grid.days && BandOf(grid.lux[static_cast<size_t>(day) * 24 + hour], m) == band) {
        continue;
      }
      svg.Rect(kMapLeft + start * kDayWidth, kMapTop + hour * kHourHeight,
               (day - start) * kDayWidth, kHourHeight, "map-cell", kBandColors[band]);
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

}  // namespace

std::string TemporalMapSection(const ReportData& data) {
  const std::string heading = "Temporal map";
  if (data.map_sensor < 0) {
    return Section("temporal-map", heading,
                   NotRecorded("Hourly illuminance",
                               "the result does not hold it (the search was cancelled, the job had "
                               "too many sensors, or the result predates it)"));
  }
  const v1::MetricSettings& m = data.result.job().metrics();
  const int sensor = data.map_sensor;
  const DayHourGrid grid = GridOf(data.result.best_hourly(), sensor);
  const double width = grid.days * kDayWidth;
  const std::string name = data.scene->sensors[sensor].name;
  Svg svg("plot-temporal-map", "map-plot", kMapLeft + width + kMapRight,
          kMapTop + 24 * kHourHeight + kMapBottom,
          "Illuminance at " + name + " by day and hour, coloured by the UDI bands");
  DrawCells(svg, grid, m);
  DrawOccupancy(svg, grid, m);
  DrawAxes(svg, grid);
  const double legend_y = kMapTop + 24 * kHourHeight + 66;
  Legend(
      svg, kMapLeft, legend_y,
      {{fmt::format("swatch:{}", kBandColors[kDark]), "no daylight"},
       {fmt::format("swatch:{}", kBandColors[kBelow]), fmt::format("< {:g} lx", m.udi_lower_lux())},
       {fmt::format("swatch:{}", kBandColors[kInRange]),
        fmt::format("{:g}–{:g} lx", m.udi_lower_lux(), m.udi_upper_lux())},
       {fmt::format("swatch:{}", kBandColors[kAbove]), fmt::format("> {:g} lx", m.udi_upper_lux())},
       {"outline:occupancy",
        fmt::format("occupied {:g}–{:g} h", m.occupied_start_h(), m.occupied_end_h())}});

  const std::array<int, 4> bands = OccupiedBands(data, sensor);
  const int occupied = bands[0] + bands[1] + bands[2] + bands[3];
  const v1::Estimate& udi = data.result.best_metrics().sensor_udi(sensor);
  const bool worst = sensor == WorstSensorByUdi(data.result.best_metrics());
  std::string caption = fmt::format(
      "Illuminance at {} ({}UDI {}), best design. Of its {} occupied hours: {} in range, {} below "
      "(of which {} without daylight), {} above.",
      name, worst ? "the sensor with the lowest UDI, " : "",
      WithError(udi.value(), udi.standard_error(), 1) + " %", occupied, bands[kInRange],
      bands[kBelow] + bands[kDark], bands[kDark], bands[kAbove]);
  return Section("temporal-map", heading,
                 "<figure class=\"plot wide\">" + svg.Finish() + "<figcaption>" +
                     EscapeXml(caption) + "</figcaption></figure>\n");
}

}  // namespace fenestra
