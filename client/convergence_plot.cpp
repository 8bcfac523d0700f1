#include "client/convergence_plot.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <ostream>

#include "client/report/svg.h"
#include "core/common/atomic_file.h"

namespace fenestra {
namespace {

constexpr double kWidth = 760, kHeight = 480;
constexpr double kLeft = 80, kRight = 230, kTop = 40, kBottom = 60;  // margins [px]
constexpr const char* kColors[] = {"#1f77b4", "#d62728", "#2ca02c", "#9467bd", "#ff7f0e"};

bool Drawable(double x, double y) { return x > 0 && y > 0 && std::isfinite(x) && std::isfinite(y); }

// Whole decades [lo, hi] (log10) around the values, at least one decade wide.
struct Decades {
  int lo = 0, hi = 1;
  Decades(double min, double max)
      : lo(static_cast<int>(std::floor(std::log10(min)))),
        hi(static_cast<int>(std::ceil(std::log10(max)))) {
    if (hi <= lo) hi = lo + 1;
  }
};

// "0.01", "1", "1000": a power of ten as plain decimals; in percent when asked.
std::string DecadeLabel(int exponent, bool percent) {
  const int e = percent ? exponent + 2 : exponent;
  const std::string number = e >= 0 ? fmt::format("{:.0f}", std::pow(10.0, e))
                                    : fmt::format("{:.{}f}", std::pow(10.0, e), -e);
  return percent ? number + "%" : number;
}

class Frame {
 public:
  Frame(Decades x, Decades y) : x_(x), y_(y) {}
  double X(double x) const {
    return kLeft + (std::log10(x) - x_.lo) / (x_.hi - x_.lo) * (kWidth - kLeft - kRight);
  }
  double Y(double y) const {
    return kTop + (y_.hi - std::log10(y)) / (y_.hi - y_.lo) * (kHeight - kTop - kBottom);
  }
  const Decades& x() const { return x_; }
  const Decades& y() const { return y_; }

 private:
  Decades x_, y_;
};

// Grid lines at 1..9 x each decade, labels at the decades, the axes and their titles.
void WriteAxes(std::ostream& out, const Frame& f, const LogLogPlot& plot) {
  const double x0 = kLeft, x1 = kWidth - kRight, y0 = kHeight - kBottom, y1 = kTop;
  out << "<g class=\"grid\" stroke=\"#dddddd\" stroke-width=\"1\">\n";
  for (int e = f.x().lo; e < f.x().hi; ++e) {
    for (int m = 1; m < 10; ++m) {
      const double x = f.X(m * std::pow(10.0, e));
      out << fmt::format("<line x1=\"{:.1f}\" y1=\"{}\" x2=\"{:.1f}\" y2=\"{}\"/>\n", x, y0, x, y1);
    }
  }
  for (int e = f.y().lo; e < f.y().hi; ++e) {
    for (int m = 1; m < 10; ++m) {
      const double y = f.Y(m * std::pow(10.0, e));
      out << fmt::format("<line x1=\"{}\" y1=\"{:.1f}\" x2=\"{}\" y2=\"{:.1f}\"/>\n", x0, y, x1, y);
    }
  }
  out << "</g>\n<g class=\"axes\" stroke=\"#000000\" stroke-width=\"1\">\n";
  out << fmt::format("<line x1=\"{}\" y1=\"{}\" x2=\"{}\" y2=\"{}\"/>\n", x0, y0, x1, y0);
  out << fmt::format("<line x1=\"{}\" y1=\"{}\" x2=\"{}\" y2=\"{}\"/>\n", x0, y0, x0, y1);
  out << "</g>\n<g class=\"ticks\" font-family=\"sans-serif\" font-size=\"12\">\n";
  for (int e = f.x().lo; e <= f.x().hi; ++e) {
    out << fmt::format("<text x=\"{:.1f}\" y=\"{}\" text-anchor=\"middle\">{}</text>\n",
                       f.X(std::pow(10.0, e)), y0 + 18, DecadeLabel(e, false));
  }
  for (int e = f.y().lo; e <= f.y().hi; ++e) {
    out << fmt::format("<text x=\"{}\" y=\"{:.1f}\" text-anchor=\"end\">{}</text>\n", x0 - 6,
                       f.Y(std::pow(10.0, e)) + 4, DecadeLabel(e, plot.y_in_percent));
  }
  out << "</g>\n";
  out << fmt::format(
      "<text class=\"x-label\" x=\"{:.1f}\" y=\"{}\" text-anchor=\"middle\" "
      "font-family=\"sans-serif\" font-size=\"14\">{}</text>\n",
      (x0 + x1) / 2, kHeight - 16, EscapeXml(plot.x_label));
  out << fmt::format(
      "<text class=\"y-label\" x=\"20\" y=\"{:.1f}\" text-anchor=\"middle\" "
      "font-family=\"sans-serif\" font-size=\"14\" transform=\"rotate(-90 20 {:.1f})\">{}</text>\n",
      (y0 + y1) / 2, (y0 + y1) / 2, EscapeXml(plot.y_label));
}

void WriteSeries(std::ostream& out, const Frame& f, const PlotSeries& s, const char* color,
                 int index) {
  std::string points;
  for (size_t k = 0; k < s.x.size() && k < s.y.size(); ++k) {
    if (Drawable(s.x[k], s.y[k])) points += fmt::format("{:.1f},{:.1f} ", f.X(s.x[k]), f.Y(s.y[k]));
  }
  out << fmt::format("<g class=\"series\" data-name=\"{}\">\n", EscapeXml(s.name));
  out << fmt::format(
      "<polyline class=\"series-line\" fill=\"none\" stroke=\"{}\" stroke-width=\"2\" "
      "points=\"{}\"/>\n",
      color, points);
  for (size_t k = 0; k < s.x.size() && k < s.y.size(); ++k) {
    if (!Drawable(s.x[k], s.y[k])) continue;
    out << fmt::format("<circle cx=\"{:.1f}\" cy=\"{:.1f}\" r=\"3.5\" fill=\"{}\"/>\n", f.X(s.x[k]),
                       f.Y(s.y[k]), color);
  }
  out << "</g>\n";
  const double ly = kTop + 10 + 22 * index, lx = kWidth - kRight + 16;
  out << fmt::format(
      "<line class=\"legend\" x1=\"{}\" y1=\"{}\" x2=\"{}\" y2=\"{}\" stroke=\"{}\" "
      "stroke-width=\"2\"/>\n<text x=\"{}\" y=\"{}\" font-family=\"sans-serif\" "
      "font-size=\"12\">{}</text>\n",
      lx, ly, lx + 24, ly, color, lx + 30, ly + 4, EscapeXml(s.name));
}

}  // namespace

absl::Status WriteLogLogSvg(const std::string& path, const LogLogPlot& plot) {
  // The ranges: every point, and the 1/sqrt(x) line over the x range
  double x_min = std::numeric_limits<double>::infinity(), x_max = 0;
  double y_min = std::numeric_limits<double>::infinity(), y_max = 0;
  for (const PlotSeries& s : plot.series) {
    for (size_t k = 0; k < s.x.size() && k < s.y.size(); ++k) {
      if (!Drawable(s.x[k], s.y[k])) continue;
      x_min = std::min(x_min, s.x[k]), x_max = std::max(x_max, s.x[k]);
      y_min = std::min(y_min, s.y[k]), y_max = std::max(y_max, s.y[k]);
    }
  }
  if (x_max == 0) return absl::InvalidArgumentError("the plot has no point to draw");
  double line_x = 0, line_y = 0;  // the first point of the 1/sqrt(x) line's series
  if (plot.sqrt_line_series >= 0 && plot.sqrt_line_series < static_cast<int>(plot.series.size())) {
    const PlotSeries& s = plot.series[plot.sqrt_line_series];
    for (size_t k = 0; k < s.x.size() && k < s.y.size() && line_x == 0; ++k) {
      if (Drawable(s.x[k], s.y[k])) line_x = s.x[k], line_y = s.y[k];
    }
  }
  const auto on_line = [&](double x) { return line_y * std::sqrt(line_x / x); };
  if (line_x > 0) {
    y_min = std::min(y_min, on_line(x_max));
    y_max = std::max(y_max, on_line(x_min));
  }
  const Frame frame(Decades(x_min, x_max), Decades(y_min, y_max));

  return WriteFileAtomically(path, [&](std::ostream& out) {
    out << fmt::format(
        "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n<svg xmlns=\"http://www.w3.org/2000/svg\" "
        "width=\"{0}\" height=\"{1}\" viewBox=\"0 0 {0} {1}\">\n<title>{2}</title>\n"
        "<rect width=\"{0}\" height=\"{1}\" fill=\"#ffffff\"/>\n"
        "<text class=\"title\" x=\"{3}\" y=\"24\" font-family=\"sans-serif\" font-size=\"15\">"
        "{2}</text>\n",
        kWidth, kHeight, EscapeXml(plot.title), kLeft);
    WriteAxes(out, frame, plot);
    for (size_t k = 0; k < plot.series.size(); ++k) {
      WriteSeries(out, frame, plot.series[k], kColors[k % std::size(kColors)], static_cast<int>(k));
    }
    if (line_x > 0) {
      const double lx = kWidth - kRight + 16, ly = kTop + 10 + 22 * plot.series.size();
      out << fmt::format(
          "<line class=\"sqrt-line\" x1=\"{:.1f}\" y1=\"{:.1f}\" x2=\"{:.1f}\" y2=\"{:.1f}\" "
          "stroke=\"#555555\" stroke-width=\"1.5\" stroke-dasharray=\"6 4\"/>\n"
          "<line class=\"legend\" x1=\"{}\" y1=\"{}\" x2=\"{}\" y2=\"{}\" stroke=\"#555555\" "
          "stroke-width=\"1.5\" stroke-dasharray=\"6 4\"/>\n<text x=\"{}\" y=\"{}\" "
          "font-family=\"sans-serif\" font-size=\"12\">&#8733; 1/&#8730;t</text>\n",
          frame.X(x_min), frame.Y(on_line(x_min)), frame.X(x_max), frame.Y(on_line(x_max)), lx, ly,
          lx + 24, ly, lx + 30, ly + 4);
    }
    out << "</svg>\n";
    return absl::OkStatus();
  });
}

}  // namespace fenestra
