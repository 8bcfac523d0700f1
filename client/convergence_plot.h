#pragma once

// A log-log line plot of errors against time as a self-contained SVG file (no scripts, fonts
// or links to fetch): decade axes with labels, one polyline with markers per series, a legend,
// and a dashed 1/sqrt(x) line through a chosen series' first point.
#include <string>
#include <vector>

#include "absl/status/status.h"

namespace fenestra {

struct PlotSeries {
  std::string name;
  std::vector<double> x, y;  // points with a value <= 0 or not finite are left out
};

struct LogLogPlot {
  std::string title, x_label, y_label;
  std::vector<PlotSeries> series;
  int sqrt_line_series = 0;  // the series whose first point the 1/sqrt(x) line passes; -1 none
  bool y_in_percent = true;  // tick labels of y as percentages
};

// Writes `plot` to `path` through a temporary file. InvalidArgument when no series has a
// point to draw.
absl::Status WriteLogLogSvg(const std::string& path, const LogLogPlot& plot);

}  // namespace fenestra
