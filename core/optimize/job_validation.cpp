// The door for jobs: every field of a Job checked, defaults filled in (job.proto states
// them; the constants here, the sampling's in core/dc/two_stage.h and the metrics' in
// core/metrics are the only other place).
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <set>
#include <string>

#include "absl/strings/str_cat.h"
#include "core/common/status_macros.h"
#include "core/common/text.h"
#include "core/dc/two_stage.h"
#include "core/metrics/annual_metrics.h"
#include "core/metrics/glare.h"
#include "core/metrics/occupancy.h"
#include "core/optimize/comfort.h"
#include "core/optimize/design_variables.h"
#include "core/optimize/job.h"
#include "core/optimize/job_proto.h"
#include "core/optimize/racing.h"
#include "core/optimize/vns.h"
#include "core/trace/path.h"
#include "core/trace/room_check.h"

namespace fenestra {
namespace {

// Illuminance thresholds beyond any daylight [lx]: direct sun peaks near 1.3e5 lx.
constexpr double kMaxIlluminanceLux = 1e6;
// Surface reflections per path: the reference cases use 30, Radiance's -ab rarely 10; past
// 1000 even a white room (reflectance 0.99) has no light left to carry.
constexpr int kMaxBounces = 1000;
constexpr int kDefaultBasisCells = 288;
// Whether a job checks its best design by the one-stage method when its sampling does not say.
constexpr bool kFinalCheckByDefault = true;
// Constraints of an objective, and the most standard errors a design may be beyond a bound.
constexpr int kMaxConstraints = 8;
// The largest solar gain a bound or a target may name [kWh].
constexpr double kMaxGainKwh = 1e9;

// The largest value of `metric`: 100 for a share [%], kMaxGainKwh for a solar gain [kWh].
double MetricUpperBound(v1::Metric metric) {
  return metric == v1::METRIC_SOLAR_GAIN || metric == v1::METRIC_COOLING_SOLAR_GAIN ? kMaxGainKwh
                                                                                    : 100;
}

// "[0, <upper>] <unit>", the range of `metric`'s values.
std::string MetricRange(v1::Metric metric) {
  const bool gain = MetricUpperBound(metric) == kMaxGainKwh;
  return absl::StrCat("[0, ", MetricUpperBound(metric), "] ", gain ? "kWh" : "%");
}
constexpr double kMaxConstraintStandardErrors = 100;

bool AllFinite(std::initializer_list<double> values) {
  return std::all_of(values.begin(), values.end(), [](double v) { return std::isfinite(v); });
}

absl::StatusOr<Scene> SceneOf(const v1::Job& job, const std::string& base_dir) {
  if (job.has_scene() && !job.scene_file().empty()) {
    return InvalidJobField("scene", "give either scene or scene_file, not both");
  }
  if (!job.scene_file().empty()) {
    return LoadScene((std::filesystem::path(base_dir) / job.scene_file()).string());
  }
  if (!job.has_scene()) return InvalidJobField("scene", "a scene or scene_file is required");
  return BuildScene(job.scene(), (std::filesystem::path(base_dir) / "job.scene").string());
}

// The range of `v`: finite, not empty, its start within it.
absl::Status CheckRange(const v1::DesignVariable& v, const std::string& field) {
  if (!AllFinite({v.lower(), v.upper(), v.start(), v.step()})) {
    return InvalidJobField(field, "lower, upper, start and step must be finite");
  }
  if (v.lower() > v.upper()) {
    return InvalidJobField(
        field, absl::StrCat("empty design range: lower ", v.lower(), " > upper ", v.upper()));
  }
  if (v.start() < v.lower() || v.start() > v.upper()) {
    return InvalidJobField(field + ".start", absl::StrCat("start ", v.start(), " is outside [",
                                                          v.lower(), ", ", v.upper(), "]"));
  }
  return absl::OkStatus();
}

absl::Status CheckVariable(const v1::DesignVariable& v, const DesignVariableInfo& info,
                           const std::string& field) {
  if (v.finishes_size() > 0) {
    return InvalidJobField(field + ".finishes", "only the finish variable lists finishes");
  }
  FENESTRA_RETURN_IF_ERROR(CheckRange(v, field));
  constexpr double kRounding = 1e-12;  // π/2 written in decimal
  if (v.lower() < info.bounds.lowest - kRounding || v.upper() > info.bounds.highest + kRounding) {
    return InvalidJobField(
        field, absl::StrCat(v.name(), " must stay within [", info.bounds.lowest, ", ",
                            info.bounds.highest, "] ", info.unit, ", the range of a real blind"));
  }
  if (v.step() < 0) return InvalidJobField(field + ".step", "must be >= 0");
  return absl::OkStatus();
}

// The finish variable `v` at `field` (job.proto): its finishes resolved into `finishes`
// against the scene's materials, its step filled in as 1 and its range as the whole list where
// lower and upper are both 0, every bound and the start an index of the list.
absl::Status FillFinishVariable(v1::DesignVariable& v, const Scene& scene, const std::string& field,
                                std::vector<SlatFinish>& finishes) {
  const int count = v.finishes_size();
  if (count < 1 || count > kMaxFinishes) {
    return InvalidJobField(
        field + ".finishes",
        absl::StrCat("the finish variable lists 1 to ", kMaxFinishes, " finishes, got ", count));
  }
  FENESTRA_ASSIGN_OR_RETURN(resolved, ResolveFinishes(v, scene, field));
  if (v.step() != 0 && v.step() != 1) {
    return InvalidJobField(field + ".step",
                           absl::StrCat("must be 1 or unset (the finish's values are the indices "
                                        "of its finishes), got ",
                                        v.step()));
  }
  v.set_step(1);
  if (v.lower() == 0 && v.upper() == 0) v.set_upper(count - 1);
  for (const auto& [value, name] : {std::pair{v.lower(), "lower"}, std::pair{v.upper(), "upper"},
                                    std::pair{v.start(), "start"}}) {
    if (!FinishIndex(value, static_cast<size_t>(count))) {
      return InvalidJobField(
          absl::StrCat(field, ".", name),
          absl::StrCat("must be the index of one of the ", count,
                       " finishes, a whole number in [0, ", count - 1, "], got ", value));
    }
  }
  FENESTRA_RETURN_IF_ERROR(CheckRange(v, field));
  finishes = std::move(resolved);
  return absl::OkStatus();
}

// The job's variables checked, its finish variable's range filled in and its finishes
// resolved into `finishes`.
absl::Status FillVariables(v1::Job& job, const Scene& scene, std::vector<SlatFinish>& finishes) {
  // The search needs a variable (RunVns refuses none); with every one fixed it evaluates the
  // start alone
  if (job.variables_size() == 0) {
    return InvalidJobField("variables",
                           "none given; the search needs at least one design variable (alpha, "
                           "width, spacing, thickness or finish; with every one fixed it "
                           "evaluates the start design alone)");
  }
  if (!scene.blind()) {
    return InvalidJobField("variables", "the scene has no blind to design");
  }
  std::set<std::string> seen;
  for (int i = 0; i < job.variables_size(); ++i) {
    v1::DesignVariable& v = *job.mutable_variables(i);
    const std::string field = absl::StrCat("variables[", i, "]");
    const DesignVariableInfo* info = FindDesignVariable(v.name());
    if (!info && v.name() != kFinishVariable) {
      return InvalidJobField(field + ".name",
                             absl::StrCat("unknown design variable '", v.name(),
                                          "' (known: alpha, width, spacing, thickness, finish)"));
    }
    if (!seen.insert(v.name()).second) {
      return InvalidJobField(field + ".name",
                             absl::StrCat("variable '", v.name(), "' given twice"));
    }
    FENESTRA_RETURN_IF_ERROR(info ? CheckVariable(v, *info, field)
                                  : FillFinishVariable(v, scene, field, finishes));
  }
  return absl::OkStatus();
}

absl::Status FillBudget(v1::Budget& budget) {
  if (budget.max_evaluations() == 0) budget.set_max_evaluations(kDefaultMaxEvaluations);
  if (budget.max_evaluations() < 1)
    return InvalidJobField("budget.max_evaluations", "must be >= 1");
  if (!(std::isfinite(budget.max_seconds()) && budget.max_seconds() >= 0)) {
    return InvalidJobField("budget.max_seconds", "must be a finite number >= 0 (0 = no limit)");
  }
  if (budget.failed_cycles_to_stop() == 0) {
    budget.set_failed_cycles_to_stop(VnsOptions().failed_cycles_to_stop);
  }
  if (budget.failed_cycles_to_stop() < -1) {
    return InvalidJobField("budget.failed_cycles_to_stop", "must be >= -1");
  }
  return absl::OkStatus();
}

// A threshold in (lowest, kMaxIlluminanceLux] lx, or [0, ...] when `zero_allowed`.
absl::Status CheckLux(double value, const std::string& field, bool zero_allowed) {
  const bool low_ok = zero_allowed ? value >= 0 : value > 0;
  if (!(low_ok && value <= kMaxIlluminanceLux)) {
    return InvalidJobField("metrics." + field,
                           absl::StrCat("must be in ", zero_allowed ? "[" : "(", "0, ",
                                        kMaxIlluminanceLux, "] lx, got ", value));
  }
  return absl::OkStatus();
}

// Hours of a leap year: the most an ASE count can reach.
constexpr int kMaxAseHours = 8784;

absl::Status FillMetricSettings(v1::MetricSettings& m) {
  const MetricOptions defaults;
  const OccupancySchedule occupancy;
  if (m.udi_lower_lux() == 0) m.set_udi_lower_lux(defaults.udi_lower_lux);
  if (m.udi_upper_lux() == 0) m.set_udi_upper_lux(defaults.udi_upper_lux);
  if (m.da_threshold_lux() == 0) m.set_da_threshold_lux(defaults.da_threshold_lux);
  if (m.sda_time_fraction_percent() == 0) {
    m.set_sda_time_fraction_percent(defaults.sda_min_da_percent);
  }
  if (m.occupied_start_h() == 0 && m.occupied_end_h() == 0) {
    m.set_occupied_start_h(occupancy.start_hour);
    m.set_occupied_end_h(occupancy.end_hour);
  }
  if (m.ase_threshold_lux() == 0) m.set_ase_threshold_lux(defaults.ase_threshold_lux);
  if (m.ase_min_hours() == 0) m.set_ase_min_hours(defaults.ase_min_hours);
  if (m.operation_sensor_percent() == 0) {
    m.set_operation_sensor_percent(defaults.operation_sensor_percent);
  }
  if (m.operation_threshold_lux() == 0) {
    m.set_operation_threshold_lux(defaults.operation_threshold_lux);
  }
  FENESTRA_RETURN_IF_ERROR(CheckLux(m.ase_threshold_lux(), "ase_threshold_lux", false));
  FENESTRA_RETURN_IF_ERROR(CheckLux(m.operation_threshold_lux(), "operation_threshold_lux", false));
  if (!(m.ase_min_hours() >= 1 && m.ase_min_hours() <= kMaxAseHours)) {
    return InvalidJobField("metrics.ase_min_hours", absl::StrCat("must be in [1, ", kMaxAseHours,
                                                                 "] h, got ", m.ase_min_hours()));
  }
  if (!(m.operation_sensor_percent() > 0 && m.operation_sensor_percent() <= 100)) {
    return InvalidJobField(
        "metrics.operation_sensor_percent",
        absl::StrCat("must be in (0, 100] %, got ", m.operation_sensor_percent()));
  }
  FENESTRA_RETURN_IF_ERROR(CheckLux(m.udi_lower_lux(), "udi_lower_lux", true));
  FENESTRA_RETURN_IF_ERROR(CheckLux(m.udi_upper_lux(), "udi_upper_lux", false));
  if (!(m.udi_lower_lux() < m.udi_upper_lux())) {
    return InvalidJobField("metrics",
                           absl::StrCat("udi_lower_lux ", m.udi_lower_lux(),
                                        " must be below udi_upper_lux ", m.udi_upper_lux()));
  }
  FENESTRA_RETURN_IF_ERROR(CheckLux(m.da_threshold_lux(), "da_threshold_lux", false));
  if (!(m.sda_time_fraction_percent() > 0 && m.sda_time_fraction_percent() <= 100)) {
    return InvalidJobField(
        "metrics.sda_time_fraction_percent",
        absl::StrCat("must be in (0, 100] %, got ", m.sda_time_fraction_percent()));
  }
  for (const auto& [hour, field] : {std::pair{m.occupied_start_h(), "occupied_start_h"},
                                    std::pair{m.occupied_end_h(), "occupied_end_h"}}) {
    if (!(hour >= 0 && hour <= 24)) {
      return InvalidJobField(absl::StrCat("metrics.", field),
                             absl::StrCat("must be in [0, 24] h, got ", hour));
    }
  }
  if (m.occupied_start_h() == m.occupied_end_h()) {
    return InvalidJobField("metrics", "occupied_start_h and occupied_end_h must differ");
  }
  return absl::OkStatus();
}

absl::Status CheckObjective(const v1::Objective& objective) {
  if (!v1::Metric_IsValid(objective.metric())) {
    return InvalidJobField("objective.metric",
                           absl::StrCat("unknown metric ", static_cast<int>(objective.metric())));
  }
  if (!v1::Goal_IsValid(objective.goal())) {
    return InvalidJobField("objective.goal",
                           absl::StrCat("unknown goal ", static_cast<int>(objective.goal()),
                                        " (GOAL_MAXIMIZE, GOAL_MINIMIZE or GOAL_TARGET)"));
  }
  if (!(objective.target() >= 0 && objective.target() <= MetricUpperBound(objective.metric()))) {
    return InvalidJobField("objective.target",
                           absl::StrCat("must be in ", MetricRange(objective.metric()),
                                        " (a metric's value), got ", objective.target()));
  }
  if (!(objective.target_tolerance() >= 0 && objective.target_tolerance() <= 100)) {
    return InvalidJobField(
        "objective.target_tolerance",
        absl::StrCat("must be in [0, 100] %, got ", objective.target_tolerance()));
  }
  return absl::OkStatus();
}

// The objective's constraints checked, constraint_standard_errors filled in where there are
// any (job.proto; the default in vns.h).
absl::Status FillConstraints(v1::Objective& objective) {
  if (objective.constraints_size() > kMaxConstraints) {
    return InvalidJobField("objective.constraints",
                           absl::StrCat("at most ", kMaxConstraints, " constraints, got ",
                                        objective.constraints_size()));
  }
  for (int i = 0; i < objective.constraints_size(); ++i) {
    const v1::Constraint& c = objective.constraints(i);
    const std::string field = absl::StrCat("objective.constraints[", i, "]");
    if (!v1::Metric_IsValid(c.metric()) || !ToSceneMetric(c.metric()).ok()) {
      return InvalidJobField(field + ".metric",
                             absl::StrCat("unknown metric ", static_cast<int>(c.metric())));
    }
    if (c.bound() != v1::Constraint::AT_MOST && c.bound() != v1::Constraint::AT_LEAST) {
      return InvalidJobField(field + ".bound", absl::StrCat("must be AT_MOST or AT_LEAST, got ",
                                                            static_cast<int>(c.bound())));
    }
    if (!(c.value() >= 0 && c.value() <= MetricUpperBound(c.metric()))) {
      return InvalidJobField(field + ".value",
                             absl::StrCat("must be in ", MetricRange(c.metric()),
                                          " (the metric's range), got ", c.value()));
    }
  }
  const double k = objective.constraint_standard_errors();
  if (!(k >= 0 && k <= kMaxConstraintStandardErrors)) {
    return InvalidJobField(
        "objective.constraint_standard_errors",
        absl::StrCat("must be in (0, ", kMaxConstraintStandardErrors, "] (0 = the default, ",
                     kDefaultConstraintStandardErrors, "), got ", k));
  }
  if (k == 0 && objective.constraints_size() > 0) {
    objective.set_constraint_standard_errors(kDefaultConstraintStandardErrors);
  }
  return absl::OkStatus();
}

// One objective of a Pareto search: a known metric, maximized or minimized (the goal filled
// in), nothing else.
absl::Status FillParetoObjective(v1::Objective& o, const std::string& field) {
  if (!v1::Metric_IsValid(o.metric()) || !ToSceneMetric(o.metric()).ok()) {
    return InvalidJobField(field + ".metric",
                           absl::StrCat("unknown metric ", static_cast<int>(o.metric())));
  }
  if (o.goal() == v1::GOAL_UNSPECIFIED) o.set_goal(v1::GOAL_MAXIMIZE);
  if (o.goal() != v1::GOAL_MAXIMIZE && o.goal() != v1::GOAL_MINIMIZE) {
    return InvalidJobField(field + ".goal", "must be GOAL_MAXIMIZE or GOAL_MINIMIZE");
  }
  if (o.target() != 0 || o.target_tolerance() != 0 || o.constraints_size() > 0 ||
      o.constraint_standard_errors() != 0) {
    return InvalidJobField(field,
                           "a Pareto objective has a metric and a goal only (constraints "
                           "go to the job's objective.constraints)");
  }
  return absl::OkStatus();
}

// A Pareto search checked, its defaults filled in (job.proto, ParetoSearch).
absl::Status FillPareto(v1::Job& job) {
  if (!job.has_pareto()) return absl::OkStatus();
  const v1::Objective& single = job.objective();
  if (single.metric() != v1::METRIC_UNSPECIFIED || single.goal() != v1::GOAL_UNSPECIFIED ||
      single.target() != 0 || single.target_tolerance() != 0) {
    return InvalidJobField("objective",
                           "a Pareto search takes its objectives from "
                           "pareto.objectives: objective holds only constraints");
  }
  v1::ParetoSearch& p = *job.mutable_pareto();
  if (p.objectives_size() < 2 || p.objectives_size() > 3) {
    return InvalidJobField("pareto.objectives",
                           absl::StrCat("two or three objectives, got ", p.objectives_size()));
  }
  std::set<int> metrics;
  for (int i = 0; i < p.objectives_size(); ++i) {
    const std::string field = absl::StrCat("pareto.objectives[", i, "]");
    FENESTRA_RETURN_IF_ERROR(FillParetoObjective(*p.mutable_objectives(i), field));
    if (!metrics.insert(p.objectives(i).metric()).second) {
      return InvalidJobField(field + ".metric", "the same metric twice");
    }
  }
  if (p.population() == 0) p.set_population(kDefaultParetoPopulation);
  if (p.population() < 4 || p.population() > kMaxParetoPopulation || p.population() % 2 != 0) {
    return InvalidJobField(
        "pareto.population",
        absl::StrCat("must be even and in [4, ", kMaxParetoPopulation, "], got ", p.population()));
  }
  if (!p.has_dominance_standard_errors()) {
    p.set_dominance_standard_errors(kDefaultDominanceStandardErrors);
  }
  const double z = p.dominance_standard_errors();
  if (!(z >= 0 && z <= kMaxConstraintStandardErrors)) {
    return InvalidJobField(
        "pareto.dominance_standard_errors",
        absl::StrCat("must be in [0, ", kMaxConstraintStandardErrors, "], got ", z));
  }
  if (job.budget().max_evaluations() < p.population()) {
    return InvalidJobField("budget.max_evaluations",
                           absl::StrCat("must hold at least one generation of ", p.population(),
                                        " designs, got ", job.budget().max_evaluations()));
  }
  return absl::OkStatus();
}

// The comfort settings filled in (job.proto, MetricSettings), and what the comfort metrics
// the search weighs need of the scene.
absl::Status FillComfort(v1::Job& job, const Scene& scene) {
  v1::MetricSettings& m = *job.mutable_metrics();
  if (m.glare_threshold() == 0) m.set_glare_threshold(kDefaultGlareThreshold);
  if (!(m.glare_threshold() > 0 && m.glare_threshold() < 1)) {
    return InvalidJobField("metrics.glare_threshold",
                           absl::StrCat("must be in (0, 1), got ", m.glare_threshold()));
  }
  if (m.cooling_start_month() == 0 && m.cooling_end_month() == 0) {
    const CoolingSeason season = DefaultCoolingSeason(scene.site.latitude_deg);
    m.set_cooling_start_month(season.start_month);
    m.set_cooling_end_month(season.end_month);
  }
  for (const auto& [month, field] : {std::pair{m.cooling_start_month(), "cooling_start_month"},
                                     std::pair{m.cooling_end_month(), "cooling_end_month"}}) {
    if (month < 1 || month > 12) {
      return InvalidJobField(absl::StrCat("metrics.", field),
                             absl::StrCat("must be a month, 1-12, got ", month));
    }
  }
  const ComfortNeeds needs = NeedsOf(SearchMetrics(job));
  if (needs.glare && scene.views.empty()) {
    return InvalidJobField("objective", "glare metrics need view points in the scene (views)");
  }
  for (const SceneWindow& w : scene.windows) {
    if (needs.Any() && w.blind && w.blind->automated_sun) {
      return InvalidJobField("objective",
                             "comfort metrics (glare, solar gains) are not taken "
                             "with an AUTOMATED_SUN blind");
    }
  }
  return absl::OkStatus();
}

absl::Status CheckNeighborhoods(const v1::Job& job) {
  for (int i = 0; i < job.neighborhoods_size(); ++i) {
    const v1::Neighborhood& n = job.neighborhoods(i);
    if (n.variables() < 0 || !(n.radius() > 0 && n.radius() <= 1)) {
      return InvalidJobField(absl::StrCat("neighborhoods[", i, "]"),
                             "needs variables >= 0 and radius in (0, 1]");
    }
  }
  return absl::OkStatus();
}

// Enough outdoor paths for every window cell, the automatic parts resolved
absl::Status CheckWindowCells(const v1::Sampling& sampling, const Scene& scene) {
  const WindowParts parts = SamplingWindowParts(sampling, scene);
  const int64_t window_cells = WindowCellsOf(scene, parts, sampling.basis_cells());
  const int batches = sampling.batches();
  // The outdoor matrix of every window (ResolveSampling bounds one window's at its most)
  const int64_t matrix_bytes =
      (window_cells + kIndoorDirectColumns) * kTregenzaBinCount * 8 * (int64_t{batches} + 2);
  if (matrix_bytes > kMaxOutdoorMatrixBytes) {
    return InvalidJobField(
        "sampling", absl::StrCat("the outdoor matrix of the scene's ", scene.windows.size(),
                                 " windows with its batches would take ", matrix_bytes >> 20,
                                 " MiB (", window_cells, " window cells x ", batches,
                                 " batches), more than the ", kMaxOutdoorMatrixBytes >> 20,
                                 " MiB allowed: fewer batches, direction cells or window parts"));
  }
  if (sampling.outdoor_paths() < window_cells * batches) {
    const std::string cells =
        scene.windows.size() == 1
            ? absl::StrCat(parts.columns, "x", parts.rows, " window parts x ",
                           sampling.basis_cells(), " direction cells")
            : absl::StrCat(window_cells, " cells of ", scene.windows.size(), " windows");
    return InvalidJobField(
        "sampling.outdoor_paths",
        absl::StrCat("must be at least one per window cell and batch (", window_cells * batches,
                     ": ", cells, " x ", batches, " batches)"));
  }
  return absl::OkStatus();
}

// The blind at every design of the job's ranges must fit the window and leave the sensors
// in the room's air.
absl::Status CheckRoomAtEveryDesign(const PreparedJob& prepared) {
  const Scene ranged = WithJobRanges(prepared.scene, prepared.job);
  for (const SceneWindow& w : ranged.windows) {
    if (!w.blind) continue;
    if (absl::Status fits = CheckBlindFits(*w.blind, w.window); !fits.ok()) {
      const std::string blind = ranged.windows.size() == 1
                                    ? "the scene's blind"
                                    : absl::StrCat("the blind of window '", w.name, "'");
      return InvalidJobField("variables", absl::StrCat("with ", blind, ": ", fits.message()));
    }
  }
  return CheckRoom(ranged);
}

// Racing's settings in `s`, their defaults filled in (RacingSettings).
absl::Status ResolveRacing(v1::Sampling& s) {
  const RacingSettings defaults;
  if (s.racing_standard_errors() == 0) s.set_racing_standard_errors(defaults.standard_errors);
  if (!(s.racing_standard_errors() >= kMinRacingStandardErrors &&
        s.racing_standard_errors() <= kMaxRacingStandardErrors)) {
    return InvalidJobField("sampling.racing_standard_errors",
                           absl::StrCat("must be in [", kMinRacingStandardErrors, ", ",
                                        kMaxRacingStandardErrors, "] (0 = the default)"));
  }
  if (s.racing_rounds().empty()) {
    for (const int parts : defaults.rounds) s.add_racing_rounds(parts);
  }
  for (int r = 0; r < s.racing_rounds_size(); ++r) {
    const int parts = s.racing_rounds(r);
    if (parts < 1 || parts >= kDesignParts || (r > 0 && parts <= s.racing_rounds(r - 1))) {
      return InvalidJobField("sampling.racing_rounds",
                             absl::StrCat("must increase, each from 1 to ", kDesignParts - 1));
    }
  }
  return absl::OkStatus();
}

}  // namespace

absl::Status InvalidJobField(const std::string& field, const std::string& reason) {
  return absl::InvalidArgumentError(absl::StrCat("job ", field, ": ", reason));
}

absl::StatusOr<v1::Sampling> ResolveSampling(const v1::Sampling& given) {
  v1::Sampling s = given;
  if (s.outdoor_paths() == 0) s.set_outdoor_paths(kDefaultOutdoorPaths);
  if (!s.has_outdoor_bounces()) s.set_outdoor_bounces(kDefaultOutdoorBounces);
  if (s.indoor_paths_per_sensor() == 0) s.set_indoor_paths_per_sensor(kDefaultIndoorPathsPerSensor);
  if (!s.has_indoor_bounces()) s.set_indoor_bounces(kDefaultIndoorBounces);
  if (s.seed() == 0) s.set_seed(kDefaultSeed);
  if (s.basis_cells() == 0) s.set_basis_cells(kDefaultBasisCells);
  if (s.backend().empty()) s.set_backend("auto");
  if (s.batches() == 0) s.set_batches(kDefaultBatches);
  if (!s.has_final_check()) s.set_final_check(kFinalCheckByDefault);
  FENESTRA_RETURN_IF_ERROR(ResolveRacing(s));
  if (s.candidates_at_once() < 0 || s.candidates_at_once() > kMaxCandidatesAtOnce) {
    return InvalidJobField(
        "sampling.candidates_at_once",
        absl::StrCat("must be in [0, ", kMaxCandidatesAtOnce, "] (0 = the default)"));
  }
  if (s.sequence() == v1::SEQUENCE_UNSPECIFIED) {
    s.set_sequence(kDefaultSequence == Sequence::kSobol ? v1::SEQUENCE_SOBOL
                                                        : v1::SEQUENCE_PSEUDO_RANDOM);
  }
  if (!v1::Sequence_IsValid(s.sequence())) {
    return InvalidJobField("sampling.sequence", "unknown sequence");
  }
  if (s.basis_cells() != 288 && s.basis_cells() != 1152) {
    return InvalidJobField("sampling.basis_cells", "must be 288 or 1152");
  }
  if (s.window_columns() < 0 || s.window_columns() > kMaxWindowPartsPerSide ||
      s.window_rows() < 0 || s.window_rows() > kMaxWindowPartsPerSide) {
    return InvalidJobField(
        "sampling.window_columns/window_rows",
        absl::StrCat("must be in [0, ", kMaxWindowPartsPerSide, "] (0 = automatic)"));
  }
  if (s.batches() < 2 || s.batches() > kMaxBatches) {
    return InvalidJobField("sampling.batches", absl::StrCat("must be in [2, ", kMaxBatches, "]"));
  }
  // The outdoor matrix's memory, with automatic parts at their most
  const auto side = [](int parts) { return parts > 0 ? parts : kMaxWindowPartsPerSide; };
  const int64_t most_cells =
      int64_t{s.basis_cells()} * side(s.window_columns()) * side(s.window_rows());
  const int64_t matrix_bytes =
      (most_cells + kIndoorDirectColumns) * kTregenzaBinCount * 8 * (int64_t{s.batches()} + 2);
  if (matrix_bytes > kMaxOutdoorMatrixBytes) {
    return InvalidJobField(
        "sampling",
        absl::StrCat("the outdoor matrix with its batches could take ", matrix_bytes >> 20,
                     " MiB (", s.basis_cells(), " direction cells x ", side(s.window_columns()),
                     "x", side(s.window_rows()), " window parts",
                     s.window_columns() == 0 || s.window_rows() == 0 ? " at most, automatic" : "",
                     " x ", s.batches(), " batches), more than the ", kMaxOutdoorMatrixBytes >> 20,
                     " MiB allowed: fewer batches, direction cells or window parts"));
  }
  const int64_t window_cells =
      int64_t{s.basis_cells()} * std::max(1, s.window_columns()) * std::max(1, s.window_rows());
  if (s.outdoor_paths() < window_cells * s.batches()) {
    return InvalidJobField("sampling.outdoor_paths",
                           absl::StrCat("must be at least one per window cell and batch (",
                                        window_cells * s.batches(), ")"));
  }
  if (s.indoor_paths_per_sensor() < s.batches()) {
    return InvalidJobField("sampling.indoor_paths_per_sensor", "must be at least the batch count");
  }
  for (const int bounces : {s.outdoor_bounces(), s.indoor_bounces()}) {
    if (bounces < -1 || bounces > kMaxBounces) {
      return InvalidJobField("sampling", absl::StrCat("bounces must be in [0, ", kMaxBounces,
                                                      "], or -1 for unlimited, got ", bounces));
    }
  }
  if (s.backend() != "auto" && s.backend() != "cpu" && s.backend() != "cuda") {
    return InvalidJobField("sampling.backend",
                           absl::StrCat("must be cpu, cuda or auto, got '", s.backend(), "'"));
  }
  return s;
}

Scene WithJobRanges(const Scene& scene, const v1::Job& job) {
  Scene ranged = scene;
  for (SceneWindow& w : ranged.windows) {
    if (!w.blind) continue;
    for (const v1::DesignVariable& v : job.variables()) {
      const DesignVariableInfo* info = FindDesignVariable(v.name());
      if (!info) continue;
      ParameterRange& range = (*w.blind).*(info->range);
      range.min = std::min(range.min, v.lower());
      range.max = std::max(range.max, v.upper());
    }
  }
  return ranged;
}

absl::StatusOr<PreparedJob> ValidateJob(const v1::Job& job, const std::string& base_dir) {
  FENESTRA_RETURN_IF_ERROR(CheckMessageText(job, "job "));
  PreparedJob prepared;
  prepared.job = job;
  FENESTRA_ASSIGN_OR_RETURN(scene, SceneOf(job, base_dir));
  prepared.scene = std::move(scene);
  v1::Job& filled = prepared.job;
  FENESTRA_RETURN_IF_ERROR(FillVariables(filled, prepared.scene, prepared.finishes));
  FENESTRA_RETURN_IF_ERROR(FillBudget(*filled.mutable_budget()));
  FENESTRA_ASSIGN_OR_RETURN(sampling, ResolveSampling(filled.sampling()));
  *filled.mutable_sampling() = sampling;
  FENESTRA_RETURN_IF_ERROR(FillMetricSettings(*filled.mutable_metrics()));
  FENESTRA_RETURN_IF_ERROR(CheckNeighborhoods(filled));
  FENESTRA_RETURN_IF_ERROR(CheckObjective(filled.objective()));
  FENESTRA_RETURN_IF_ERROR(FillConstraints(*filled.mutable_objective()));
  FENESTRA_RETURN_IF_ERROR(FillPareto(filled));
  FENESTRA_RETURN_IF_ERROR(FillComfort(filled, prepared.scene));
  FENESTRA_RETURN_IF_ERROR(CheckWindowCells(filled.sampling(), prepared.scene));
  FENESTRA_RETURN_IF_ERROR(CheckRoomAtEveryDesign(prepared));
  return prepared;
}

}  // namespace fenestra
