#include "client/progress_display.h"

#include <fmt/format.h>
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <map>
#include <string_view>

#include "core/common/text.h"
#include "core/optimize/design_variables.h"
#include "core/optimize/final_check.h"

namespace fenestra {
namespace {

std::string Clock(double seconds) {
  if (!std::isfinite(seconds) || seconds < 0) return "--:--";
  const long s = std::lround(seconds);
  if (s >= 3600) return fmt::format("{}:{:02}:{:02}", s / 3600, s / 60 % 60, s % 60);
  return fmt::format("{:02}:{:02}", s / 60, s % 60);
}

std::string Value(const v1::Estimate& e, int digits = 2) {
  return fmt::format("{:.{}f} ± {:.{}f}", e.value(), digits, e.standard_error(), digits);
}

// "+13.21 ± 1.91 % (6.9 SE)"
std::string Difference(const v1::Estimate& d) {
  std::string out = fmt::format("{:+.2f} ± {:.2f} %", d.value(), d.standard_error());
  if (d.standard_error() > 0) {
    out += fmt::format(" ({:.1f} SE)", std::abs(d.value()) / d.standard_error());
  }
  return out;
}

// A job metric as the result's lines name it: "UDI", "ASE", "blind in place", ...
std::string_view MetricLabel(v1::Metric metric) {
  switch (metric) {
    case v1::METRIC_UDI_ALL_SENSORS:
      return "UDI all sensors";
    case v1::METRIC_DA:
      return "DA";
    case v1::METRIC_CDA:
      return "cDA";
    case v1::METRIC_SDA:
      return "sDA";
    case v1::METRIC_UDI_FELL_SHORT:
      return "UDI fell short";
    case v1::METRIC_UDI_EXCEEDED:
      return "UDI exceeded";
    case v1::METRIC_ASE:
      return "ASE";
    case v1::METRIC_BLIND_IN_PLACE:
      return "blind in place";
    default:
      return "UDI";
  }
}

// "ASE at most 10%: 4.0 +- 0.0 holds"
std::string ConstraintLine(const v1::ConstraintResult& c) {
  return fmt::format("{} {} {:g}%: {:.1f} +- {:.1f} {}\n", MetricLabel(c.constraint().metric()),
                     c.constraint().bound() == v1::Constraint::AT_LEAST ? "at least" : "at most",
                     c.constraint().value(), c.estimate().value(), c.estimate().standard_error(),
                     c.holds() ? "holds" : "broken");
}

bool live_line = false;

}  // namespace

std::string FormatDesign(const google::protobuf::Map<std::string, double>& design) {
  const std::map<std::string, double> sorted(design.begin(), design.end());
  std::string out;
  for (const auto& [name, value] : sorted) {
    out += fmt::format("{}{}={:.4g}", out.empty() ? "" : " ", name, value);
  }
  return out;
}

std::string FormatProgress(const JobProgress& p) {
  if (p.final_check) {
    const v1::FinalCheck& c = *p.final_check;
    return fmt::format(
        "[{}/{}] check of the best design ({}): one-stage {} %, two-stage {} %, difference {}{} "
        "| {} elapsed",
        p.evaluations, p.max_evaluations, FormatDesign(p.best.design()), Value(c.one_stage()),
        Value(c.two_stage()), Difference(c.difference()), c.disagrees() ? ": DISAGREES" : "",
        Clock(p.elapsed_seconds));
  }
  return fmt::format("[{}/{}] best {} % ({}) | current {} %{} ({}) | {} elapsed, ~{} left",
                     p.evaluations, p.max_evaluations, Value(p.best.value()),
                     FormatDesign(p.best.design()), Value(p.current.value()),
                     p.current.cached()      ? " cached"
                     : p.current.raced_out() ? " raced out"
                                             : "",
                     FormatDesign(p.current.design()), Clock(p.elapsed_seconds),
                     Clock(p.remaining_seconds));
}

std::string StageText(const std::string& stage, bool cached) {
  if (stage == "sky") return "building the sky matrix";
  if (stage == "outdoor")
    return cached ? "outdoor matrix from the cache" : "tracing the outdoor matrix";
  if (stage == "check") return "checking the best design by the one-stage method";
  return "searching";
}

JobProgress FromProto(const v1::JobProgress& p) {
  JobProgress progress;
  progress.evaluations = p.evaluations();
  progress.max_evaluations = p.max_evaluations();
  progress.current = p.current();
  progress.best = p.best();
  progress.elapsed_seconds = p.elapsed_seconds();
  progress.remaining_seconds = p.remaining_seconds();
  if (p.has_final_check()) progress.final_check = p.final_check();
  return progress;
}

void ShowProgress(const JobProgress& progress) {
  const std::string line = FormatProgress(progress);
  if (isatty(STDOUT_FILENO)) {
    std::printf("\r\033[K%s", line.c_str());
    live_line = true;
  } else {
    std::printf("%s\n", line.c_str());
  }
  std::fflush(stdout);
}

void EndProgress() {
  if (live_line) std::printf("\n");
  live_line = false;
  std::fflush(stdout);
}

// A Pareto search's front: one line per member, its objectives with their errors.
std::string FormatFront(const v1::JobResult& r) {
  if (!r.has_pareto()) return "";
  const v1::ParetoResult& p = r.pareto();
  std::string names;
  for (const v1::Objective& o : r.job().pareto().objectives()) {
    names += fmt::format("{}{} ({})", names.empty() ? "" : " against ", v1::Metric_Name(o.metric()),
                         o.goal() == v1::GOAL_MINIMIZE ? "minimized" : "maximized");
  }
  std::string out =
      fmt::format("Pareto front of {}: {} designs after {} generations, hypervolume {:.4g}\n",
                  names, p.front_size(), p.generations(),
                  p.hypervolume_size() > 0 ? p.hypervolume(p.hypervolume_size() - 1) : 0.0);
  for (const v1::FrontMember& m : p.front()) {
    std::string values;
    for (const v1::Estimate& o : m.objectives()) values += fmt::format(" {}", Value(o));
    out += fmt::format("  step {}:{} at {}\n", m.evaluation(), values, FormatDesign(m.design()));
  }
  return out;
}

std::string FormatResult(const v1::JobResult& r) {
  const v1::Metrics& m = r.best_metrics();
  std::string out = fmt::format("best design: {}\n", FormatDesign(r.best_design()));
  if (const auto finish = r.best_design().find(std::string(kFinishVariable));
      finish != r.best_design().end()) {
    out += fmt::format("finish: {}\n", FinishNameAt(r.job(), finish->second));
  }
  out += fmt::format("objective: {} %\n", Value(r.best_value()));
  out += fmt::format(
      "UDI {} % (fell short {} %, exceeded {} %), UDI all sensors {} %, DA {} %, cDA {} %, "
      "sDA {} %\n",
      Value(m.udi()), Value(m.udi_fell_short()), Value(m.udi_exceeded()),
      Value(m.udi_all_sensors()), Value(m.da()), Value(m.cda()), Value(m.sda()));
  if (m.has_ase()) {
    const v1::MetricSettings& s = r.job().metrics();
    out += fmt::format("ASE{:g},{} {} % of the sensors (LEED v4.1 daylight option 1: {} points)",
                       s.ase_threshold_lux(), s.ase_min_hours(), Value(m.ase()), m.leed_points());
    if (m.has_blind_in_place() && m.blind_in_place().value() < 100) {
      out += fmt::format(", blind in place {} % of the hours", Value(m.blind_in_place()));
    }
    out += "\n";
  }
  if (m.has_glare_autonomy()) {
    out += fmt::format("glare at the views: autonomy {} %, hours of glare {} % (DGP >= {:g})\n",
                       Value(m.glare_autonomy()), Value(m.glare_hours()),
                       r.job().metrics().glare_threshold());
  }
  if (m.has_solar_gain_kwh()) {
    out += fmt::format(
        "solar gain through the windows: {} kWh a year, {} kWh in the cooling "
        "season (months {}-{})\n",
        Value(m.solar_gain_kwh()), Value(m.cooling_solar_gain_kwh()),
        r.job().metrics().cooling_start_month(), r.job().metrics().cooling_end_month());
  }
  out += FormatFront(r);
  for (const v1::ConstraintResult& c : r.best_constraints()) out += ConstraintLine(c);
  for (const v1::ViewGlare& g : r.best_glare()) {
    out += fmt::format(
        "glare at {}: autonomy {} % of {} hours (DGP < 0.40), mean DGP {}, EN 17037 {}, the sun "
        "in view {} hours ({:.2f} s for all views)\n",
        QuoteText(g.view()), Value(g.autonomy()), g.analysed_hours(), Value(g.mean_dgp(), 3),
        g.en17037(), g.sunlit_hours(), r.timings().glare_seconds());
  }
  const v1::Timings& t = r.timings();
  const std::string comfort =
      t.comfort_seconds() > 0
          ? fmt::format(" (comfort metrics {:.2f} s of them)", t.comfort_seconds())
          : "";
  out += fmt::format(
      "{} evaluations ({}), backend {}: sky {:.2f} s, outdoor {:.2f} s, search started at "
      "{:.2f} s, evaluations {:.2f} s{}, total {:.2f} s\n",
      r.evaluations(), r.stop_reason(), r.backend(), t.sky_seconds(), t.outdoor_seconds(),
      t.start_seconds(), t.evaluation_seconds(), comfort, t.total_seconds());
  if (r.candidates_at_once() > 1) {
    out += fmt::format("{} candidates at once: {} evaluations made ahead and dropped\n",
                       r.candidates_at_once(), r.evaluations_discarded());
  }
  if (r.has_final_check()) {
    const v1::FinalCheck& c = r.final_check();
    out += fmt::format(
        "final check (one-stage, {} paths per sensor{}, {:.2f} s): {} %, difference to the "
        "two-stage value {}\n",
        c.paths_per_sensor(), c.paths_limited() ? ", the most allowed" : "", c.seconds(),
        Value(c.one_stage()), Difference(c.difference()));
    if (c.disagrees()) {
      out += fmt::format(
          "warning: the two-stage value and the one-stage check differ by more than {:g} "
          "standard errors; the check traces without a reflection limit, so the stages' limits "
          "(sampling.indoor_bounces, outdoor_bounces) may leave out light it counts\n",
          kFinalCheckDisagreementStandardErrors);
    }
  }
  return out;
}

}  // namespace fenestra
