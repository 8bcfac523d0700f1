// fenestra dc: one-stage daylight coefficients of a scene's sensors (146 Tregenza bins).
#include <fmt/format.h>

#include <filesystem>
#include <memory>
#include <string>

#include "absl/status/status.h"
#include "client/cli_util.h"
#include "client/commands.h"
#include "core/common/radiance_matrix.h"
#include "core/dc/one_stage.h"
#include "core/geometry/scene.h"

namespace fenestra {
namespace {

// InvalidArgument unless `path` can be created: its folder exists.
absl::Status CheckWritable(const std::string& path, const std::string& flag) {
  const std::filesystem::path parent = std::filesystem::path(path).parent_path();
  if (!parent.empty() && !std::filesystem::is_directory(parent)) {
    return absl::InvalidArgumentError(
        fmt::format("{}: folder '{}' does not exist", flag, parent.string()));
  }
  return absl::OkStatus();
}

}  // namespace

void AddDcCommand(CLI::App& app) {
  struct DcArgs {
    std::string scene, output, standard_error, set, format = "ascii";
    int64_t paths = 100000;
    int bounces = 0;
    uint64_t seed = 1;
    int threads = 0;
    bool no_roulette = false;
    bool no_weight_windows = false;
    double roulette_threshold = OneStageOptions{}.roulette_threshold;
  };
  auto args = std::make_shared<DcArgs>();
  CLI::App* command = app.add_subcommand(
      "dc",
      "Trace one-stage daylight coefficients (rows = sensors, 146 columns: bin 0 = "
      "ground, 1..145 = Tregenza sky patches)");
  command->add_option("SCENE", args->scene, "Scene file (JSON)")->required();
  command->add_option("-o,--output", args->output, "Output matrix D [sr]")->required();
  command->add_option("--stderr", args->standard_error,
                      "Also write the standard error of each coefficient [sr]");
  command->add_option("--paths", args->paths, "Paths per sensor")->capture_default_str();
  command
      ->add_option("--bounces", args->bounces,
                   "Surface reflections allowed (Radiance -ab minus 1); 0 = unlimited, "
                   "ended by Russian roulette")
      ->capture_default_str();
  command->add_option("--seed", args->seed, "Random seed")->capture_default_str();
  command->add_option("--threads", args->threads, "CPU threads (0 = all cores)")
      ->capture_default_str();
  command->add_option("--set", args->set, "Blind design values, e.g. alpha=0.5,width=0.12");
  command->add_flag("--no-roulette", args->no_roulette,
                    "No Russian roulette (needs --bounces > 0)");
  command
      ->add_option("--roulette-threshold", args->roulette_threshold,
                   "Path weight below which Russian roulette plays, in (0, 1]")
      ->capture_default_str();
  command->add_option("--format", args->format, "Matrix format")
      ->check(CLI::IsMember({"ascii", "float"}))
      ->capture_default_str();
  command->callback([args] {
    // Check everything before tracing, so bad input writes nothing
    if (!args->standard_error.empty() && args->standard_error == args->output) {
      Fail(absl::InvalidArgumentError("--stderr must name another file than --output"));
    }
    if (const absl::Status s = CheckWritable(args->output, "--output"); !s.ok()) Fail(s);
    if (!args->standard_error.empty()) {
      if (const absl::Status s = CheckWritable(args->standard_error, "--stderr"); !s.ok()) {
        Fail(s);
      }
    }
    const Scene scene = ValueOrFail(LoadScene(args->scene));
    const BlindDesign design =
        ValueOrFail(DesignWithOverrides(scene, ValueOrFail(ParseDesignValues(args->set))));
    OneStageOptions options;
    options.paths_per_sensor = args->paths;
    options.max_bounces = args->bounces;
    options.seed = args->seed;
    options.threads = args->threads;
    options.russian_roulette = !args->no_roulette;
    options.roulette_threshold = args->roulette_threshold;
    options.weight_windows = !args->no_weight_windows;

    // Trace and write
    const OneStageResult result = ValueOrFail(ComputeOneStage(scene, design, options));
    const MatrixFormat format =
        args->format == "float" ? MatrixFormat::kFloat : MatrixFormat::kAscii;
    if (const absl::Status s = WriteRadianceMatrix(args->output, result.coefficients, format);
        !s.ok()) {
      Fail(s);
    }
    if (!args->standard_error.empty()) {
      const absl::Status s =
          WriteRadianceMatrix(args->standard_error, result.standard_error, format);
      if (!s.ok()) {
        std::error_code ignored;
        std::filesystem::remove(args->output, ignored);  // both files or neither
        Fail(s);
      }
    }

    // Report
    const double rays_per_second = result.rays_traced / std::max(result.wall_seconds, 1e-9);
    fmt::print("dc: {} sensors x {} paths, {} ({}), {} backend on {} threads\n",
               scene.sensors.size(), result.paths_per_sensor,
               args->bounces > 0 ? fmt::format("at most {} reflections", args->bounces)
                                 : std::string("unlimited reflections"),
               result.importance_cells > 0 ? std::string("weight windows")
               : options.russian_roulette
                   ? fmt::format("Russian roulette below weight {}", options.roulette_threshold)
                   : std::string("no Russian roulette"),
               result.backend, result.threads);
    fmt::print("rays traced {}, {:.3g} rays/s, wall time {:.2f} s\n", result.rays_traced,
               rays_per_second, result.wall_seconds);
    if (result.importance_cells > 0) {
      fmt::print("weight windows: pilot {} paths, {} importance cells, {:.2f} branches per path\n",
                 result.pilot_paths, result.importance_cells,
                 static_cast<double>(result.branches) /
                     (static_cast<double>(result.paths_per_sensor) * scene.sensors.size()));
    }
    if (result.bounce_limit_paths > 0) {
      fmt::print("{} paths ({:.3g}%) were cut by the bounce limit: their light is missing\n",
                 result.bounce_limit_paths,
                 100.0 * result.bounce_limit_paths /
                     (static_cast<double>(result.paths_per_sensor) * scene.sensors.size()));
    }
    for (size_t s = 0; s < scene.sensors.size(); ++s) {
      fmt::print(
          "  {:<12} sky sum {:.5e} sr +- {:.2e} ({:.2f}%), ground {:.3e} sr\n",
          scene.sensors[s].name, result.sky_sum(s), result.sky_sum_standard_error(s),
          result.sky_sum(s) > 0 ? 100 * result.sky_sum_standard_error(s) / result.sky_sum(s) : 0.0,
          result.coefficients(s, 0));
    }
    fmt::print(
        "mean relative standard error {:.2f}% (coefficients above 1% of their row's "
        "maximum)\n",
        100 * MeanRelativeStandardError(result));
    fmt::print("wrote {}{}\n", args->output,
               args->standard_error.empty() ? "" : " and " + args->standard_error);
  });
}

}  // namespace fenestra
