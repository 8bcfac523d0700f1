#pragma once

// Building blocks of the report's inline SVG figures: escaping, scales, ticks, an element
// writer and charts with labelled axes. Styles come from the page's stylesheet (classes),
// so every figure prints the same way the page shows it.
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace fenestra {

// Text made safe inside XML elements and attribute values.
std::string EscapeXml(std::string_view text);

// About how wide `text` is drawn at 12 px in a sans-serif font [px] (its characters, not
// its bytes, times an average width).
double TextWidth(std::string_view text, double font_px = 12);

// A coordinate for SVG markup: two decimals at most, no exponent, no "-0".
std::string Px(double v);

// "Nice" tick values (1, 2 or 5 x 10^k apart) within [lo, hi], about `target` of them.
std::vector<double> NiceTicks(double lo, double hi, int target);

// A tick's label with as many decimals as the tick step needs.
std::string TickLabel(double value, double step);

// The range [lo, hi] of `values` widened by `fraction` of its span on both sides; a
// single value gets a span of 1. Fills *lo, *hi.
void PaddedRange(const std::vector<double>& values, double fraction, double* lo, double* hi);

// Colour of `fraction` in [0, 1] on the viridis scale (readable in grey and by colour-blind
// readers), as "#rrggbb".
std::string ViridisColor(double fraction);

// The stops of the viridis scale, for colour bars.
std::vector<std::pair<double, std::string>> ViridisStops();

enum class Anchor { kStart, kMiddle, kEnd };

using Points = std::vector<std::pair<double, double>>;

// The convex hull of `points` (Andrew's monotone chain), counter-clockwise; points closer
// than 1e-12 count as one.
Points ConvexHull(Points points);

// SVG markup, element by element; coordinates in px of the figure's viewBox.
class Svg {
 public:
  // A figure `width` x `height` px with element id `id`, classes "figure" and `css_class`
  // and a <title> (what screen readers and tooltips say).
  Svg(std::string_view id, std::string_view css_class, double width, double height,
      std::string_view title);

  void Line(double x1, double y1, double x2, double y2, std::string_view css_class);
  void Rect(double x, double y, double width, double height, std::string_view css_class,
            std::string_view fill = {});
  void Circle(double cx, double cy, double r, std::string_view css_class,
              std::string_view fill = {});
  void Polyline(const Points& points, std::string_view css_class);
  void Polygon(const Points& points, std::string_view css_class, std::string_view fill = {});
  // Text at (x, y) (its baseline), turned by `rotate_deg` about that point.
  void Text(double x, double y, std::string_view text, std::string_view css_class,
            Anchor anchor = Anchor::kStart, double rotate_deg = 0);
  // A path from SVG path data `d` (numbers and commands only).
  void Path(std::string_view d, std::string_view css_class);
  // Raw markup (definitions such as gradients and patterns), already escaped.
  void Raw(std::string_view markup);
  // <g class="css_class">, closed by EndGroup.
  void BeginGroup(std::string_view css_class);
  void EndGroup();

  double width() const { return width_; }
  double height() const { return height_; }
  std::string_view id() const { return id_; }

  // The figure's markup, closed.
  std::string Finish();

 private:
  std::string id_;
  double width_, height_;
  std::string out_;
};

// An axis: its label with the unit, e.g. "UDI [%]", and its range; `integer` axes tick
// whole numbers only (counts).
struct Axis {
  std::string label;
  double lo = 0, hi = 1;
  bool integer = false;
};

// The ticks of `axis`: NiceTicks, whole numbers only on integer axes.
std::vector<double> AxisTicks(const Axis& axis, int target);

// A plotting area inside a figure with an x axis below it and a y axis on its left:
// frame, grid lines, ticks and labels.
class Chart {
 public:
  // The area's top-left corner and size [px].
  Chart(Svg& svg, double left, double top, double width, double height, Axis x, Axis y);

  // Pixel positions of data values.
  double X(double value) const;
  double Y(double value) const;
  // Draws the grid, the frame, the ticks and the axis labels.
  void DrawAxes(int x_ticks = 6, int y_ticks = 5);
  // Error bar (with caps) from value - error to value + error at x.
  void ErrorBar(double x, double value, double error, std::string_view css_class);
  // A step line through (x, y) points: horizontal to each next x, then vertical.
  void StepLine(const Points& points, double x_end, std::string_view css_class);
  double left() const { return left_; }
  double top() const { return top_; }
  double width() const { return width_; }
  double height() const { return height_; }

 private:
  Svg& svg_;
  double left_, top_, width_, height_;
  Axis x_, y_;
};

// A marker for one point: a circle, or a diamond for emphasised points (which stays
// distinct when printed in grey).
void Marker(Svg& svg, double x, double y, bool emphasised, std::string_view css_class);

// Legend entries from (x, y) (the first row's baseline): each a marker or line sample
// ("point", "cached", "improved", "line:<class>", "swatch:<colour>", "outline:<class>")
// followed by its text, in rows 18 px apart that fit the figure's width. Returns the last
// row's baseline.
double Legend(Svg& svg, double x, double y,
              const std::vector<std::pair<std::string, std::string>>& entries);

// A vertical colour bar for `lo`..`hi` with ticks on its right and `label` above it, its
// top-left corner at (x, y), `height` px tall; its gradient's id is made from the figure's.
void ViridisColorBar(Svg& svg, double x, double y, double height, double lo, double hi,
                     std::string_view label);

}  // namespace fenestra
