#pragma once

// The tracing flags that `fenestra dc` and `fenestra convergence` share: the method, the
// design, the backend and each method's sampling, and the stage options they give.
#include <cstdint>
#include <memory>
#include <string>

#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "core/dc/dc_backend.h"
#include "core/dc/two_stage.h"
#include "core/geometry/scene.h"

namespace CLI {
class App;
}  // namespace CLI

namespace fenestra {

// Independent batches of each stage's paths for `dc` and `convergence`, paired (D_b = I_b O_b):
// D's standard errors, both stages' noise included, come from their scatter, with
// batches - 1 degrees of freedom; 32 estimates them within about 13% (8, the jobs' default,
// within 27%), which tracing to a target error needs to stop near the target. The batch
// count leaves D itself unchanged up to the outdoor paths' rounding to whole batches.
inline constexpr int kDcBatches = 32;

struct DcFlags {
  std::string scene, set, method = "one-stage", backend = "cpu", window_parts = "auto";
  // One-stage
  int64_t paths = OneStageOptions{}.paths_per_sensor;
  int bounces = OneStageOptions{}.max_bounces;
  bool no_weight_windows = false;
  // Both methods
  uint64_t seed = 0;  // AddDcFlags sets the jobs' defaults here and below
  int threads = 0;
  bool no_roulette = false;
  double roulette_threshold = OneStageOptions{}.roulette_threshold;
  // "pseudo-random" or "sobol" (Sampling.sequence)
  std::string sequence = kDefaultSequence == Sequence::kSobol ? "sobol" : "pseudo-random";
  // Two-stage
  int64_t outdoor_paths = 0, indoor_paths = 0;
  int outdoor_bounces = 0, indoor_bounces = 0;
  int basis = 0;
  int batches = kDcBatches;
  CLI::App* command = nullptr;  // where the flags were added, to tell which were given
};

// Adds the flags to `command`. Their defaults: the two-stage sampling and the seed those of
// the jobs (core/optimize/job.cpp, ResolveSampling), the rest those of OneStageOptions; every
// path count divided by `paths_divisor` (for commands whose first run is a small one).
// `flags` must outlive the command.
void AddDcFlags(CLI::App* command, DcFlags* flags, int64_t paths_divisor = 1);

// InvalidArgument when a flag of the other method was given (--bounces caps one-stage paths;
// the two-stage method has --outdoor-bounces and --indoor-bounces) or a bounce limit is
// below -1.
absl::Status CheckMethodFlags(const DcFlags& flags);

// The scene, the design the flags set, the backend and the window parts, all checked.
struct DcInput {
  Scene scene;
  BlindDesign design;
  std::unique_ptr<DcBackend> backend;
  WindowParts parts;
};
absl::StatusOr<DcInput> LoadDcInput(const DcFlags& flags);

// The options of each stage and method from the flags (window parts from the input).
OneStageOptions OneStageOptionsFrom(const DcFlags& flags);
OutdoorOptions OutdoorOptionsFrom(const DcFlags& flags, WindowParts parts);
IndoorOptions IndoorOptionsFrom(const DcFlags& flags, WindowParts parts);

// "at most N reflections" or, for max_bounces < 0, "unlimited reflections".
std::string ReflectionLimit(int max_bounces);

}  // namespace fenestra
