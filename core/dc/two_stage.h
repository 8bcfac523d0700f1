#pragma once

// The two-stage method (DESIGN.md section 1): the outdoor matrix O (window cells x 146
// sky bins) once per site, the indoor matrix I (sensors x window cells) per design, and
// D = I O. The outdoor stage sees only outdoor surfaces, the indoor stage only indoor
// surfaces and the blind; each builds its own acceleration structure from them.
//
// Window sampling: the outdoor stage starts its paths at uniform points of the whole
// window rectangle, and the indoor stage connects to uniform window points, so O is the
// mean over the window area of the radiance arriving from each direction cell. A
// centre-only estimate (paths from the window's centre) would instead take the view from
// one point; it differs where the outdoor view changes across the window (the sill and
// head see different parts of a street canyon), and it makes I O inconsistent with the
// one-stage D, which integrates over the whole opening.
#include <Eigen/Core>
#include <cstdint>
#include <string>
#include <vector>

#include "absl/status/statusor.h"
#include "core/common/radiance_matrix.h"
#include "core/dc/dc_backend.h"
#include "core/geometry/hemisphere_basis.h"
#include "core/geometry/scene.h"

namespace fenestra {

// The window split into columns x rows equal parts, each with its own direction cells
// (core/trace/two_stage_modes.h). One part assumes the outdoor radiance from a direction is
// the same all over the window; more parts relax that at no extra tracing cost.
struct WindowParts {
  int columns = 1;
  int rows = 1;
  bool operator==(const WindowParts&) const = default;
};

// The default split: parts at most 0.5 m wide and high (at most 8 a side), which keeps
// the error of the averaging well below the Monte Carlo error for views of streets and
// courtyards from ordinary windows (examples/city_office).
WindowParts AutomaticWindowParts(const Window& window);

// WindowParts from "COLUMNSxROWS" (e.g. "4x2"), or InvalidArgument.
absl::StatusOr<WindowParts> ParseWindowParts(const std::string& text);

struct OutdoorOptions {
  int64_t paths = 20'000'000;  // in total, spread evenly over the window cells
  int max_bounces = 30;        // surface reflections; < 0 = unlimited (roulette)
  uint64_t seed = 1;
  int threads = 0;  // CPU threads; 0 = every hardware thread
  int basis_cells = 288;
  WindowParts parts;
  bool russian_roulette = true;
  double roulette_threshold = 1.0;  // as OneStageOptions
};

// O: mean radiance arriving at each window part from each direction cell per unit
// radiance of each sky bin [-], with standard errors from the per-path second moment.
// Rows: window cells, part * basis_cells + direction cell.
struct OutdoorResult {
  Matrix coefficients;    // window cells x 146
  Matrix standard_error;  // window cells x 146
  int basis_cells = 0;
  WindowParts parts;
  int64_t paths_per_cell = 0;
  uint64_t rays_traced = 0;
  size_t triangles = 0;  // outdoor triangles traced against
  double wall_seconds = 0;
  std::string backend;
};

struct IndoorOptions {
  int64_t paths_per_sensor = 200'000;
  int max_bounces = 5;  // reflections whose light may reach a sensor; < 0 = unlimited
  uint64_t seed = 1;
  int threads = 0;
  int basis_cells = 288;
  WindowParts parts;
  int batches = 8;  // independent batches of paths (standard errors, metric errors)
  bool russian_roulette = true;
  double roulette_threshold = 1.0;
};

// I: irradiance at each sensor per unit radiance leaving each window part from each
// direction cell [sr], as the mean of independent batch estimates.
struct IndoorResult {
  WindowParts parts;
  Matrix coefficients;          // sensors x cells
  Matrix standard_error;        // sensors x cells, from the batches
  std::vector<Matrix> batches;  // per batch: sensors x cells
  int64_t paths_per_sensor = 0;
  uint64_t rays_traced = 0;
  size_t triangles = 0;      // indoor triangles traced against (blind included)
  double wall_seconds = 0;   // scene preparation included
  double trace_seconds = 0;  // the tracing itself (on a GPU: the kernel)
  std::string backend;
};

// D = I O with its standard error: the indoor part from the batches (their covariances
// included), the outdoor part sum_k I_ik^2 se(O_kj)^2 (cells are traced independently).
struct TwoStageResult {
  Matrix coefficients;          // sensors x 146 [sr]
  Matrix standard_error;        // sensors x 146 [sr]
  std::vector<Matrix> batches;  // I_b O, sensors x 146
  // Per sensor: the sum of D over the sky bins (1..145) [sr] and its standard error, both
  // stages' errors included (O's through each cell's row sum, from the per-path moments).
  Eigen::VectorXd sky_sum;
  Eigen::VectorXd sky_sum_standard_error;
};

// The basis of `cells` cells (288 or 1152), or InvalidArgument.
absl::StatusOr<HemisphereBasis> BasisFor(int cells);

// The outdoor stage of `scene`: its outdoor surfaces and window only. Traced by
// `backend`, or by the Embree CPU backend when null.
absl::StatusOr<OutdoorResult> ComputeOutdoorStage(const Scene& scene, const OutdoorOptions& options,
                                                  DcBackend* backend = nullptr);

// The indoor stage of `scene` at `design`: indoor surfaces and the blind only.
absl::StatusOr<IndoorResult> ComputeIndoorStage(const Scene& scene, const BlindDesign& design,
                                                const IndoorOptions& options,
                                                DcBackend* backend = nullptr);

// The indoor stage of one scene for many blind designs with the same random streams (an
// optimization's candidates); made by DcBackend::MakeIndoorStages.
class IndoorStages {
 public:
  virtual ~IndoorStages() = default;
  // I for `design`. A design outside the blind's ranges may be refused (InvalidArgument):
  // the replay is only valid within them.
  virtual absl::StatusOr<IndoorResult> Compute(const BlindDesign& design) const = 0;
};

// For the indoor stage's tracers: the basis `options` ask for, or InvalidArgument for bad
// options; their per-path settings; I from the sums of a trace.
absl::StatusOr<HemisphereBasis> CheckIndoorOptions(const IndoorOptions& options);
PathSettings IndoorPathSettings(const IndoorOptions& options);
IndoorResult IndoorResultFromTally(const IndoorTally& tally, const IndoorOptions& options);

// The window in `geometry`'s local frame, split into `parts`.
TraceWindow LocalWindow(const TraceGeometry& geometry, const Window& window, WindowParts parts);

// D = I O. InvalidArgument when the bases or the window parts differ.
absl::StatusOr<TwoStageResult> CombineStages(const IndoorResult& indoor,
                                             const OutdoorResult& outdoor);

// The triangles of `mesh` on `side`.
TriangleMesh SelectSide(const TriangleMesh& mesh, Side side);

}  // namespace fenestra
