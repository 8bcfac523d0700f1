// fenestra dc: one-stage daylight coefficients of a scene's sensors (146 Tregenza bins).
#include <fmt/format.h>

#include <filesystem>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "absl/status/status.h"
#include "client/cli_util.h"
#include "client/commands.h"
#include "core/common/radiance_matrix.h"
#include "core/dc/dc_backend.h"
#include "core/dc/one_stage.h"
#include "core/dc/two_stage.h"
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
    std::string method = "one-stage", backend = "cpu", outdoor_matrix, indoor_matrix;
    int basis = 288;
    std::string window_parts = "auto";
    int64_t outdoor_paths = 20'000'000;
    int64_t indoor_paths = 200'000;
  };
  auto args = std::make_shared<DcArgs>();
  // D = I O: the outdoor stage (outdoor surfaces, from the window), the indoor stage
  // (indoor surfaces and the blind, to the window), then the product.
  static const auto RunTwoStage = [](const DcArgs& a, const Scene& scene, const BlindDesign& design,
                                     DcBackend& backend, MatrixFormat format) {
    const WindowParts parts = a.window_parts == "auto"
                                  ? AutomaticWindowParts(scene.window)
                                  : ValueOrFail(ParseWindowParts(a.window_parts));
    // What both stages take from the command line
    const auto set_common = [&](auto& options) {
      options.max_bounces = a.bounces > 0 ? a.bounces : -1;
      options.seed = a.seed;
      options.threads = a.threads;
      options.basis_cells = a.basis;
      options.parts = parts;
    };
    OutdoorOptions outdoor;
    outdoor.paths = a.outdoor_paths;
    set_common(outdoor);
    IndoorOptions indoor;
    indoor.paths_per_sensor = a.indoor_paths;
    set_common(indoor);
    const OutdoorResult o = ValueOrFail(ComputeOutdoorStage(scene, outdoor, &backend));
    const IndoorResult i = ValueOrFail(ComputeIndoorStage(scene, design, indoor, &backend));
    const TwoStageResult d = ValueOrFail(CombineStages(i, o));
    WriteAll({{a.output, &d.coefficients},
              {a.standard_error, &d.standard_error},
              {a.outdoor_matrix, &o.coefficients},
              {a.indoor_matrix, &i.coefficients}},
             format);
    const std::string limit = a.bounces > 0
                                  ? fmt::format("at most {} reflections per stage", a.bounces)
                                  : std::string("unlimited reflections");
    fmt::print("dc two-stage on {}, {}x{} window parts x {} direction cells, {}:\n", backend.Name(),
               parts.columns, parts.rows, a.basis, limit);
    fmt::print(
        "  outdoor stage: {} paths, {} triangles, {} rays, {:.2f} s, mean relative SE {:.4f}\n",
        o.paths_per_cell * o.sky_view.size(), o.triangles, o.rays_traced, o.wall_seconds,
        MeanRelativeError(o.coefficients.topRows(o.sky_view.size()),
                          o.standard_error.topRows(o.sky_view.size())));
    fmt::print(
        "  indoor stage: {} sensors x {} paths, {} triangles, {} rays, {:.2f} s, mean "
        "relative SE {:.4f}\n",
        scene.sensors.size(), i.paths_per_sensor, i.triangles, i.rays_traced, i.wall_seconds,
        MeanRelativeError(i.coefficients, i.standard_error));
    fmt::print("  D = I O: mean relative SE {:.4f}\n",
               MeanRelativeError(d.coefficients, d.standard_error));
    for (size_t s = 0; s < scene.sensors.size(); ++s) {
      fmt::print("  {:<12} sky sum {:.5e} sr, ground {:.3e} sr\n", scene.sensors[s].name,
                 d.coefficients.row(static_cast<Eigen::Index>(s)).tail(145).sum(),
                 d.coefficients(static_cast<Eigen::Index>(s), 0));
    }
  };
  CLI::App* command = app.add_subcommand(
      "dc",
      "Trace daylight coefficients (rows = sensors, 146 columns: bin 0 = ground, 1..145 = "
      "Tregenza sky patches), one-stage or two-stage");
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
  command->add_flag("--no-weight-windows", args->no_weight_windows,
                    "Plain Russian roulette instead of weight windows (one-stage)");
  command->add_flag("--no-roulette", args->no_roulette,
                    "No Russian roulette (needs --bounces > 0)");
  command
      ->add_option("--roulette-threshold", args->roulette_threshold,
                   "Path weight below which Russian roulette plays, in (0, 1]")
      ->capture_default_str();
  command->add_option("--method", args->method, "one-stage, or two-stage (D = I O)")
      ->check(CLI::IsMember({"one-stage", "two-stage"}))
      ->capture_default_str();
  command->add_option("--backend", args->backend, "cpu, cuda or auto")
      ->check(CLI::IsMember({"cpu", "cuda", "auto"}))
      ->capture_default_str();
  command
      ->add_option("--basis", args->basis,
                   "Two-stage: direction cells of each window part, 288 or 1152")
      ->check(CLI::IsMember({288, 1152}))
      ->capture_default_str();
  command
      ->add_option("--window-parts", args->window_parts,
                   "Two-stage: the window split into COLUMNSxROWS parts, each with its own "
                   "direction cells; auto = parts of at most 0.5 m")
      ->capture_default_str();
  command->add_option("--outdoor-paths", args->outdoor_paths, "Two-stage: outdoor paths in total")
      ->capture_default_str();
  command->add_option("--indoor-paths", args->indoor_paths, "Two-stage: indoor paths per sensor")
      ->capture_default_str();
  command->add_option("--outdoor-matrix", args->outdoor_matrix,
                      "Two-stage: also write O ((window cells + 146) x 146: the window cells' "
                      "reflected radiance, then the identity for the direct columns) [-]");
  command->add_option("--indoor-matrix", args->indoor_matrix,
                      "Two-stage: also write I (sensors x (window cells + 146): light through the "
                      "window cells, then straight from each sky bin) [sr]");
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
    for (const auto& [path, flag] : {std::pair{args->outdoor_matrix, "--outdoor-matrix"},
                                     std::pair{args->indoor_matrix, "--indoor-matrix"}}) {
      if (path.empty()) continue;
      if (args->method != "two-stage") {
        Fail(absl::InvalidArgumentError(fmt::format("{} needs --method two-stage", flag)));
      }
      if (const absl::Status s = CheckWritable(path, flag); !s.ok()) Fail(s);
    }
    const Scene scene = ValueOrFail(LoadScene(args->scene));
    const BlindDesign design =
        ValueOrFail(DesignWithOverrides(scene, ValueOrFail(ParseDesignValues(args->set))));
    std::unique_ptr<DcBackend> backend = ValueOrFail(MakeBackend(args->backend));
    const MatrixFormat matrix_format =
        args->format == "float" ? MatrixFormat::kFloat : MatrixFormat::kAscii;
    if (args->method == "two-stage") {
      RunTwoStage(*args, scene, design, *backend, matrix_format);
      return;
    }
    OneStageOptions options;
    options.paths_per_sensor = args->paths;
    options.max_bounces = args->bounces;
    options.seed = args->seed;
    options.threads = args->threads;
    options.russian_roulette = !args->no_roulette;
    options.roulette_threshold = args->roulette_threshold;
    options.weight_windows = !args->no_weight_windows;

    // Trace and write
    const OneStageResult result =
        ValueOrFail(ComputeOneStage(scene, design, options, backend.get()));
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
