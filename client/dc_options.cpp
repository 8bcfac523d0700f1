#include "client/dc_options.h"

#include <fmt/format.h>

#include <CLI/CLI.hpp>
#include <span>
#include <utility>

#include "client/cli_util.h"
#include "core/common/status_macros.h"
#include "core/optimize/job.h"
#include "core/trace/room_check.h"

namespace fenestra {
namespace {

// The jobs' sampling defaults, from the one place that fills them in.
const v1::Sampling& JobSamplingDefaults() {
  static const v1::Sampling defaults = *ResolveSampling(v1::Sampling());
  return defaults;
}

constexpr const char* kOneStageOnly[] = {"--paths", "--bounces", "--no-weight-windows"};
constexpr const char* kTwoStageOnly[] = {"--outdoor-paths",  "--indoor-paths", "--outdoor-bounces",
                                         "--indoor-bounces", "--basis",        "--window-parts",
                                         "--batches"};

bool Given(const DcFlags& flags, const char* name) {
  return flags.command != nullptr && flags.command->count(name) > 0;
}

// The roulette flags apply to both methods; the stages keep their own defaults unless given.
template <class Options>
void SetRoulette(const DcFlags& flags, Options& options) {
  if (Given(flags, "--no-roulette")) options.russian_roulette = !flags.no_roulette;
  if (Given(flags, "--roulette-threshold")) options.roulette_threshold = flags.roulette_threshold;
}

Sequence SequenceFrom(const DcFlags& flags) {
  return flags.sequence == "sobol" ? Sequence::kSobol : Sequence::kPseudoRandom;
}

// What both stages of the two-stage method take from the flags alike.
template <class StageOptions>
void SetStageOptions(const DcFlags& flags, WindowParts parts, StageOptions& options) {
  options.seed = flags.seed;
  options.sequence = SequenceFrom(flags);
  options.threads = flags.threads;
  options.basis_cells = flags.basis;
  options.parts = parts;
  options.batches = flags.batches;
  SetRoulette(flags, options);
}

void AddOneStageFlags(CLI::App* command, DcFlags* flags) {
  command->add_option("--paths", flags->paths, "One-stage: paths per sensor")
      ->capture_default_str();
  command
      ->add_option("--bounces", flags->bounces,
                   "One-stage only: surface reflections a path may make, indoors and outdoors "
                   "together (Radiance -ab minus 1); 0 = none (the direct component), -1 = "
                   "unlimited, ended by "
                   "Russian roulette. "
                   "The two-stage method takes --outdoor-bounces and --indoor-bounces")
      ->capture_default_str();
  command->add_flag("--no-weight-windows", flags->no_weight_windows,
                    "One-stage: plain Russian roulette instead of weight windows");
  command->add_flag("--no-roulette", flags->no_roulette,
                    "No Russian roulette (needs a bounce limit)");
  command
      ->add_option("--roulette-threshold", flags->roulette_threshold,
                   fmt::format("Path weight below which Russian roulette plays, in (0, 1]; "
                               "two-stage: both stages, by default {}",
                               OutdoorOptions{}.roulette_threshold))
      ->capture_default_str();
}

// `paths_default` says where the path counts' defaults come from.
void AddTwoStageFlags(CLI::App* command, DcFlags* flags, const std::string& paths_default) {
  command
      ->add_option("--outdoor-paths", flags->outdoor_paths,
                   fmt::format("Two-stage: outdoor paths in total ({})", paths_default))
      ->capture_default_str();
  command
      ->add_option("--indoor-paths", flags->indoor_paths,
                   fmt::format("Two-stage: indoor paths per sensor ({})", paths_default))
      ->capture_default_str();
  command
      ->add_option("--outdoor-bounces", flags->outdoor_bounces,
                   "Two-stage: reflections of an outdoor path, from the window to the sky (the "
                   "jobs' default); 0 = the sky seen directly, -1 = unlimited, ended by Russian "
                   "roulette")
      ->capture_default_str();
  command
      ->add_option("--indoor-bounces", flags->indoor_bounces,
                   "Two-stage: reflections of an indoor path, from the sensor to the window (the "
                   "jobs' default); 0 = the window seen directly, -1 = unlimited, ended by "
                   "Russian roulette")
      ->capture_default_str();
  command
      ->add_option("--basis", flags->basis,
                   "Two-stage: direction cells of each window part, 288 or 1152")
      ->check(CLI::IsMember({288, 1152}))
      ->capture_default_str();
  command
      ->add_option("--window-parts", flags->window_parts,
                   "Two-stage: the window split into COLUMNSxROWS parts, each with its own "
                   "direction cells; auto = parts of at most 0.5 m")
      ->capture_default_str();
  command
      ->add_option("--batches", flags->batches,
                   "Two-stage: independent batches of each stage's paths, paired (D_b = I_b "
                   "O_b); their scatter gives the standard errors, both stages' noise included")
      ->check(CLI::Range(2, kMaxBatches))
      ->capture_default_str();
}

}  // namespace

void AddDcFlags(CLI::App* command, DcFlags* flags, int64_t paths_divisor) {
  const v1::Sampling& job = JobSamplingDefaults();
  flags->command = command;
  flags->paths /= paths_divisor;
  flags->seed = job.seed();
  flags->outdoor_paths = job.outdoor_paths() / paths_divisor;
  flags->indoor_paths = job.indoor_paths_per_sensor() / paths_divisor;
  flags->outdoor_bounces = job.outdoor_bounces();
  flags->indoor_bounces = job.indoor_bounces();
  flags->basis = job.basis_cells();

  command->add_option("SCENE", flags->scene, "Scene file (JSON)")->required();
  command->add_option("--method", flags->method, "one-stage, or two-stage (D = I O)")
      ->check(CLI::IsMember({"one-stage", "two-stage"}))
      ->capture_default_str();
  command->add_option("--set", flags->set, "Blind design values, e.g. alpha=0.5,width=0.12");
  command->add_option("--backend", flags->backend, "cpu, cuda or auto (a GPU when there is one)")
      ->check(CLI::IsMember({"cpu", "cuda", "auto"}))
      ->capture_default_str();
  command->add_option("--seed", flags->seed, "Random seed")->capture_default_str();
  command
      ->add_option("--sequence", flags->sequence,
                   "How a path's first draws are made: pseudo-random, or sobol (Owen-scrambled "
                   "Sobol points, one randomization per batch; standard errors from the batches)")
      ->check(CLI::IsMember({"pseudo-random", "sobol"}))
      ->capture_default_str();
  command->add_option("--threads", flags->threads, "CPU threads (0 = all cores)")
      ->capture_default_str();

  AddOneStageFlags(command, flags);
  AddTwoStageFlags(command, flags,
                   paths_divisor == 1 ? std::string("the jobs' default")
                                      : fmt::format("the jobs' default / {}", paths_divisor));
}

absl::Status CheckMethodFlags(const DcFlags& flags) {
  const bool two_stage = flags.method == "two-stage";
  if (two_stage && Given(flags, "--bounces")) {
    return absl::InvalidArgumentError(fmt::format(
        "--bounces is the one-stage limit; the two-stage method takes --outdoor-bounces "
        "(default {}) and --indoor-bounces (default {}), -1 = unlimited",
        JobSamplingDefaults().outdoor_bounces(), JobSamplingDefaults().indoor_bounces()));
  }
  for (const char* name : two_stage ? std::span<const char* const>(kOneStageOnly)
                                    : std::span<const char* const>(kTwoStageOnly)) {
    if (Given(flags, name)) {
      return absl::InvalidArgumentError(fmt::format("{} applies to --method {} only", name,
                                                    two_stage ? "one-stage" : "two-stage"));
    }
  }
  for (const auto& [value, name] : {std::pair{flags.bounces, "--bounces"},
                                    std::pair{flags.outdoor_bounces, "--outdoor-bounces"},
                                    std::pair{flags.indoor_bounces, "--indoor-bounces"}}) {
    if (value < -1) {
      return absl::InvalidArgumentError(
          fmt::format("{} must be >= 0, or -1 for unlimited, got {}", name, value));
    }
  }
  return absl::OkStatus();
}

absl::StatusOr<DcInput> LoadDcInput(const DcFlags& flags) {
  DcInput input;
  FENESTRA_ASSIGN_OR_RETURN(scene, LoadValidScene(flags.scene));
  input.scene = std::move(scene);
  FENESTRA_ASSIGN_OR_RETURN(values, ParseDesignValues(flags.set));
  FENESTRA_ASSIGN_OR_RETURN(design, DesignWithOverrides(input.scene, values));
  input.design = std::move(design);
  if (flags.window_parts == "auto") {
    input.parts = AutomaticWindowParts(input.scene.window());
  } else {
    FENESTRA_ASSIGN_OR_RETURN(parts, ParseWindowParts(flags.window_parts));
    input.parts = parts;
  }
  FENESTRA_ASSIGN_OR_RETURN(backend, MakeBackend(flags.backend));
  input.backend = std::move(backend);
  return input;
}

OneStageOptions OneStageOptionsFrom(const DcFlags& flags) {
  OneStageOptions options;
  options.paths_per_sensor = flags.paths;
  options.max_bounces = flags.bounces;
  options.seed = flags.seed;
  options.threads = flags.threads;
  options.weight_windows = !flags.no_weight_windows;
  options.sequence = SequenceFrom(flags);
  SetRoulette(flags, options);
  return options;
}

OutdoorOptions OutdoorOptionsFrom(const DcFlags& flags, WindowParts parts) {
  OutdoorOptions options;
  options.paths = flags.outdoor_paths;
  options.max_bounces = flags.outdoor_bounces;
  SetStageOptions(flags, parts, options);
  return options;
}

IndoorOptions IndoorOptionsFrom(const DcFlags& flags, WindowParts parts) {
  IndoorOptions options;
  options.paths_per_sensor = flags.indoor_paths;
  options.max_bounces = flags.indoor_bounces;
  SetStageOptions(flags, parts, options);
  return options;
}

std::string ReflectionLimit(int max_bounces) {
  return max_bounces >= 0 ? fmt::format("at most {} reflections", max_bounces)
                          : std::string("unlimited reflections");
}

}  // namespace fenestra
