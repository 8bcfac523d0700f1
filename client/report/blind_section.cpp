// The blind at the best design, in section and to scale: the slats as the tracer's generator
// (core/geometry/blind) makes them, the window's opening and the wall, with dimensions; and
// an enlarged detail of two slats.
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <numbers>

#include "client/report/sections.h"
#include "client/report/svg.h"
#include "core/geometry/blind.h"
#include "core/geometry/material.h"

namespace fenestra {
namespace {

constexpr double kMaxWidth = 250, kMaxHeight = 440;  // drawing area of the section [px]
constexpr double kDetailSize = 300;                  // of the detail [px]
constexpr double kSectionLeft = 70, kSectionTop = 40, kSectionRight = 150, kSectionBottom = 62;

using Uv = std::pair<double, double>;  // depth from the outer face [m], along the stack [m]
using Xy = std::pair<double, double>;  // [px]

// The blind in section: each slat's cross-section, its centre, and how it was laid out.
struct BlindCut {
  BlindLayout layout;
  std::vector<std::vector<Uv>> slats;  // corners, counter-clockwise
  std::vector<Uv> centers;
  double half_height = 0;  // of the opening along the stack [m]
  double depth = 0;        // of the wall [m]
  bool vertical = false;
};

// Generates the slats as the tracer does and projects each onto the section plane.
BlindCut SectionOf(const Scene& scene, const BlindDesign& design) {
  const Window& w = scene.window();
  const BlindSpec& spec = *scene.blind();
  const Vec3d stack = spec.vertical ? w.across : w.up;
  TriangleMesh mesh;
  BlindCut section;
  section.layout = GenerateBlind(w, spec, design, 0, mesh);
  section.half_height = 0.5 * (spec.vertical ? w.width_m : w.height_m);
  section.depth = w.depth_m;
  section.vertical = spec.vertical;
  constexpr size_t kTrianglesPerSlat = 12;
  for (int k = 0; k < section.layout.slat_count; ++k) {
    std::vector<Uv> corners;
    for (size_t v = 3 * kTrianglesPerSlat * k; v < 3 * kTrianglesPerSlat * (k + 1); ++v) {
      const Vec3d d = mesh.vertices[v] - w.center;
      corners.emplace_back(-Dot(d, w.normal), Dot(d, stack));
    }
    section.slats.push_back(ConvexHull(corners));
    Uv c{0, 0};
    for (const Uv& p : section.slats.back()) c.first += p.first, c.second += p.second;
    const double n = static_cast<double>(section.slats.back().size());
    section.centers.emplace_back(c.first / n, c.second / n);
  }
  return section;
}

Points ToPx(const Chart& chart, const std::vector<Uv>& uv) {
  Points px;
  for (const auto& [u, v] : uv) px.emplace_back(chart.X(u), chart.Y(v));
  return px;
}

// A dimension between a and b [px]: extension lines from them along `outward` (a unit
// vector) to `distance` px, the dimension line there with slashes at its ends, and the text
// beyond it, along the line.
void Dimension(Svg& svg, Xy a, Xy b, Xy outward, double distance, const std::string& text) {
  const double dx = b.first - a.first, dy = b.second - a.second, length = std::hypot(dx, dy);
  if (!(length > 0)) return;
  const auto [ox, oy] = outward;
  const Xy p{a.first + distance * ox, a.second + distance * oy};
  const Xy q{b.first + distance * ox, b.second + distance * oy};
  for (const auto& [from, to] : {std::pair{a, p}, std::pair{b, q}}) {
    svg.Line(from.first + 2 * ox, from.second + 2 * oy, to.first + 4 * ox, to.second + 4 * oy,
             "dim-extension");
  }
  svg.Line(p.first, p.second, q.first, q.second, "dim-line");
  const double sx = 3 * (dx / length + ox), sy = 3 * (dy / length + oy);
  for (const Xy& end : {p, q}) {
    svg.Line(end.first - sx, end.second - sy, end.first + sx, end.second + sy, "dim-line");
  }
  // Along the line, reading upwards; glyphs rise along `up`, so the baseline goes further
  // out when they would rise towards the line
  double angle = std::atan2(dy, dx) * 180 / std::numbers::pi;
  if (angle >= 90) angle -= 180;
  if (angle < -90) angle += 180;
  const double rad = angle * std::numbers::pi / 180;
  const double rises_outward = std::sin(rad) * ox - std::cos(rad) * oy;
  const double gap = rises_outward >= 0 ? 4 : 13;
  svg.Text(0.5 * (p.first + q.first) + gap * ox, 0.5 * (p.second + q.second) + gap * oy, text,
           "dim-text", Anchor::kMiddle, angle);
}

// Hatching for cut walls, with an id made from the figure's.
std::string WallFill(Svg& svg) {
  const std::string id = fmt::format("{}-hatch", svg.id());
  svg.Raw(fmt::format(
      "<defs><pattern id=\"{}\" width=\"6\" height=\"6\" patternUnits=\"userSpaceOnUse\" "
      "patternTransform=\"rotate(45)\"><rect width=\"6\" height=\"6\" fill=\"#d9d9d9\"/>"
      "<line x1=\"0\" y1=\"0\" x2=\"0\" y2=\"6\" stroke=\"#737373\" stroke-width=\"1\"/>"
      "</pattern></defs>\n",
      EscapeXml(id)));
  return fmt::format("url(#{})", id);
}

void DrawWall(Svg& svg, const Chart& chart, const BlindCut& s, double stub) {
  const std::string fill = WallFill(svg);
  for (const double side : {1.0, -1.0}) {
    const double inner = side * s.half_height, outer = side * (s.half_height + stub);
    svg.Polygon(ToPx(chart, {{0, inner}, {s.depth, inner}, {s.depth, outer}, {0, outer}}), "wall",
                fill);
  }
  svg.Line(chart.X(0), chart.Y(-s.half_height), chart.X(0), chart.Y(s.half_height), "window-face");
}

void DrawSlats(Svg& svg, const Chart& chart, const BlindCut& s) {
  svg.BeginGroup("slats");
  for (const std::vector<Uv>& slat : s.slats) svg.Polygon(ToPx(chart, slat), "slat");
  svg.EndGroup();
}

// The section's extent [m]: outdoors in front of the wall, the room behind the slats.
struct SectionExtent {
  double u0, u1, v0, v1, stub;
};

SectionExtent ExtentOf(const BlindCut& s) {
  double u1 = s.depth;
  for (const std::vector<Uv>& slat : s.slats) {
    for (const Uv& p : slat) u1 = std::max(u1, p.first);
  }
  double v1 = s.half_height;
  for (const std::vector<Uv>& slat : s.slats) {
    for (const Uv& p : slat) v1 = std::max(v1, std::abs(p.second));
  }
  const double stub = std::max(0.15, 0.12 * s.half_height);
  const double v = std::max(v1, s.half_height + stub) + 0.2;
  return {-0.25, u1 + 0.3, -v, v, stub};
}

// A chart of the extent at equal scale in both directions, within max_width x max_height.
Chart EqualScaleChart(Svg& svg, double u0, double u1, double v0, double v1, double max_width,
                      double max_height, const std::string& u_label, const std::string& v_label) {
  const double scale = std::min(max_width / (u1 - u0), max_height / (v1 - v0));
  return Chart(svg, kSectionLeft, kSectionTop, (u1 - u0) * scale, (v1 - v0) * scale,
               {u_label, u0, u1}, {v_label, v0, v1});
}

std::string StackLabel(bool vertical) {
  return vertical ? "across the window, from its centre [m]"
                  : "height from the opening's centre [m]";
}

// The section as figure `id`; `what` names the design in its title and caption.
std::string SectionFigure(const BlindCut& s, std::string_view id, std::string_view what) {
  const SectionExtent e = ExtentOf(s);
  const double scale = std::min(kMaxWidth / (e.u1 - e.u0), kMaxHeight / (e.v1 - e.v0));
  Svg svg(id, "blind-plot", kSectionLeft + (e.u1 - e.u0) * scale + kSectionRight,
          kSectionTop + (e.v1 - e.v0) * scale + kSectionBottom,
          fmt::format("The blind at {} in section", what));
  Chart chart = EqualScaleChart(svg, e.u0, e.u1, e.v0, e.v1, kMaxWidth, kMaxHeight,
                                "depth from the window's outer face [m]", StackLabel(s.vertical));
  chart.DrawAxes(5, 8);
  DrawWall(svg, chart, s, e.stub);
  DrawSlats(svg, chart, s);
  svg.Text(chart.X(e.u0) + 4, kSectionTop - 8, "outdoors", "plan-label");
  svg.Text(chart.left() + chart.width() - 4, kSectionTop - 8, "room", "plan-label", Anchor::kEnd);
  Dimension(svg, {chart.X(0), chart.Y(s.half_height)}, {chart.X(0), chart.Y(-s.half_height)},
            {-1, 0}, 18, fmt::format("opening {:.2f} m", 2 * s.half_height));
  Dimension(svg, {chart.X(0), chart.Y(s.half_height + e.stub)},
            {chart.X(s.depth), chart.Y(s.half_height + e.stub)}, {0, -1}, 10,
            fmt::format("{:.0f} mm", 1000 * s.depth));
  if (s.layout.slat_count > 1) {
    double front = s.depth;
    for (const std::vector<Uv>& slat : s.slats) {
      for (const Uv& p : slat) front = std::max(front, p.first);
    }
    Dimension(svg, {chart.X(front) + 6, chart.Y(s.centers.back().second)},
              {chart.X(front) + 6, chart.Y(s.centers.front().second)}, {1, 0}, 6,
              fmt::format("{} slats, axes {:.3f} m apart", s.layout.slat_count, s.layout.pitch_m));
  }
  return "<figure class=\"plot\">" + svg.Finish() + "<figcaption>" +
         EscapeXml(fmt::format("Section through the window at {}, to scale (1 m = {:.0f} px).",
                               what, scale)) +
         "</figcaption></figure>\n";
}

// The tilt: the window plane's direction from the slat's centre past its end, and an arc
// from it to the slat, just beyond the slat's end.
void DrawTilt(Svg& svg, const Chart& chart, Uv center, double tilt, double half_width_m) {
  const double cx = chart.X(center.first), cy = chart.Y(center.second);
  const double r = chart.X(half_width_m) - chart.X(0) + 12;
  svg.Line(cx, cy, cx, cy - r - 8, "reference-line");
  const double ex = cx + r * std::sin(tilt), ey = cy - r * std::cos(tilt);
  svg.Path(fmt::format("M {} {} A {} {} 0 0 {} {} {}", Px(cx), Px(cy - r), Px(r), Px(r),
                       tilt >= 0 ? 1 : 0, Px(ex), Px(ey)),
           "angle-arc");
  svg.Text(cx + (tilt >= 0 ? 8 : -8), cy - r - 4,
           fmt::format("α = {:.1f}°", tilt * 180 / std::numbers::pi), "dim-text",
           tilt >= 0 ? Anchor::kStart : Anchor::kEnd);
}

std::string DetailFigure(const BlindCut& s, const BlindDesign& design) {
  const int k = std::max(0, (s.layout.slat_count - 2) / 2);
  const int last = std::min(k + 1, s.layout.slat_count - 1);
  const double r = 0.5 * std::hypot(design.slat_width_m, design.slat_thickness_m);
  const double margin = 0.45 * r + 0.012;
  const double u0 = s.depth - margin, u1 = s.centers[k].first + r + margin;
  const double v0 = s.centers[k].second - r - margin, v1 = s.centers[last].second + r + margin;
  const double scale = kDetailSize / std::max(u1 - u0, v1 - v0);
  Svg svg("plot-blind-detail", "blind-plot", kSectionLeft + (u1 - u0) * scale + kSectionRight,
          kSectionTop + (v1 - v0) * scale + kSectionBottom,
          "Two slats enlarged, with their dimensions");
  Chart chart = EqualScaleChart(svg, u0, u1, v0, v1, kDetailSize, kDetailSize,
                                "depth from the window's outer face [m]", StackLabel(s.vertical));
  chart.DrawAxes(4, 4);
  svg.Line(chart.X(s.depth), chart.top(), chart.X(s.depth), chart.top() + chart.height(),
           "reference-line");
  svg.Text(chart.X(s.depth) - 5, chart.top() + 6, "wall's inner face", "dim-text", Anchor::kEnd,
           -90);
  for (int i = k; i <= last; ++i) svg.Polygon(ToPx(chart, s.slats[i]), "slat");
  DrawTilt(svg, chart, s.centers[last], design.tilt_rad, 0.5 * design.slat_width_m);
  // Width and thickness along the lower slat, on its room side
  const Uv c = s.centers[k];
  const double sin_a = std::sin(design.tilt_rad), cos_a = std::cos(design.tilt_rad);
  const double h = 0.5 * design.slat_width_m, t = 0.5 * design.slat_thickness_m;
  const Uv top{c.first + h * sin_a + t * cos_a, c.second + h * cos_a - t * sin_a};
  const Uv bottom{c.first - h * sin_a + t * cos_a, c.second - h * cos_a - t * sin_a};
  Dimension(svg, {chart.X(top.first), chart.Y(top.second)},
            {chart.X(bottom.first), chart.Y(bottom.second)}, {cos_a, sin_a}, 10,
            fmt::format("w = {:.0f} mm, t = {:.0f} mm", 1000 * design.slat_width_m,
                        1000 * design.slat_thickness_m));
  if (last > k) {
    const double right = chart.left() + chart.width();
    Dimension(svg, {right, chart.Y(s.centers[last].second)}, {right, chart.Y(c.second)}, {1, 0}, 10,
              fmt::format("p = {:.1f} mm", 1000 * s.layout.pitch_m));
  }
  return "<figure class=\"plot\">" + svg.Finish() +
         fmt::format(
             "<figcaption>Two slats enlarged (1 m = {:.0f} px): the tilt α from the "
             "window plane, slat width w and thickness t, and the pitch p between the "
             "slat axes.</figcaption></figure>\n",
             scale);
}

std::string BlindTable(const Scene& scene, const BlindCut& s, const BlindDesign& d) {
  const BlindSpec& spec = *scene.blind();
  const SlatFinish finish = FinishOf(spec, d);
  const auto material = [&](uint32_t index) {
    const Material& m = scene.materials[index];
    return fmt::format("{} ({})", m.name, DescribeMaterial(m));
  };
  return HtmlTable(
      "blind-table", {"quantity", "value"},
      {{"orientation", s.vertical ? "vertical slats" : "horizontal slats"},
       {"tilt α",
        fmt::format("{:.4f} rad ({:.1f}°)", d.tilt_rad, d.tilt_rad * 180 / std::numbers::pi)},
       {"slat width w", fmt::format("{:.1f} mm", 1000 * d.slat_width_m)},
       {"slat spacing s", fmt::format("{:.1f} mm", 1000 * d.slat_spacing_m)},
       {"slat thickness t", fmt::format("{:.1f} mm", 1000 * d.slat_thickness_m)},
       {"pitch p (w + s, widened so tilted slats never overlap)",
        fmt::format("{:.1f} mm", 1000 * s.layout.pitch_m)},
       {"slats", fmt::format("{}", s.layout.slat_count)},
       {"slat axes behind the wall's inner face",
        fmt::format("{:.1f} mm", 1000 * s.layout.axis_depth_m)},
       {"clearance to the wall", fmt::format("{:.1f} mm", 1000 * spec.wall_gap_m)},
       {"slat length beyond the opening, each end",
        fmt::format("{:.1f} mm", 1000 * spec.side_margin_m)},
       {"slat material", material(finish.material)},
       {"slat material, outer faces (to the window at α = 0)", material(finish.outer_material)},
       {"window opening",
        fmt::format("{:.2f} × {:.2f} m, wall {:.2f} m thick", scene.window().width_m,
                    scene.window().height_m, scene.window().depth_m)}});
}

}  // namespace

std::string BlindSectionFigure(const Scene& scene, const BlindDesign& design, std::string_view id,
                               std::string_view what) {
  return SectionFigure(SectionOf(scene, design), id, what);
}

std::string BlindSection(const ReportData& data) {
  const std::string heading = "The blind at the best design";
  if (!data.scene) {
    return Section("blind", heading, NotRecorded("The scene", "this result does not hold its job"));
  }
  if (!data.scene->blind() || !data.best_design.has_blind) {
    return Section("blind", heading, NotRecorded("A blind", "the scene has none"));
  }
  const BlindCut s = SectionOf(*data.scene, data.best_design);
  std::string body = Note(
      "Drawn from the slats the tracer used (core/geometry/blind): each slat's cross-section, "
      "the wall cut through above and below the opening, outdoors on the left.");
  body += "<div class=\"figures\">" + SectionFigure(s, "plot-blind-section", "the best design") +
          DetailFigure(s, data.best_design) + "</div>\n";
  return Section("blind", heading, body + BlindTable(*data.scene, s, data.best_design));
}

}  // namespace fenestra
