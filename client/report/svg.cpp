#include "client/report/svg.h"

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cmath>

namespace fenestra {

double TextWidth(std::string_view text, double font_px) {
  size_t characters = 0;
  for (const char c : text) characters += (static_cast<unsigned char>(c) & 0xc0) != 0x80;
  return 0.58 * font_px * static_cast<double>(characters);
}

std::string Px(double v) {
  std::string s = fmt::format("{:.2f}", v);
  while (s.back() == '0') s.pop_back();
  if (s.back() == '.') s.pop_back();
  return s == "-0" ? "0" : s;
}

namespace {

std::string ClassAttribute(std::string_view css_class) {
  return css_class.empty() ? "" : fmt::format(" class=\"{}\"", EscapeXml(css_class));
}

std::string FillAttribute(std::string_view fill) {
  return fill.empty() ? "" : fmt::format(" fill=\"{}\"", EscapeXml(fill));
}

std::string PointList(const Points& points) {
  std::string out;
  for (const auto& [x, y] : points)
    out += fmt::format("{}{},{}", out.empty() ? "" : " ", Px(x), Px(y));
  return out;
}

// Viridis at 9 evenly spaced stops (matplotlib's colormap, van der Walt & Smith 2015).
constexpr std::array<std::array<int, 3>, 9> kViridis = {{{0x44, 0x01, 0x54},
                                                         {0x47, 0x2d, 0x7b},
                                                         {0x3b, 0x52, 0x8b},
                                                         {0x2c, 0x72, 0x8e},
                                                         {0x21, 0x91, 0x8c},
                                                         {0x28, 0xae, 0x80},
                                                         {0x5e, 0xc9, 0x62},
                                                         {0xad, 0xdc, 0x30},
                                                         {0xfd, 0xe7, 0x25}}};

}  // namespace

std::vector<double> AxisTicks(const Axis& axis, int target) {
  std::vector<double> ticks = NiceTicks(axis.lo, axis.hi, target);
  if (axis.integer && ticks.size() > 1 && ticks[1] - ticks[0] < 1) {
    ticks.clear();
    for (double t = std::ceil(axis.lo); t <= axis.hi; ++t) ticks.push_back(t);
  }
  return ticks;
}

std::string EscapeXml(std::string_view text) {
  std::string out;
  out.reserve(text.size());
  for (const char c : text) {
    switch (c) {
      case '&':
        out += "&amp;";
        break;
      case '<':
        out += "&lt;";
        break;
      case '>':
        out += "&gt;";
        break;
      case '"':
        out += "&quot;";
        break;
      case '\'':
        out += "&#39;";
        break;
      default:
        // Control characters other than tab and newline are not allowed in XML
        if (static_cast<unsigned char>(c) < 0x20 && c != '\t' && c != '\n') {
          out += ' ';
        } else {
          out += c;
        }
    }
  }
  return out;
}

std::vector<double> NiceTicks(double lo, double hi, int target) {
  if (!(hi > lo) || !std::isfinite(lo) || !std::isfinite(hi)) return {lo};
  // The factor nearest (geometrically) to the raw step, as d3's tickIncrement chooses it
  const double raw = (hi - lo) / std::max(1, target);
  const double magnitude = std::pow(10.0, std::floor(std::log10(raw)));
  const double error = raw / magnitude;
  const double factor = error >= std::sqrt(50.0)   ? 10
                        : error >= std::sqrt(10.0) ? 5
                        : error >= std::sqrt(2.0)  ? 2
                                                   : 1;
  const double step = factor * magnitude;
  std::vector<double> ticks;
  for (double t = std::ceil(lo / step - 1e-9) * step; t <= hi + 1e-9 * step; t += step) {
    ticks.push_back(std::abs(t) < 1e-12 * step ? 0.0 : t);
  }
  return ticks;
}

std::string TickLabel(double value, double step) {
  const int decimals =
      step > 0 ? std::clamp(static_cast<int>(-std::floor(std::log10(step) + 1e-9)), 0, 6) : 0;
  const double rounded = std::abs(value) < 0.5 * std::pow(10.0, -decimals) ? 0.0 : value;
  return fmt::format("{:.{}f}", rounded, decimals);
}

void PaddedRange(const std::vector<double>& values, double fraction, double* lo, double* hi) {
  if (values.empty()) {
    *lo = 0;
    *hi = 1;
    return;
  }
  *lo = *std::min_element(values.begin(), values.end());
  *hi = *std::max_element(values.begin(), values.end());
  const double span = *hi - *lo;
  if (!(span > 0)) {
    *lo -= 0.5;
    *hi += 0.5;
    return;
  }
  *lo -= fraction * span;
  *hi += fraction * span;
}

std::string ViridisColor(double fraction) {
  const double f = std::clamp(std::isfinite(fraction) ? fraction : 0.0, 0.0, 1.0) * 8;
  const int i = std::min(7, static_cast<int>(f));
  const double t = f - i;
  int rgb[3];
  for (int c = 0; c < 3; ++c) {
    rgb[c] =
        static_cast<int>(std::lround(kViridis[i][c] + t * (kViridis[i + 1][c] - kViridis[i][c])));
  }
  return fmt::format("#{:02x}{:02x}{:02x}", rgb[0], rgb[1], rgb[2]);
}

std::vector<std::pair<double, std::string>> ViridisStops() {
  std::vector<std::pair<double, std::string>> stops;
  for (int i = 0; i <= 8; ++i) stops.emplace_back(i / 8.0, ViridisColor(i / 8.0));
  return stops;
}

Points ConvexHull(Points p) {
  std::sort(p.begin(), p.end());
  p.erase(std::unique(p.begin(), p.end(),
                      [](const auto& a, const auto& b) {
                        return std::abs(a.first - b.first) < 1e-12 &&
                               std::abs(a.second - b.second) < 1e-12;
                      }),
          p.end());
  if (p.size() < 3) return p;
  auto cross = [](const auto& o, const auto& a, const auto& b) {
    return (a.first - o.first) * (b.second - o.second) -
           (a.second - o.second) * (b.first - o.first);
  };
  Points hull(2 * p.size());
  size_t k = 0;
  for (size_t i = 0; i < p.size(); ++i) {
    while (k >= 2 && cross(hull[k - 2], hull[k - 1], p[i]) <= 0) --k;
    hull[k++] = p[i];
  }
  for (size_t i = p.size() - 1, t = k + 1; i > 0; --i) {
    while (k >= t && cross(hull[k - 2], hull[k - 1], p[i - 1]) <= 0) --k;
    hull[k++] = p[i - 1];
  }
  hull.resize(k - 1);
  return hull;
}

Svg::Svg(std::string_view id, std::string_view css_class, double width, double height,
         std::string_view title)
    : id_(id), width_(width), height_(height) {
  out_ = fmt::format(
      "<svg xmlns=\"http://www.w3.org/2000/svg\" id=\"{}\" class=\"figure {}\" "
      "viewBox=\"0 0 {} {}\" width=\"{}\" height=\"{}\" role=\"img\">\n<title>{}</title>\n",
      EscapeXml(id), EscapeXml(css_class), Px(width), Px(height), Px(width), Px(height),
      EscapeXml(title));
}

void Svg::Line(double x1, double y1, double x2, double y2, std::string_view css_class) {
  out_ += fmt::format("<line x1=\"{}\" y1=\"{}\" x2=\"{}\" y2=\"{}\"{}/>\n", Px(x1), Px(y1), Px(x2),
                      Px(y2), ClassAttribute(css_class));
}

void Svg::Rect(double x, double y, double width, double height, std::string_view css_class,
               std::string_view fill) {
  out_ += fmt::format("<rect x=\"{}\" y=\"{}\" width=\"{}\" height=\"{}\"{}{}/>\n", Px(x), Px(y),
                      Px(width), Px(height), ClassAttribute(css_class), FillAttribute(fill));
}

void Svg::Circle(double cx, double cy, double r, std::string_view css_class,
                 std::string_view fill) {
  out_ += fmt::format("<circle cx=\"{}\" cy=\"{}\" r=\"{}\"{}{}/>\n", Px(cx), Px(cy), Px(r),
                      ClassAttribute(css_class), FillAttribute(fill));
}

void Svg::Polyline(const Points& points, std::string_view css_class) {
  out_ +=
      fmt::format("<polyline points=\"{}\"{}/>\n", PointList(points), ClassAttribute(css_class));
}

void Svg::Polygon(const Points& points, std::string_view css_class, std::string_view fill) {
  out_ += fmt::format("<polygon points=\"{}\"{}{}/>\n", PointList(points),
                      ClassAttribute(css_class), FillAttribute(fill));
}

void Svg::Text(double x, double y, std::string_view text, std::string_view css_class, Anchor anchor,
               double rotate_deg) {
  const char* anchors[] = {"start", "middle", "end"};
  const std::string rotation = rotate_deg == 0 ? ""
                                               : fmt::format(" transform=\"rotate({} {} {})\"",
                                                             Px(rotate_deg), Px(x), Px(y));
  out_ += fmt::format("<text x=\"{}\" y=\"{}\" text-anchor=\"{}\"{}{}>{}</text>\n", Px(x), Px(y),
                      anchors[static_cast<int>(anchor)], rotation, ClassAttribute(css_class),
                      EscapeXml(text));
}

void Svg::Path(std::string_view d, std::string_view css_class) {
  out_ += fmt::format("<path d=\"{}\"{}/>\n", EscapeXml(d), ClassAttribute(css_class));
}

void Svg::Raw(std::string_view markup) { out_ += markup; }

void Svg::BeginGroup(std::string_view css_class) {
  out_ += fmt::format("<g{}>\n", ClassAttribute(css_class));
}

void Svg::EndGroup() { out_ += "</g>\n"; }

std::string Svg::Finish() { return out_ + "</svg>\n"; }

Chart::Chart(Svg& svg, double left, double top, double width, double height, Axis x, Axis y)
    : svg_(svg), left_(left), top_(top), width_(width), height_(height), x_(x), y_(y) {}

double Chart::X(double value) const { return left_ + (value - x_.lo) / (x_.hi - x_.lo) * width_; }

double Chart::Y(double value) const {
  return top_ + height_ - (value - y_.lo) / (y_.hi - y_.lo) * height_;
}

void Chart::DrawAxes(int x_ticks, int y_ticks) {
  const double bottom = top_ + height_;
  const std::vector<double> xs = AxisTicks(x_, x_ticks);
  const std::vector<double> ys = AxisTicks(y_, y_ticks);
  const double x_step = xs.size() > 1 ? xs[1] - xs[0] : 1;
  const double y_step = ys.size() > 1 ? ys[1] - ys[0] : 1;
  svg_.BeginGroup("axes");
  for (const double t : xs) {
    svg_.Line(X(t), top_, X(t), bottom, "grid");
    svg_.Line(X(t), bottom, X(t), bottom + 5, "tick");
    svg_.Text(X(t), bottom + 18, TickLabel(t, x_step), "tick-label", Anchor::kMiddle);
  }
  for (const double t : ys) {
    svg_.Line(left_, Y(t), left_ + width_, Y(t), "grid");
    svg_.Line(left_ - 5, Y(t), left_, Y(t), "tick");
    svg_.Text(left_ - 8, Y(t) + 4, TickLabel(t, y_step), "tick-label", Anchor::kEnd);
  }
  svg_.Rect(left_, top_, width_, height_, "frame");
  svg_.Text(left_ + width_ / 2, bottom + 38, x_.label, "axis-label", Anchor::kMiddle);
  svg_.Text(left_ - 46, top_ + height_ / 2, y_.label, "axis-label", Anchor::kMiddle, -90);
  svg_.EndGroup();
}

void Chart::ErrorBar(double x, double value, double error, std::string_view css_class) {
  if (!(error > 0)) return;
  const double px = X(x), lo = Y(value - error), hi = Y(value + error);
  svg_.Line(px, lo, px, hi, css_class);
  svg_.Line(px - 3, lo, px + 3, lo, css_class);
  svg_.Line(px - 3, hi, px + 3, hi, css_class);
}

void Chart::StepLine(const Points& points, double x_end, std::string_view css_class) {
  if (points.empty()) return;
  Points line;
  for (size_t i = 0; i < points.size(); ++i) {
    if (i > 0) line.emplace_back(X(points[i].first), Y(points[i - 1].second));
    line.emplace_back(X(points[i].first), Y(points[i].second));
  }
  line.emplace_back(X(x_end), Y(points.back().second));
  svg_.Polyline(line, css_class);
}

void Marker(Svg& svg, double x, double y, bool emphasised, std::string_view css_class) {
  if (emphasised) {
    svg.Polygon({{x, y - 6}, {x + 6, y}, {x, y + 6}, {x - 6, y}}, css_class);
  } else {
    svg.Circle(x, y, 3.5, css_class);
  }
}

double Legend(Svg& svg, double x, double y,
              const std::vector<std::pair<std::string, std::string>>& entries) {
  const double left = x;
  for (const auto& [sample, text] : entries) {
    const double width = 20 + TextWidth(text) + 18;
    if (x > left && x + width - 18 > svg.width() - 4) {  // the next row
      x = left;
      y += 18;
    }
    const std::string_view s = sample;
    if (s == "point") {
      Marker(svg, x + 6, y - 4, false, "point");
    } else if (s == "cached") {
      Marker(svg, x + 6, y - 4, false, "point cached");
    } else if (s == "improved") {
      Marker(svg, x + 6, y - 4, true, "point improved");
    } else if (s.starts_with("line:")) {
      svg.Line(x, y - 4, x + 14, y - 4, s.substr(5));
    } else if (s.starts_with("swatch:")) {
      svg.Rect(x, y - 11, 14, 12, "swatch", s.substr(7));
    } else if (s.starts_with("outline:")) {
      svg.Rect(x, y - 11, 14, 12, s.substr(8));
    }
    svg.Text(x + 20, y, text, "legend-text");
    x += width;
  }
  return y;
}

void ViridisColorBar(Svg& svg, double x, double y, double height, double lo, double hi,
                     std::string_view label) {
  const std::string id = fmt::format("{}-gradient", svg.id());
  std::string defs = fmt::format(
      "<defs><linearGradient id=\"{}\" x1=\"0\" y1=\"1\" x2=\"0\" y2=\"0\">", EscapeXml(id));
  for (const auto& [offset, color] : ViridisStops()) {
    defs += fmt::format("<stop offset=\"{}\" stop-color=\"{}\"/>", Px(offset), color);
  }
  svg.Raw(defs + "</linearGradient></defs>\n");
  svg.Rect(x, y, 14, height, "colorbar", fmt::format("url(#{})", id));
  const std::vector<double> ticks = NiceTicks(lo, hi, 5);
  const double step = ticks.size() > 1 ? ticks[1] - ticks[0] : 1;
  for (const double t : ticks) {
    const double ty = y + height - (t - lo) / (hi - lo) * height;
    svg.Line(x + 14, ty, x + 18, ty, "tick");
    svg.Text(x + 21, ty + 4, TickLabel(t, step), "tick-label");
  }
  svg.Text(x, y - 10, label, "axis-label");
}

}  // namespace fenestra
