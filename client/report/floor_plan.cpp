// The floor plan: the room's indoor surfaces projected on the floor plane (x east, y north),
// the window, and the sensors coloured by the best design's UDI and DA, and by their sunlit
// hours (ASE's) where the result holds them; the scene's view points with their view
// directions.
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>
#include <string_view>

#include "absl/strings/str_join.h"
#include "client/report/sections.h"
#include "client/report/svg.h"

namespace fenestra {
namespace {

constexpr double kPlanMaxWidth = 320, kPlanMaxHeight = 640;  // [px]
constexpr double kPlanLeft = 64, kPlanTop = 30, kLabelRoom = 40, kBarRoom = 56, kPlanBottom = 60;
constexpr double kPadding = 0.5;  // around the room [m]
constexpr double kSensorRadius = 7;
constexpr size_t kMaxLabelledSensors = 200;
constexpr double kViewArrow = 26;  // a horizontal view direction's arrow [px]

using Xy = std::pair<double, double>;

// What a text or mark covers on the page [px], for placing the view points' names.
struct PlanBox {
  double x0, y0, x1, y1;
  bool Meets(const PlanBox& o) const { return x0 < o.x1 && o.x0 < x1 && y0 < o.y1 && o.y0 < y1; }
  bool Within(const PlanBox& o) const {
    return x0 >= o.x0 && x1 <= o.x1 && y0 >= o.y0 && y1 <= o.y1;
  }
};

// The box of `text` drawn `px` high with its baseline at (x, y), anchored as `anchor`.
PlanBox TextBox(double x, double y, std::string_view text, double px, Anchor anchor) {
  const double w = TextWidth(text, px);
  const double x0 = anchor == Anchor::kStart ? x : (anchor == Anchor::kEnd ? x - w : x - w / 2);
  return {x0, y - 0.8 * px, x0 + w, y + 0.3 * px};
}

// The eight corners of the window's opening (outer and inner face) in plan.
std::vector<Xy> WindowCorners(const Window& w) {
  std::vector<Xy> corners;
  for (const double depth : {0.0, w.depth_m}) {
    for (const double a : {-0.5, 0.5}) {
      for (const double u : {-0.5, 0.5}) {
        const Vec3d p =
            w.center - depth * w.normal + (a * w.width_m) * w.across + (u * w.height_m) * w.up;
        corners.emplace_back(p.x, p.y);
      }
    }
  }
  return corners;
}

// The plan's extent [m]: indoor triangles, window and sensors, padded.
struct Extent {
  double min_x = std::numeric_limits<double>::infinity(), min_y = min_x;
  double max_x = -min_x, max_y = -min_x;
  void Add(double x, double y) {
    min_x = std::min(min_x, x), max_x = std::max(max_x, x);
    min_y = std::min(min_y, y), max_y = std::max(max_y, y);
  }
};

Extent PlanExtent(const Scene& scene) {
  Extent e;
  const TriangleMesh& mesh = scene.fixed;
  for (size_t t = 0; t < mesh.TriangleCount(); ++t) {
    if (mesh.side[t] != Side::kIndoor) continue;
    for (int k = 0; k < 3; ++k) e.Add(mesh.vertices[3 * t + k].x, mesh.vertices[3 * t + k].y);
  }
  for (const SceneWindow& w : scene.windows) {
    for (const auto& [x, y] : WindowCorners(w.window)) e.Add(x, y);
  }
  for (const Sensor& s : scene.sensors) e.Add(s.position.x, s.position.y);
  for (const ViewPoint& v : scene.views) e.Add(v.position.x, v.position.y);
  e.min_x -= kPadding, e.min_y -= kPadding, e.max_x += kPadding, e.max_y += kPadding;
  return e;
}

// Floors and other flat surfaces filled, walls as thick lines, then the window.
void DrawRoom(Svg& svg, const Chart& chart, const Scene& scene) {
  const TriangleMesh& mesh = scene.fixed;
  std::vector<Points> walls;
  svg.BeginGroup("room");
  for (size_t t = 0; t < mesh.TriangleCount(); ++t) {
    if (mesh.side[t] != Side::kIndoor) continue;
    const Vec3d* v = &mesh.vertices[3 * t];
    const Vec3d normal = Cross(v[1] - v[0], v[2] - v[0]);
    if (std::abs(normal.z) > 0.2 * Length(normal)) {
      svg.Polygon({{chart.X(v[0].x), chart.Y(v[0].y)},
                   {chart.X(v[1].x), chart.Y(v[1].y)},
                   {chart.X(v[2].x), chart.Y(v[2].y)}},
                  "plan-floor");
      continue;
    }
    // A wall's triangle projects to a segment: its two vertices farthest apart in plan
    double longest = -1;
    Points segment;
    for (int a = 0; a < 3; ++a) {
      const Vec3d p = v[a], q = v[(a + 1) % 3];
      const double d = std::hypot(p.x - q.x, p.y - q.y);
      if (d > longest) {
        longest = d;
        segment = {{chart.X(p.x), chart.Y(p.y)}, {chart.X(q.x), chart.Y(q.y)}};
      }
    }
    walls.push_back(segment);
  }
  for (const Points& w : walls)
    svg.Line(w[0].first, w[0].second, w[1].first, w[1].second, "plan-wall");
  for (const SceneWindow& w : scene.windows) {
    Points window;
    for (const auto& [x, y] : ConvexHull(WindowCorners(w.window))) {
      window.emplace_back(chart.X(x), chart.Y(y));
    }
    svg.Polygon(window, "plan-window");
  }
  svg.EndGroup();
}

// "window 2.00 x 1.50 m" (a named window: "north 2.00 x 1.50 m") just outside the window's
// outer face, along it; its box goes to `taken`.
void LabelWindow(Svg& svg, const Chart& chart, const std::string& name, const Window& w,
                 std::vector<PlanBox>& taken) {
  const std::string text = fmt::format("{} {:.2f} × {:.2f} m", name, w.width_m, w.height_m);
  const double n = std::hypot(w.normal.x, w.normal.y);
  const double x = chart.X(w.center.x), y = chart.Y(w.center.y);
  if (n < 0.5) {  // a roof light: the label over its middle
    svg.Text(x, y - 8, text, "plan-label", Anchor::kMiddle);
    taken.push_back(TextBox(x, y - 8, text, 12, Anchor::kMiddle));
    return;
  }
  // Outward on the page; the text reads along the wall, glyphs rising up or to the left
  const double ox = w.normal.x / n, oy = -w.normal.y / n;
  const bool along_x = std::abs(oy) >= std::abs(ox);
  const double rises_outward = along_x ? -oy : -ox;
  const double gap = rises_outward >= 0 ? 6 : 17;
  const double tx = x + gap * ox, ty = y + gap * oy;
  svg.Text(tx, ty, text, "plan-label", Anchor::kMiddle, along_x ? 0 : -90);
  const PlanBox b = TextBox(tx, ty, text, 12, Anchor::kMiddle);
  // Turned by -90° about (tx, ty): x's offsets become upward ones, y's rightward ones
  taken.push_back(
      along_x ? b : PlanBox{tx + b.y0 - ty, ty - (b.x1 - tx), tx + b.y1 - ty, ty - (b.x0 - tx)});
}

void DrawNorthArrow(Svg& svg, double x, double y, std::vector<PlanBox>& taken) {
  svg.Polygon({{x, y}, {x + 6, y + 16}, {x, y + 12}, {x - 6, y + 16}}, "north-arrow");
  svg.Text(x, y - 4, "N", "plan-label", Anchor::kMiddle);
  taken.push_back({x - 8, y - 15, x + 8, y + 16});
}

// Each sensor's name sits above it and its value below, centred; they fit when no two
// sensors closer than a label's width share a column of labels.
bool LabelsFit(const std::vector<Xy>& at, double label_width) {
  if (at.size() > kMaxLabelledSensors) return false;
  for (size_t i = 0; i < at.size(); ++i) {
    for (size_t j = i + 1; j < at.size(); ++j) {
      const double dx = std::abs(at[j].first - at[i].first);
      const double dy = std::abs(at[j].second - at[i].second);
      if (dx < label_width + 4 && dy < 2 * kSensorRadius + 30) return false;
    }
  }
  return true;
}

// What one plan shows: a value per sensor on a colour scale, with its label.
struct PlanValues {
  std::string id;         // the figure's element id
  std::string what;       // e.g. "UDI 100–3000 lx [%]"
  std::string bar_label;  // the colour bar's, e.g. "UDI [%]"
  double lo = 0, hi = 100;
  std::vector<double> values;
  std::vector<std::string> labels;
  std::vector<bool> marked;  // sensors with a square around them; empty = none
  std::string caption;       // empty = `what` of each sensor
};

// A plan of one metric [%] per sensor, value ± SE as labels.
PlanValues EstimatePlan(const std::string& id, const std::string& what,
                        const std::string& short_name,
                        const google::protobuf::RepeatedPtrField<v1::Estimate>& estimates) {
  PlanValues plan;
  plan.id = id, plan.what = what, plan.bar_label = short_name + " [%]";
  for (const v1::Estimate& e : estimates) {
    plan.values.push_back(e.value());
    plan.labels.push_back(WithError(e.value(), e.standard_error(), 1));
  }
  return plan;
}

// The sensors: coloured dots, with names and values where they fit, the marked ones squared;
// what they cover goes to `taken`.
bool DrawSensors(Svg& svg, const Scene& scene, const std::vector<Xy>& at, const PlanValues& plan,
                 std::vector<PlanBox>& taken) {
  double longest = 0;
  for (size_t i = 0; i < plan.labels.size(); ++i) {
    longest =
        std::max({longest, TextWidth(scene.sensors[i].name, 11), TextWidth(plan.labels[i], 11.5)});
  }
  const bool labelled = LabelsFit(at, longest);
  svg.BeginGroup("sensors");
  for (size_t i = 0; i < at.size(); ++i) {
    const double fraction = (plan.values[i] - plan.lo) / (plan.hi - plan.lo);
    svg.Circle(at[i].first, at[i].second, kSensorRadius, "sensor", ViridisColor(fraction));
    const double reach = kSensorRadius + 4;  // the map sensor's ring
    taken.push_back(
        {at[i].first - reach, at[i].second - reach, at[i].first + reach, at[i].second + reach});
    if (!plan.marked.empty() && plan.marked[i]) {
      const double half = kSensorRadius + 2;
      svg.Rect(at[i].first - half, at[i].second - half, 2 * half, 2 * half, "marked-sensor");
    }
    if (!labelled) continue;
    const double name_y = at[i].second - kSensorRadius - 4;
    const double value_y = at[i].second + kSensorRadius + 13;
    svg.Text(at[i].first, name_y, scene.sensors[i].name, "sensor-name", Anchor::kMiddle);
    svg.Text(at[i].first, value_y, plan.labels[i], "sensor-value", Anchor::kMiddle);
    taken.push_back(TextBox(at[i].first, name_y, scene.sensors[i].name, 10.5, Anchor::kMiddle));
    taken.push_back(TextBox(at[i].first, value_y, plan.labels[i], 11.5, Anchor::kMiddle));
  }
  svg.EndGroup();
  return labelled;
}

// A view point on the page: the eye, its arrow's unit direction (up where it looks straight up
// or down) and the arrow's tip [px].
struct ViewMark {
  double x, y, ux, uy, tx, ty;
};

// A view's dot and arrow (the arrow's length the view direction's share in the plan); what
// they cover goes to `taken`.
ViewMark DrawViewMark(Svg& svg, const Chart& chart, const ViewPoint& v,
                      std::vector<PlanBox>& taken) {
  const double x = chart.X(v.position.x), y = chart.Y(v.position.y);
  const double dx = v.direction.x, dy = -v.direction.y;  // on the page, y points south
  const double length = std::hypot(dx, dy);
  const bool level = length > 0.05;
  const ViewMark m{x,
                   y,
                   level ? dx / length : 0,
                   level ? dy / length : -1,
                   x + kViewArrow * dx,
                   y + kViewArrow * dy};
  if (level) {
    svg.Line(x, y, m.tx - 6 * m.ux, m.ty - 6 * m.uy, "view-arrow");
    svg.Polygon({{m.tx, m.ty},
                 {m.tx - 8 * m.ux - 4 * m.uy, m.ty - 8 * m.uy + 4 * m.ux},
                 {m.tx - 8 * m.ux + 4 * m.uy, m.ty - 8 * m.uy - 4 * m.ux}},
                "view-arrow-head");
  }
  svg.Circle(x, y, 4, "view-point");
  taken.push_back(
      {std::min(x, m.tx) - 5, std::min(y, m.ty) - 5, std::max(x, m.tx) + 5, std::max(y, m.ty) + 5});
  return m;
}

struct NameSpot {
  double x, y;
  Anchor anchor;
};

// Where a view's name may go, in order: beyond the arrow's tip, behind the eye, below, above,
// right and left of it.
std::vector<NameSpot> NameSpots(const ViewMark& m) {
  const auto along = [](double u) {
    return u > 0.4 ? Anchor::kStart : (u < -0.4 ? Anchor::kEnd : Anchor::kMiddle);
  };
  const auto baseline = [](double y, double u) {
    return u > 0.4 ? y + 10 : (u < -0.4 ? y - 2 : y + 4);
  };
  const double bx = m.tx + 5 * m.ux, by = m.ty + 5 * m.uy;
  const double ex = m.x - 8 * m.ux, ey = m.y - 8 * m.uy;
  return {{bx, baseline(by, m.uy), along(m.ux)}, {ex, baseline(ey, -m.uy), along(-m.ux)},
          {m.x, m.y + 17, Anchor::kMiddle},      {m.x, m.y - 8, Anchor::kMiddle},
          {m.x + 8, m.y + 4, Anchor::kStart},    {m.x - 8, m.y + 4, Anchor::kEnd}};
}

// The first spot where `text` meets nothing `taken` and stays within `bounds`.
std::optional<NameSpot> FreeSpot(const ViewMark& m, std::string_view text,
                                 const std::vector<PlanBox>& taken, const PlanBox& bounds) {
  for (const NameSpot& spot : NameSpots(m)) {
    const PlanBox box = TextBox(spot.x, spot.y, text, 10.5, spot.anchor);
    if (box.Within(bounds) &&
        std::none_of(taken.begin(), taken.end(), [&](const PlanBox& t) { return t.Meets(box); })) {
      return spot;
    }
  }
  return std::nullopt;
}

// The view points: each a dot with an arrow of its view direction projected on the plan, and
// its name where it fits clear of what is `taken` within `bounds`; where it does not, the
// view's tag "V1", "V2", ... (by its order in the scene). Returns "V2 = name" for each tag.
std::vector<std::string> DrawViews(Svg& svg, const Chart& chart,
                                   const std::vector<ViewPoint>& views, std::vector<PlanBox>& taken,
                                   const PlanBox& bounds) {
  svg.BeginGroup("views");
  std::vector<ViewMark> marks;
  for (const ViewPoint& v : views) marks.push_back(DrawViewMark(svg, chart, v, taken));
  std::vector<std::string> tags;
  for (size_t k = 0; k < views.size(); ++k) {
    std::string text = views[k].name;
    std::optional<NameSpot> spot = FreeSpot(marks[k], text, taken, bounds);
    if (!spot) {
      text = fmt::format("V{}", k + 1);
      tags.push_back(fmt::format("{} = {}", text, views[k].name));
      spot = FreeSpot(marks[k], text, taken, bounds).value_or(NameSpots(marks[k]).front());
    }
    svg.Text(spot->x, spot->y, text, "view-name", spot->anchor);
    taken.push_back(TextBox(spot->x, spot->y, text, 10.5, spot->anchor));
  }
  svg.EndGroup();
  return tags;
}

// One plan with the sensors coloured by `plan`'s values.
std::string PlanFigure(const ReportData& data, const PlanValues& plan) {
  const Scene& scene = *data.scene;
  const Extent e = PlanExtent(scene);
  const double scale =
      std::min(kPlanMaxWidth / (e.max_x - e.min_x), kPlanMaxHeight / (e.max_y - e.min_y));
  const double width = (e.max_x - e.min_x) * scale, height = (e.max_y - e.min_y) * scale;
  Svg svg(plan.id, "plan-plot", kPlanLeft + width + kLabelRoom + kBarRoom,
          kPlanTop + height + kPlanBottom, "Floor plan with the sensors coloured by " + plan.what);
  Chart chart(svg, kPlanLeft, kPlanTop, width, height, {"x, east [m]", e.min_x, e.max_x},
              {"y, north [m]", e.min_y, e.max_y});
  chart.DrawAxes(std::max(2, static_cast<int>(width / 60)),
                 std::max(2, static_cast<int>(height / 60)));
  DrawRoom(svg, chart, scene);
  std::vector<PlanBox> taken;
  for (const SceneWindow& w : scene.windows) LabelWindow(svg, chart, w.name, w.window, taken);
  DrawNorthArrow(svg, kPlanLeft + width - 14, kPlanTop + 20, taken);

  std::vector<Xy> at;
  for (const Sensor& s : scene.sensors)
    at.emplace_back(chart.X(s.position.x), chart.Y(s.position.y));
  const bool labelled = DrawSensors(svg, scene, at, plan, taken);
  if (data.map_sensor >= 0) {
    svg.Circle(at[data.map_sensor].first, at[data.map_sensor].second, kSensorRadius + 4,
               "map-sensor");
  }
  std::vector<std::string> tags;
  if (!scene.views.empty()) {
    const PlanBox bounds{kPlanLeft, kPlanTop, kPlanLeft + width + kLabelRoom - 4,
                         kPlanTop + height};
    tags = DrawViews(svg, chart, scene.views, taken, bounds);
  }
  ViridisColorBar(svg, kPlanLeft + width + kLabelRoom, kPlanTop + 20, std::min(height - 20, 220.0),
                  plan.lo, plan.hi, plan.bar_label);
  std::string figure =
      "<figure class=\"plot\">" + svg.Finish() + "<figcaption>" +
      EscapeXml(plan.caption.empty() ? plan.what + " of each sensor, best design" : plan.caption);
  if (!labelled) figure += " (values in the table below)";
  if (data.map_sensor >= 0) figure += "; the ring marks the temporal map's sensor";
  if (!scene.views.empty()) figure += "; the arrows mark the view points and where they look";
  if (!tags.empty()) figure += EscapeXml(" (" + absl::StrJoin(tags, ", ") + ")");
  return figure + "</figcaption></figure>\n";
}

// Each sensor's sunlit hours (direct sun above ASE's threshold), those ASE counts squared.
PlanValues SunlitPlan(const ReportData& data) {
  const v1::Metrics& m = data.result.best_metrics();
  PlanValues plan;
  plan.id = "plot-floor-sunlit";
  plan.what = fmt::format("sunlit hours (direct sun above {:g} lx)", data.ase_threshold_lux);
  plan.bar_label = "sun [h]";
  plan.lo = 0;
  plan.hi = data.ase_min_hours;
  int counted = 0;
  for (const int hours : m.sensor_sunlit_hours()) {
    plan.values.push_back(hours);
    plan.labels.push_back(fmt::format("{} h", hours));
    plan.marked.push_back(hours >= data.ase_min_hours);
    counted += hours >= data.ase_min_hours;
    plan.hi = std::max(plan.hi, static_cast<double>(hours));
  }
  plan.caption = fmt::format(
      "Analysed hours with more than {:g} lx of direct sun at each sensor, best design{}; the "
      "squares mark the {} sensor{} with at least {} h, those ASE counts",
      data.ase_threshold_lux, data.operated_blind ? " with the window bare (as ASE asks)" : "",
      counted, counted == 1 ? "" : "s", data.ase_min_hours);
  return plan;
}

// Mean illuminance of each sensor over the occupied steps [lx].
std::vector<double> OccupiedMeans(const ReportData& data) {
  const v1::HourlyIlluminance& h = data.result.best_hourly();
  const int steps = h.month_size();
  std::vector<double> means;
  for (int i = 0; i < h.sensors_size(); ++i) {
    double sum = 0;
    int count = 0;
    for (int j = 0; j < steps; ++j) {
      if (!data.occupied[j]) continue;
      sum += h.illuminance_lux(i * steps + j);
      ++count;
    }
    means.push_back(count > 0 ? sum / count : 0);
  }
  return means;
}

std::string SensorTable(const ReportData& data, const std::string& udi, const std::string& da) {
  const Scene& scene = *data.scene;
  const v1::Metrics& m = data.result.best_metrics();
  const bool hourly = data.map_sensor >= 0;
  const std::vector<double> means = hourly ? OccupiedMeans(data) : std::vector<double>();
  const bool sunlit = m.sensor_sunlit_hours_size() > 0;
  std::vector<std::vector<std::string>> rows;
  for (size_t i = 0; i < scene.sensors.size(); ++i) {
    const Sensor& s = scene.sensors[i];
    const int k = static_cast<int>(i);
    rows.push_back({s.name, fmt::format("{:.2f}", s.position.x),
                    fmt::format("{:.2f}", s.position.y), fmt::format("{:.2f}", s.position.z),
                    WithError(m.sensor_udi(k).value(), m.sensor_udi(k).standard_error(), 1),
                    WithError(m.sensor_da(k).value(), m.sensor_da(k).standard_error(), 1),
                    hourly ? fmt::format("{:.0f}", means[i]) : "not recorded"});
    if (sunlit) rows.back().push_back(fmt::format("{}", m.sensor_sunlit_hours(k)));
  }
  std::vector<std::string> header = {
      "sensor", "x [m]", "y [m]", "z [m]", udi, da, "mean E, occupied hours [lx]"};
  if (sunlit)
    header.push_back(fmt::format("sunlit hours (> {:g} lx direct)", data.ase_threshold_lux));
  return HtmlTable("sensor-table", header, rows);
}

}  // namespace

std::string FloorPlanSection(const ReportData& data) {
  const std::string heading = "Floor plan and sensors";
  if (!data.scene) {
    return Section("floor-plan", heading,
                   NotRecorded("The scene", "this result does not hold its job"));
  }
  const int sensors = static_cast<int>(data.scene->sensors.size());
  const v1::Metrics& m = data.result.best_metrics();
  if (m.sensor_udi_size() != sensors || m.sensor_da_size() != sensors) {
    return Section("floor-plan", heading,
                   NotRecorded("Per-sensor metrics", "the result holds none"));
  }
  const v1::MetricSettings& settings = data.result.job().metrics();
  const std::string udi =
      fmt::format("UDI {:g}–{:g} lx [%]", settings.udi_lower_lux(), settings.udi_upper_lux());
  const std::string da = fmt::format("DA{:g} [%]", settings.da_threshold_lux());
  std::string body = Note(
      "Indoor surfaces seen from above: floors shaded, walls as lines, the window's opening in "
      "blue; north is up. Each sensor shows its value ± standard error for the best design.");
  body += "<div class=\"figures\">" +
          PlanFigure(data, EstimatePlan("plot-floor-udi", udi, "UDI", m.sensor_udi())) +
          PlanFigure(data, EstimatePlan("plot-floor-da", da, "DA", m.sensor_da()));
  if (m.sensor_sunlit_hours_size() == sensors) body += PlanFigure(data, SunlitPlan(data));
  body += "</div>\n";
  return Section("floor-plan", heading, body + SensorTable(data, udi, da));
}

}  // namespace fenestra
