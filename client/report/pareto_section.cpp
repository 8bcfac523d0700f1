// The report's section on a Pareto search (job.proto, ParetoResult): every evaluated design in
// the plane of the first two objectives, the front with its error bars, the best design and
// three chosen members (A and B, the front's ends by the first objective; C, the member
// between them nearest the ideal corner), the hypervolume per generation, the front as a table
// and the blind of the chosen members in section.
#include <fmt/format.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <limits>
#include <map>
#include <string>
#include <vector>

#include "absl/strings/str_join.h"
#include "client/report/sections.h"
#include "client/report/svg.h"
#include "core/optimize/design_variables.h"

namespace fenestra {
namespace {

constexpr double kFrontWidth = 560, kFrontHeight = 400;  // [px]
constexpr double kFrontLeft = 84, kFrontTop = 52, kFrontRight = 24, kFrontBottom = 72;
constexpr double kVolumeWidth = 420, kVolumeHeight = 300;
constexpr double kBetterLength = 30;  // of the "better" arrows [px]
// Rows of the front's table at most; a longer front shows every k-th member besides the
// chosen ones and the best design.
constexpr size_t kMaxFrontRows = 40;

using Xy = std::pair<double, double>;

// One objective of the search: its metric's name, unit and direction.
struct ParetoObjective {
  std::string name;  // e.g. "sDA300/50%", "glare hours"
  std::string unit = "%";
  bool maximize = true;
};

std::vector<ParetoObjective> ObjectivesOf(const v1::Job& job) {
  std::vector<ParetoObjective> objectives;
  for (const v1::Objective& o : job.pareto().objectives()) {
    ParetoObjective p;
    p.maximize = o.goal() != v1::GOAL_MINIMIZE;
    switch (o.metric()) {
      case v1::METRIC_GLARE_AUTONOMY:
        p.name = "glare autonomy";
        break;
      case v1::METRIC_GLARE_HOURS:
        p.name = "glare hours";
        break;
      case v1::METRIC_SOLAR_GAIN:
        p.name = "solar gain", p.unit = "kWh";
        break;
      case v1::METRIC_COOLING_SOLAR_GAIN:
        p.name = "cooling-season solar gain", p.unit = "kWh";
        break;
      default:
        p.name = MetricName(o.metric(), job.metrics());
    }
    objectives.push_back(std::move(p));
  }
  return objectives;
}

std::string AxisLabel(const ParetoObjective& o) { return fmt::format("{} [{}]", o.name, o.unit); }

// The front's members that hold every objective, finite, by the first objective, best first;
// the best design's member; and the chosen members A, B, C (indices into `members`).
struct Front {
  std::vector<const v1::FrontMember*> members;
  size_t best = 0;
  std::vector<size_t> chosen;
};

bool SameDesign(const google::protobuf::Map<std::string, double>& a,
                const google::protobuf::Map<std::string, double>& b) {
  if (a.size() != b.size()) return false;
  for (const auto& [name, value] : a) {
    const auto it = b.find(name);
    if (it == b.end() || std::abs(it->second - value) > 1e-9 * std::max(1.0, std::abs(value))) {
      return false;
    }
  }
  return true;
}

// A and B, the ends by the first objective; C, of the members between them, the one nearest
// the ideal corner with each objective scaled to [0, 1] over the front (0 at its best).
std::vector<size_t> ChosenMembers(const std::vector<const v1::FrontMember*>& members,
                                  const std::vector<ParetoObjective>& objectives) {
  const size_t n = members.size();
  if (n <= 2) return n == 2 ? std::vector<size_t>{0, 1} : std::vector<size_t>(n, 0);
  const int count = static_cast<int>(objectives.size());
  std::vector<double> lo(count, std::numeric_limits<double>::infinity()), hi(count, -lo[0]);
  for (const v1::FrontMember* m : members) {
    for (int k = 0; k < count; ++k) {
      lo[k] = std::min(lo[k], m->objectives(k).value());
      hi[k] = std::max(hi[k], m->objectives(k).value());
    }
  }
  size_t nearest = 1;
  double nearest_distance = std::numeric_limits<double>::infinity();
  for (size_t i = 1; i + 1 < n; ++i) {
    double distance = 0;
    for (int k = 0; k < count; ++k) {
      const double v = members[i]->objectives(k).value(), span = hi[k] - lo[k];
      const double scaled = span > 0 ? (objectives[k].maximize ? hi[k] - v : v - lo[k]) / span : 0;
      distance += scaled * scaled;
    }
    if (distance < nearest_distance) nearest_distance = distance, nearest = i;
  }
  return {0, n - 1, nearest};
}

Front FrontOf(const v1::JobResult& r, const std::vector<ParetoObjective>& objectives) {
  Front front;
  for (const v1::FrontMember& m : r.pareto().front()) {
    if (m.objectives_size() != static_cast<int>(objectives.size())) continue;
    const bool finite = std::all_of(m.objectives().begin(), m.objectives().end(), [](auto& e) {
      return std::isfinite(e.value()) && std::isfinite(e.standard_error());
    });
    if (finite) front.members.push_back(&m);
  }
  // By the first objective, best first, ties by the second
  const auto better = [&](const v1::FrontMember* a, const v1::FrontMember* b, int k) {
    const double x = a->objectives(k).value(), y = b->objectives(k).value();
    return objectives[k].maximize ? x > y : x < y;
  };
  std::stable_sort(front.members.begin(), front.members.end(), [&](auto* a, auto* b) {
    return better(a, b, 0) || (!better(b, a, 0) && better(a, b, 1));
  });
  for (size_t i = 0; i < front.members.size(); ++i) {
    if (SameDesign(front.members[i]->design(), r.best_design())) {
      front.best = i;
      break;
    }
  }
  front.chosen = ChosenMembers(front.members, objectives);
  return front;
}

std::string ChosenName(size_t c) { return std::string(1, static_cast<char>('A' + c)); }

// The first two objectives of every evaluated design (repeats from the cache left out).
Points EvaluatedPoints(const v1::JobResult& r) {
  Points points;
  for (const v1::Evaluation& e : r.history()) {
    if (e.cached() || e.objectives_size() < 2) continue;
    const double x = e.objectives(0).value(), y = e.objectives(1).value();
    if (std::isfinite(x) && std::isfinite(y)) points.emplace_back(x, y);
  }
  return points;
}

// Objective `k`'s axis over the evaluated designs and the front's error bars, padded.
Axis ObjectiveAxis(const ParetoObjective& o, int k, const Points& evaluated, const Front& f) {
  std::vector<double> ends;
  for (const auto& [x, y] : evaluated) ends.push_back(k == 0 ? x : y);
  for (const v1::FrontMember* m : f.members) {
    const v1::Estimate& e = m->objectives(k);
    ends.push_back(e.value() - e.standard_error());
    ends.push_back(e.value() + e.standard_error());
  }
  Axis axis{AxisLabel(o)};
  PaddedRange(ends, 0.06, &axis.lo, &axis.hi);
  return axis;
}

// An arrow from (x0, y0) to (x1, y1): a line and a filled head.
void BetterArrow(Svg& svg, double x0, double y0, double x1, double y1) {
  const double length = std::hypot(x1 - x0, y1 - y0);
  const double ux = (x1 - x0) / length, uy = (y1 - y0) / length;
  svg.Line(x0, y0, x1 - 6 * ux, y1 - 6 * uy, "better");
  svg.Polygon({{x1, y1},
               {x1 - 8 * ux - 4 * uy, y1 - 8 * uy + 4 * ux},
               {x1 - 8 * ux + 4 * uy, y1 - 8 * uy - 4 * ux}},
              "better-head");
}

// "better" with an arrow at the end of each axis where its objective improves: below the x
// axis's label, and left of the y axis's label, reading upwards.
void BetterArrows(Svg& svg, const Chart& chart, bool x_maximize, bool y_maximize) {
  const double left = chart.left(), right = left + chart.width();
  const double top = chart.top(), bottom = top + chart.height();
  const double ay = bottom + 56;
  const double x0 = x_maximize ? right - kBetterLength : left + kBetterLength;
  BetterArrow(svg, x0, ay, x_maximize ? right : left, ay);
  svg.Text(x_maximize ? x0 - 5 : x0 + 5, ay + 4, "better", "better-label",
           x_maximize ? Anchor::kEnd : Anchor::kStart);
  const double ax = left - 66;
  const double y0 = y_maximize ? top + kBetterLength : bottom - kBetterLength;
  BetterArrow(svg, ax, y0, ax, y_maximize ? top : bottom);
  svg.Text(ax + 4, y_maximize ? y0 + 5 : y0 - 5, "better", "better-label",
           y_maximize ? Anchor::kEnd : Anchor::kStart, -90);
}

// A chosen member's letter's extent [px].
struct LetterBox {
  double x0, y0, x1, y1;
};

// `letter` beside the member at (x, y): above right of it, else below right, above left or
// below left, the first clear of the letters drawn before (`letters`, which it joins).
void PlaceLetter(Svg& svg, double x, double y, const std::string& letter,
                 std::vector<LetterBox>& letters) {
  constexpr double kSize = 13;  // the letters' font [px]
  const double w = TextWidth(letter, kSize);
  LetterBox box{};
  for (const auto& [dx, dy] : {Xy{9, -9}, Xy{9, 19}, Xy{-9 - w, -9}, Xy{-9 - w, 19}}) {
    box = {x + dx, y + dy - 0.8 * kSize, x + dx + w, y + dy + 0.3 * kSize};
    const bool clear = std::none_of(letters.begin(), letters.end(), [&](const LetterBox& o) {
      return box.x0 < o.x1 && o.x0 < box.x1 && box.y0 < o.y1 && o.y0 < box.y1;
    });
    if (clear) break;
  }
  svg.Text(box.x0, box.y0 + 0.8 * kSize, letter, "pareto-label");
  letters.push_back(box);
}

// The front: its members joined in order, each with its error bars in both objectives and a
// diamond; a ring around the best design; the chosen members' letters.
void DrawFront(Svg& svg, Chart& chart, const Front& f) {
  svg.BeginGroup("front");
  Points line;
  for (const v1::FrontMember* m : f.members) {
    line.emplace_back(chart.X(m->objectives(0).value()), chart.Y(m->objectives(1).value()));
  }
  svg.Polyline(line, "best-line");
  for (const v1::FrontMember* m : f.members) {
    const v1::Estimate &x = m->objectives(0), &y = m->objectives(1);
    chart.ErrorBar(x.value(), y.value(), y.standard_error(), "errorbar improved");
    if (!(x.standard_error() > 0)) continue;
    const double py = chart.Y(y.value());
    const double lo = chart.X(x.value() - x.standard_error());
    const double hi = chart.X(x.value() + x.standard_error());
    svg.Line(lo, py, hi, py, "errorbar improved");
    svg.Line(lo, py - 3, lo, py + 3, "errorbar improved");
    svg.Line(hi, py - 3, hi, py + 3, "errorbar improved");
  }
  for (const auto& [x, y] : line) Marker(svg, x, y, true, "point improved front-member");
  svg.Circle(line[f.best].first, line[f.best].second, 10, "pareto-best");
  std::vector<LetterBox> letters;
  for (size_t c = 0; c < f.chosen.size(); ++c) {
    const auto& [x, y] = line[f.chosen[c]];
    PlaceLetter(svg, x, y, ChosenName(c), letters);
  }
  svg.EndGroup();
}

// The legend in rows from (12, 18), each sample drawn as in the figure.
void FrontLegend(Svg& svg) {
  const std::vector<std::string> texts = {"evaluated design", "front member ± 1 SE", "the front",
                                          "best design"};
  double x = 12, y = 18;
  for (size_t k = 0; k < texts.size(); ++k) {
    const double width = 20 + TextWidth(texts[k]) + 18;
    if (x > 12 && x + width - 18 > svg.width() - 4) x = 12, y += 18;
    if (k == 0) svg.Circle(x + 7, y - 4, 2.5, "point evaluated");
    if (k == 1) Marker(svg, x + 7, y - 4, true, "point improved");
    if (k == 2) svg.Line(x, y - 4, x + 14, y - 4, "best-line");
    if (k == 3) svg.Circle(x + 7, y - 4, 7, "pareto-best");
    svg.Text(x + 20, y, texts[k], "legend-text");
    x += width;
  }
}

std::string FrontFigure(const ReportData& data, const std::vector<ParetoObjective>& objectives,
                        const Front& f) {
  const Points evaluated = EvaluatedPoints(data.result);
  Svg svg("plot-pareto-front", "pareto-plot", kFrontWidth, kFrontHeight,
          fmt::format("The evaluated designs and the Pareto front: {} against {}",
                      objectives[1].name, objectives[0].name));
  Chart chart(svg, kFrontLeft, kFrontTop, kFrontWidth - kFrontLeft - kFrontRight,
              kFrontHeight - kFrontTop - kFrontBottom,
              ObjectiveAxis(objectives[0], 0, evaluated, f),
              ObjectiveAxis(objectives[1], 1, evaluated, f));
  chart.DrawAxes(6, 5);
  BetterArrows(svg, chart, objectives[0].maximize, objectives[1].maximize);
  svg.BeginGroup("evaluations");
  for (const auto& [x, y] : evaluated) svg.Circle(chart.X(x), chart.Y(y), 2.5, "point evaluated");
  svg.EndGroup();
  DrawFront(svg, chart, f);
  FrontLegend(svg);
  std::vector<std::string> chosen;
  for (size_t c = 0; c < f.chosen.size(); ++c) {
    chosen.push_back(
        fmt::format("{} evaluation {}", ChosenName(c), f.members[f.chosen[c]]->evaluation() + 1));
  }
  const std::string caption = fmt::format(
      "{} evaluated designs (grey) and the {} members of the front (diamonds, joined by {}), "
      "each ± 1 standard error in both objectives; the ring marks the best design. Chosen: {}.",
      evaluated.size(), f.members.size(), objectives[0].name, absl::StrJoin(chosen, ", "));
  return "<figure class=\"plot\">" + svg.Finish() + "<figcaption>" + EscapeXml(caption) +
         "</figcaption></figure>\n";
}

// A hypervolume's unit: the objectives' units multiplied; values of 10^4 and more in
// thousands (or millions, ...), *scale the factor the values are divided by.
std::string VolumeUnit(const std::vector<ParetoObjective>& objectives, double largest,
                       double* scale) {
  std::vector<std::string> units;
  for (const ParetoObjective& o : objectives) units.push_back(o.unit);
  static constexpr const char* kPowers[] = {"", "10³ ", "10⁶ ", "10⁹ ", "10¹² "};
  int power = 0;
  *scale = 1;
  while (power < 4 && largest / *scale >= 1e4) *scale *= 1e3, ++power;
  return kPowers[power] + absl::StrJoin(units, " × ");
}

std::string HypervolumeFigure(const v1::ParetoResult& p,
                              const std::vector<ParetoObjective>& objectives) {
  if (p.hypervolume_size() == 0) {
    return NotRecorded("The hypervolume per generation", "the result holds none");
  }
  double largest = 0, scale = 1;
  for (const double v : p.hypervolume()) largest = std::max(largest, std::abs(v));
  const std::string unit = VolumeUnit(objectives, largest, &scale);
  std::vector<double> values;
  for (const double v : p.hypervolume()) values.push_back(v / scale);
  Axis y{fmt::format("hypervolume [{}]", unit)};
  PaddedRange(values, 0.08, &y.lo, &y.hi);
  const double n = static_cast<double>(values.size());
  Svg svg("plot-hypervolume", "pareto-plot", kVolumeWidth, kVolumeHeight,
          "The hypervolume the front dominates, per generation");
  Chart chart(svg, kFrontLeft, 20, kVolumeWidth - kFrontLeft - kFrontRight, kVolumeHeight - 20 - 62,
              {"generation [number]", -0.5, n - 0.5, true}, y);
  chart.DrawAxes(6, 5);
  svg.BeginGroup("hypervolume");
  Points line;
  for (size_t g = 0; g < values.size(); ++g) {
    line.emplace_back(chart.X(static_cast<double>(g)), chart.Y(values[g]));
  }
  svg.Polyline(line, "best-line");
  for (const auto& [x, py] : line) Marker(svg, x, py, false, "point");
  svg.EndGroup();
  std::vector<std::string> reference;
  for (const double r : p.reference()) reference.push_back(fmt::format("{:g}", r));
  const std::string caption = fmt::format(
      "After each generation (0: the initial population), the hypervolume the front dominates "
      "up to the reference point ({}), each objective in the direction it is optimized.",
      reference.empty() ? "not recorded" : absl::StrJoin(reference, ", "));
  return "<figure class=\"plot\">" + svg.Finish() + "<figcaption>" + EscapeXml(caption) +
         "</figcaption></figure>\n";
}

// The members the table shows: all, or for a long front every k-th with the chosen ones and
// the best design.
std::vector<size_t> TableRows(const Front& f) {
  const size_t n = f.members.size();
  const size_t every = n <= kMaxFrontRows ? 1 : (n + kMaxFrontRows - 1) / kMaxFrontRows;
  std::vector<size_t> rows;
  for (size_t i = 0; i < n; ++i) {
    const bool chosen = std::find(f.chosen.begin(), f.chosen.end(), i) != f.chosen.end();
    if (i % every == 0 || chosen || i == f.best) rows.push_back(i);
  }
  return rows;
}

// The metrics beside the objectives the table shows where the members hold them: sDA and UDI,
// unless one is an objective.
std::vector<v1::Metric> ExtraMetrics(const v1::Job& job, const Front& f) {
  std::vector<v1::Metric> extra;
  for (const v1::Metric metric : {v1::METRIC_SDA, v1::METRIC_UDI}) {
    const auto& objectives = job.pareto().objectives();
    const bool objective = std::any_of(objectives.begin(), objectives.end(), [&](const auto& o) {
      return (o.metric() == v1::METRIC_UNSPECIFIED ? v1::METRIC_UDI : o.metric()) == metric;
    });
    const bool held = std::any_of(f.members.begin(), f.members.end(), [&](const auto* m) {
      return MetricEstimate(m->metrics(), metric) != nullptr;
    });
    if (!objective && held) extra.push_back(metric);
  }
  return extra;
}

std::string MemberLabel(const Front& f, size_t i) {
  std::vector<std::string> labels;
  for (size_t c = 0; c < f.chosen.size(); ++c) {
    if (f.chosen[c] == i) labels.push_back(ChosenName(c));
  }
  if (i == f.best) labels.push_back("best");
  return absl::StrJoin(labels, ", ");
}

std::string FrontTable(const ReportData& data, const std::vector<ParetoObjective>& objectives,
                       const Front& f) {
  const v1::Job& job = data.result.job();
  const std::vector<v1::Metric> extra = ExtraMetrics(job, f);
  std::vector<std::string> header = {"member", "evaluation [number]"};
  for (const v1::DesignVariable& v : job.variables()) {
    if (!v.fixed() && v.upper() > v.lower()) header.push_back(v.name());
  }
  for (const ParetoObjective& o : objectives) {
    header.push_back(AxisLabel(o) + (o.maximize ? " (higher is better)" : " (lower is better)"));
  }
  for (const v1::Metric m : extra) header.push_back(MetricName(m, job.metrics()) + " [%]");
  std::vector<std::vector<std::string>> rows;
  const std::vector<size_t> shown = TableRows(f);
  for (const size_t i : shown) {
    const v1::FrontMember& m = *f.members[i];
    std::vector<std::string> row = {MemberLabel(f, i), std::to_string(m.evaluation() + 1)};
    for (const v1::DesignVariable& v : job.variables()) {
      if (v.fixed() || !(v.upper() > v.lower())) continue;
      const auto it = m.design().find(v.name());
      row.push_back(it == m.design().end() ? "-" : DesignValue(v, it->second));
    }
    for (const v1::Estimate& o : m.objectives()) {
      row.push_back(WithError(o.value(), o.standard_error()));
    }
    for (const v1::Metric metric : extra) {
      const v1::Estimate* e = MetricEstimate(m.metrics(), metric);
      row.push_back(e ? WithError(e->value(), e->standard_error()) : "-");
    }
    rows.push_back(std::move(row));
  }
  std::string html = HtmlTable("pareto-front-table", header, rows);
  if (shown.size() < f.members.size()) {
    html += Note(fmt::format(
        "{} of the {} members shown: one in every {} by {}, and the chosen ones and the best "
        "design.",
        shown.size(), f.members.size(), (f.members.size() + kMaxFrontRows - 1) / kMaxFrontRows,
        objectives[0].name));
  }
  return html;
}

// The blind of each chosen member in section, where the scene has a blind.
std::string ChosenBlinds(const ReportData& data, const Front& f) {
  if (!data.scene || !data.scene->blind()) return "";
  std::vector<std::string> names;
  std::string figures;
  for (size_t c = 0; c < f.chosen.size(); ++c) {
    const v1::FrontMember& m = *f.members[f.chosen[c]];
    const std::string name = ChosenName(c);
    names.push_back(name);
    const std::map<std::string, double> values(m.design().begin(), m.design().end());
    absl::StatusOr<BlindDesign> design =
        JobDesignWithOverrides(*data.scene, data.result.job(), values);
    if (!design.ok() || !design->has_blind) {
      figures +=
          NotRecorded("The blind at " + name, design.ok() ? std::string("the design has none")
                                                          : std::string(design.status().message()));
      continue;
    }
    std::string id = "plot-pareto-blind-" + name;
    std::transform(id.begin(), id.end(), id.begin(), [](char ch) { return std::tolower(ch); });
    figures += BlindSectionFigure(
        *data.scene, *design, id,
        fmt::format("front member {} (evaluation {})", name, m.evaluation() + 1));
  }
  std::string heading = names.back();
  if (names.size() > 1) {
    names.pop_back();
    heading = absl::StrJoin(names, ", ") + " and " + heading;
  }
  return fmt::format("<h3>The blind at {}</h3>\n<div class=\"figures\">", EscapeXml(heading)) +
         figures + "</div>\n";
}

std::string FrontNote(const ReportData& data, const std::vector<ParetoObjective>& objectives) {
  const v1::ParetoSearch& search = data.result.job().pareto();
  const double k = search.has_dominance_standard_errors() ? search.dominance_standard_errors() : 1;
  return Note(fmt::format(
      "A design is on the front when no evaluated design beats it in every objective by more "
      "than {:g} combined standard errors (ParetoSearch.dominance_standard_errors). Each member "
      "is drawn with its error bars, ± 1 standard error in each objective, so neighbouring "
      "members whose bars overlap are not distinguishable: the Monte Carlo estimate does not "
      "tell which of them is better. More paths per sensor narrow the bars and thin the front. "
      "A and B are the front's ends by {}, C the member between them nearest the ideal corner "
      "with each objective scaled to [0, 1] over the front; the best design of the rest of this "
      "report is the front's best in {}.",
      k, objectives[0].name, objectives[0].name));
}

}  // namespace

std::string ParetoSection(const ReportData& data) {
  const v1::JobResult& r = data.result;
  if (!r.has_pareto()) return "";
  const std::string heading = "The Pareto front";
  const std::vector<ParetoObjective> objectives = ObjectivesOf(r.job());
  if (objectives.size() < 2) {
    return Section("pareto", heading,
                   NotRecorded("The Pareto objectives", "the result's job lists fewer than two"));
  }
  const Front f = FrontOf(r, objectives);
  if (f.members.empty()) {
    return Section("pareto", heading,
                   NotRecorded("The front", "no member holds every objective's value"));
  }
  const v1::ParetoResult& p = r.pareto();
  std::string body = Note(fmt::format(
      "NSGA-II over {} generations of {} designs; {} of its evaluated designs are on the front.",
      p.generations(), r.job().pareto().population(), f.members.size()));
  if (objectives.size() > 2) {
    body += Note(fmt::format(
        "Three objectives: the figure plots the first two ({} across, {} up); the table holds {} "
        "as well.",
        objectives[0].name, objectives[1].name, objectives[2].name));
  }
  body += "<div class=\"figures\">" + FrontFigure(data, objectives, f) +
          HypervolumeFigure(p, objectives) + "</div>\n";
  body += FrontNote(data, objectives) + FrontTable(data, objectives, f) + ChosenBlinds(data, f);
  return Section("pareto", heading, body);
}

}  // namespace fenestra
