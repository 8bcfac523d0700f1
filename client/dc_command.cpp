// fenestra dc: daylight coefficients of a scene's sensors (146 Tregenza bins), one-stage or
// two-stage, for a number of paths or until a target error.
#include <fmt/format.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "absl/status/status.h"
#include "client/cli_util.h"
#include "client/commands.h"
#include "client/dc_options.h"
#include "core/common/radiance_matrix.h"
#include "core/dc/dc_backend.h"
#include "core/dc/one_stage.h"
#include "core/dc/rounds.h"
#include "core/dc/two_stage.h"
#include "core/geometry/scene.h"

namespace fenestra {
namespace {

// Exit code when --target-error was not reached within the limits (the matrices are written).
constexpr int kTargetNotReachedExitCode = 2;

struct DcArgs {
  DcFlags flags;
  std::string output, standard_error, format = "ascii", outdoor_matrix, indoor_matrix;
  double target_error = 0;  // 0 = trace the given paths once
  TargetErrorOptions limits;
};

// InvalidArgument unless `path` can be created: its folder exists.
absl::Status CheckWritable(const std::string& path, const std::string& flag) {
  const std::filesystem::path parent = std::filesystem::path(path).parent_path();
  if (!parent.empty() && !std::filesystem::is_directory(parent)) {
    return absl::InvalidArgumentError(
        fmt::format("{}: folder '{}' does not exist", flag, parent.string()));
  }
  return absl::OkStatus();
}

// Checks everything that needs no tracing, so bad input writes nothing.
absl::Status CheckArgs(const DcArgs& a) {
  if (const absl::Status s = CheckMethodFlags(a.flags); !s.ok()) return s;
  if (!a.standard_error.empty() && a.standard_error == a.output) {
    return absl::InvalidArgumentError("--stderr must name another file than --output");
  }
  if (const absl::Status s = CheckWritable(a.output, "--output"); !s.ok()) return s;
  if (!a.standard_error.empty()) {
    if (const absl::Status s = CheckWritable(a.standard_error, "--stderr"); !s.ok()) return s;
  }
  for (const auto& [path, flag] : {std::pair{a.outdoor_matrix, "--outdoor-matrix"},
                                   std::pair{a.indoor_matrix, "--indoor-matrix"}}) {
    if (path.empty()) continue;
    if (a.flags.method != "two-stage") {
      return absl::InvalidArgumentError(fmt::format("{} needs --method two-stage", flag));
    }
    if (const absl::Status s = CheckWritable(path, flag); !s.ok()) return s;
  }
  if (a.target_error < 0 || a.target_error >= 1) {
    return absl::InvalidArgumentError(
        fmt::format("--target-error must be in (0, 1), got {}", a.target_error));
  }
  for (const char* limit : {"--max-seconds", "--max-paths", "--max-outdoor-paths"}) {
    if (a.target_error == 0 && a.flags.command->count(limit) > 0) {
      return absl::InvalidArgumentError(fmt::format("{} needs --target-error", limit));
    }
  }
  return absl::OkStatus();
}

// Writes each (path, matrix) pair; on a failure removes what it wrote and fails.
void WriteAll(const std::vector<std::pair<std::string, const Matrix*>>& outputs,
              MatrixFormat format) {
  std::vector<std::string> written;
  for (const auto& [path, matrix] : outputs) {
    if (path.empty()) continue;
    if (const absl::Status s = WriteRadianceMatrix(path, *matrix, format); !s.ok()) {
      std::error_code ignored;
      for (const std::string& w : written) std::filesystem::remove(w, ignored);
      Fail(s);
    }
    written.push_back(path);
  }
  fmt::print("wrote {}\n", fmt::join(written, ", "));
}

// Per sensor: the sky sum with its standard error (both stages' for the two-stage method) and
// its relative standard error; the indoor stage's share of the variance when given.
void PrintSkySums(const Scene& scene, const Matrix& d, const Eigen::VectorXd& sum,
                  const Eigen::VectorXd& error, const Eigen::VectorXd* indoor_variance) {
  const Eigen::VectorXd relative = RelativeErrors(sum, error);
  for (Eigen::Index s = 0; s < sum.size(); ++s) {
    std::string share;
    if (indoor_variance != nullptr && error(s) > 0) {
      share = fmt::format(", indoor stage {:.0f}% of its variance",
                          100 * std::min(1.0, (*indoor_variance)(s) / (error(s) * error(s))));
    }
    fmt::print("  {:<12} sky sum {:.5e} sr +- {:.2e} ({:.2f}%){}, ground {:.3e} sr\n",
               scene.sensors[s].name, sum(s), error(s), 100 * relative(s), share, d(s, 0));
  }
}

void PrintRound(const Scene& scene, const RoundReport& r, bool two_stage) {
  const std::string paths = two_stage ? fmt::format("{} outdoor paths, {} indoor paths per sensor",
                                                    r.outdoor_paths, r.paths_per_sensor)
                                      : fmt::format("{} paths per sensor", r.paths_per_sensor);
  const std::string share = two_stage ? fmt::format(" (indoor stage {:.0f}% of its variance)",
                                                    100 * r.indoor_variance_share)
                                      : "";
  fmt::print("round {}: {}, {:.2f} s; largest relative SE {:.2f}% at {}{}\n", r.round + 1, paths,
             r.elapsed_seconds, 100 * r.max_relative_error, scene.sensors[r.worst_sensor].name,
             share);
  std::fflush(stdout);  // live when piped
}

// Says how tracing to the target ended; true when it reached the target.
bool PrintOutcome(const Scene& scene, const TargetOutcome& outcome, double target) {
  const RoundReport& last = outcome.rounds.back();
  if (outcome.reached) {
    fmt::print(
        "target {:.2f}% reached in {:.2f} s ({} round{}): largest sky-sum relative SE {:.2f}% "
        "({})\n",
        100 * target, last.elapsed_seconds, outcome.rounds.size(),
        outcome.rounds.size() > 1 ? "s" : "", 100 * last.max_relative_error,
        scene.sensors[last.worst_sensor].name);
    return true;
  }
  fmt::print(stderr,
             "target {:.2f}% not reached after {:.2f} s ({} round{}): largest sky-sum relative "
             "SE {:.2f}% ({}); {}\n",
             100 * target, last.elapsed_seconds, outcome.rounds.size(),
             outcome.rounds.size() > 1 ? "s" : "", 100 * last.max_relative_error,
             scene.sensors[last.worst_sensor].name, outcome.stop_reason);
  return false;
}

// One-stage: trace (once or to the target), write, report. False when a target was missed.
bool RunOneStage(const DcArgs& a, DcInput& in, MatrixFormat format) {
  const OneStageOptions options = OneStageOptionsFrom(a.flags);
  OneStageResult result;
  TargetOutcome outcome;
  if (a.target_error > 0) {
    TargetErrorOptions target = a.limits;
    target.relative_error = a.target_error;
    OneStageToTarget run = ValueOrFail(
        TraceOneStageToTarget(in.scene, in.design, options, target, in.backend.get(),
                              [&](const RoundReport& r) { PrintRound(in.scene, r, false); }));
    result = std::move(run.result);
    outcome = std::move(run.outcome);
  } else {
    result = ValueOrFail(ComputeOneStage(in.scene, in.design, options, in.backend.get()));
  }
  WriteAll({{a.output, &result.coefficients}, {a.standard_error, &result.standard_error}}, format);

  // Report
  const double all_paths =
      static_cast<double>(result.paths_per_sensor) * static_cast<double>(in.scene.sensors.size());
  fmt::print("dc: {} sensors x {} paths, {} ({}), {} backend on {} threads\n",
             in.scene.sensors.size(), result.paths_per_sensor, ReflectionLimit(options.max_bounces),
             result.importance_cells > 0 ? std::string("weight windows")
             : options.russian_roulette
                 ? fmt::format("Russian roulette below weight {}", options.roulette_threshold)
                 : std::string("no Russian roulette"),
             result.backend, result.threads);
  fmt::print("rays traced {}, {:.3g} rays/s, wall time {:.2f} s\n", result.rays_traced,
             result.rays_traced / std::max(result.wall_seconds, 1e-9), result.wall_seconds);
  if (result.importance_cells > 0) {
    fmt::print("weight windows: pilot {} paths, {} importance cells, {:.2f} branches per path\n",
               result.pilot_paths, result.importance_cells, result.branches / all_paths);
  }
  if (result.bounce_limit_paths > 0) {
    fmt::print("{} paths ({:.3g}%) were cut by the bounce limit: their light is missing\n",
               result.bounce_limit_paths, 100.0 * result.bounce_limit_paths / all_paths);
  }
  PrintSkySums(in.scene, result.coefficients, result.sky_sum, result.sky_sum_standard_error,
               nullptr);
  fmt::print(
      "mean relative standard error {:.2f}% (coefficients above 1% of their row's maximum)\n",
      100 * MeanRelativeStandardError(result));
  return a.target_error <= 0 || PrintOutcome(in.scene, outcome, a.target_error);
}

// Two-stage: D = I O from the outdoor stage (outdoor surfaces, from the window) and the indoor
// stage (indoor surfaces and the blind, to the window), traced once or to the target.
bool RunTwoStage(const DcArgs& a, DcInput& in, MatrixFormat format) {
  const OutdoorOptions outdoor_options = OutdoorOptionsFrom(a.flags, in.parts);
  const IndoorOptions indoor_options = IndoorOptionsFrom(a.flags, in.parts);
  TwoStageToTarget run;
  if (a.target_error > 0) {
    TargetErrorOptions target = a.limits;
    target.relative_error = a.target_error;
    run = ValueOrFail(TraceTwoStageToTarget(
        in.scene, in.design, outdoor_options, indoor_options, target, in.backend.get(),
        [&](const RoundReport& r) { PrintRound(in.scene, r, true); }));
  } else {
    run.outdoor = ValueOrFail(ComputeOutdoorStage(in.scene, outdoor_options, in.backend.get()));
    run.indoor =
        ValueOrFail(ComputeIndoorStage(in.scene, in.design, indoor_options, in.backend.get()));
    run.combined = ValueOrFail(CombineStages(run.indoor, run.outdoor));
  }
  const OutdoorResult& o = run.outdoor;
  const IndoorResult& i = run.indoor;
  const TwoStageResult& d = run.combined;
  WriteAll({{a.output, &d.coefficients},
            {a.standard_error, &d.standard_error},
            {a.outdoor_matrix, &o.coefficients},
            {a.indoor_matrix, &i.coefficients}},
           format);

  // Report (O's window cells, not its identity rows)
  const Eigen::Index cells = o.sky_view.size();
  fmt::print("dc two-stage on {}, {}x{} window parts x {} direction cells:\n", o.backend,
             in.parts.columns, in.parts.rows, o.basis_cells);
  fmt::print(
      "  outdoor stage: {} paths, {}, {} triangles, {} rays, {:.2f} s, mean relative SE of O "
      "{:.4f}\n",
      o.paths_per_cell * cells, ReflectionLimit(outdoor_options.max_bounces), o.triangles,
      o.rays_traced, o.wall_seconds,
      MeanRelativeError(o.coefficients.topRows(cells), o.standard_error.topRows(cells)));
  fmt::print(
      "  indoor stage: {} sensors x {} paths in {} batches, {}, {} triangles, {} rays, {:.2f} "
      "s, mean relative SE of I {:.4f}\n",
      in.scene.sensors.size(), i.paths_per_sensor, i.batches.size(),
      ReflectionLimit(indoor_options.max_bounces), i.triangles, i.rays_traced, i.wall_seconds,
      MeanRelativeError(i.coefficients, i.standard_error));
  fmt::print("  D = I O: mean relative SE {:.4f}; sky sums with both stages' errors:\n",
             MeanRelativeError(d.coefficients, d.standard_error));
  const Eigen::VectorXd indoor_variance = IndoorSkySumVariance(i, o);
  PrintSkySums(in.scene, d.coefficients, d.sky_sum, d.sky_sum_standard_error, &indoor_variance);
  return a.target_error <= 0 || PrintOutcome(in.scene, run.outcome, a.target_error);
}

}  // namespace

void AddDcCommand(CLI::App& app) {
  auto args = std::make_shared<DcArgs>();
  CLI::App* command = app.add_subcommand(
      "dc",
      "Trace daylight coefficients (rows = sensors, 146 columns: bin 0 = ground, 1..145 = "
      "Tregenza sky patches), one-stage or two-stage, for given paths or to a target error");
  AddDcFlags(command, &args->flags);
  command->add_option("-o,--output", args->output, "Output matrix D [sr]")->required();
  command->add_option("--stderr", args->standard_error,
                      "Also write the standard error of each coefficient [sr]");
  command->add_option(
      "--outdoor-matrix", args->outdoor_matrix,
      "Two-stage: also write O ((window cells + 292) x 146: the window cells' "
      "reflected radiance, then the identity for each block of direct columns) [-]");
  command->add_option(
      "--indoor-matrix", args->indoor_matrix,
      "Two-stage: also write I (sensors x (window cells + 292): light through the "
      "window cells, then straight from each sky bin: light reflected in the room, then "
      "the sensor's own view) [sr]");
  command->add_option("--format", args->format, "Matrix format")
      ->check(CLI::IsMember({"ascii", "float"}))
      ->capture_default_str();
  command->add_option(
      "--target-error", args->target_error,
      fmt::format(
          "Trace in rounds until every sensor's sky sum (D over bins 1..145) has a relative "
          "standard error at most this, e.g. 0.02. The first round traces the paths asked for; "
          "each next one, with its own random streams, is sized from the errors so far (error ~ "
          "1/sqrt(paths)) to land at {:.0f}% of the target; the rounds are merged by path "
          "count. Two-stage: from each sensor's variance split into the indoor stage's (the "
          "scatter of its batches through the mean O) and the outdoor stage's (the rest), and "
          "each stage's closest-hit rays per path, each round grows each stage by the factor "
          "that reaches the target at the least cost (paths in proportion to sqrt(variance / "
          "rays)); a stage whose "
          "share is already small is not traced again. Exit code {} when a limit stops it first "
          "(the matrices are still written)",
          100 * kTargetAim, kTargetNotReachedExitCode));
  command
      ->add_option("--max-seconds", args->limits.max_seconds,
                   "With --target-error: stop tracing after this many seconds")
      ->capture_default_str();
  command
      ->add_option("--max-paths", args->limits.max_paths_per_sensor,
                   "With --target-error: at most this many paths per sensor (one-stage; "
                   "two-stage: indoor)")
      ->capture_default_str();
  command
      ->add_option("--max-outdoor-paths", args->limits.max_outdoor_paths,
                   "With --target-error, two-stage: at most this many outdoor paths")
      ->capture_default_str();
  command->callback([args] {
    if (const absl::Status s = CheckArgs(*args); !s.ok()) Fail(s);
    DcInput input = ValueOrFail(LoadDcInput(args->flags));
    const MatrixFormat format =
        args->format == "float" ? MatrixFormat::kFloat : MatrixFormat::kAscii;
    const bool done = args->flags.method == "two-stage" ? RunTwoStage(*args, input, format)
                                                        : RunOneStage(*args, input, format);
    if (!done) throw CLI::RuntimeError(kTargetNotReachedExitCode);
  });
}

}  // namespace fenestra
