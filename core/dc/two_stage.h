#pragma once

// The two-stage method (core/README.md, "Two-stage method"): the outdoor matrix O ((window
// cells + 292) x 146 sky bins) once per site, the indoor matrix I (sensors x (window cells +
// 292)) per design, and D = I O. The outdoor stage sees only outdoor surfaces, the indoor
// stage only indoor surfaces and the blind; each builds its own acceleration structure from
// them.
//
// Window sampling: the outdoor stage starts its paths at uniform points of each window part,
// and the indoor stage connects to uniform window points, so O is the mean over the part's
// area of the radiance arriving from each direction cell. A centre-only estimate (paths
// from the window's centre) would instead take the view from one point; it differs where
// the outdoor view changes across the window (the sill and head see different parts of a
// street canyon), and it makes I O inconsistent with the one-stage D, which integrates
// over the whole opening.
//
// Direct light: the indoor stage tests each window connection against the outdoor
// surfaces; light that comes straight from the sky goes into a column per sky bin (I's
// direct part), and only light whose view meets an outdoor surface goes through the window
// cells and O (core/trace/two_stage_modes.h). O's rows are the window cells (the mean
// radiance of what the cell sees, given that it sees a surface), then the identity for
// each block of direct columns (light reflected in the room, then the sensor's own view of
// the sky, which the direct sun replaces): D = I O. Averaged over a cell, the sky's edge against
// the buildings moved a sensor by 3.6% (6.4% with a black city) where slats in the window plane let
// it see each cell only in strips (bench/results/two_stage_bias_cpu2.txt).
//
// Several windows: O's cell rows and I's cell columns hold every window's cells, one window
// after the other, above and before the direct rows and columns, which the windows share. The
// outdoor stage traces each window's cells on their own (its paths end where they go back in
// through any window); the indoor stage's next-event estimates draw a point of all windows'
// area, and a bounce ray scores at the window it leaves by (core/trace/two_stage_modes.h).
// So D = I O sums the light of every window, as the one-stage method does.
//
// Errors: both stages are traced in the same number B of independent batches, and batch b
// of D is I_b O_b, so D (their mean) and every metric's jackknife see the noise of both
// stages and the covariance that sensors and hours share through O.
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
// In options for a scene of several windows, a side of 0 splits each window on that side
// as AutomaticWindowParts does (PartsOfWindow).
struct WindowParts {
  int columns = 1;
  int rows = 1;
  bool operator==(const WindowParts&) const = default;
};

// The default split: parts at most 0.5 m wide and high (at most 8 a side), which keeps
// the error of the averaging well below the Monte Carlo error for views of streets and
// courtyards from ordinary windows (examples/city_office).
WindowParts AutomaticWindowParts(const Window& window);

// `parts` for `window`: each side of 0 as AutomaticWindowParts.
WindowParts PartsOfWindow(const Window& window, WindowParts parts);

// The cells of every window of `scene` split into `parts` (PartsOfWindow), in a basis of
// `basis_cells`: the rows of O above its direct rows, I's columns before its direct columns.
int WindowCellsOf(const Scene& scene, WindowParts parts, int basis_cells);

// WindowParts from "COLUMNSxROWS" (e.g. "4x2"), or InvalidArgument.
absl::StatusOr<WindowParts> ParseWindowParts(const std::string& text);

// The two-stage method's sampling by default: the jobs' (job.proto, Sampling; filled in by
// ResolveSampling, core/optimize/job.h) and the stages' options'. Reflections are unlimited,
// paths ended by Russian roulette alone: limits cheap enough to matter cut the light of the
// city office's room (walls of reflectance 0.8) by 2-12 points of UDI, and unlimited paths
// cost no more than 15 or 20 reflections (bench/README.md, "Reflection limits").
inline constexpr int64_t kDefaultOutdoorPaths = 20'000'000;
inline constexpr int kDefaultOutdoorBounces = -1;
inline constexpr int64_t kDefaultIndoorPathsPerSensor = 200'000;
inline constexpr int kDefaultIndoorBounces = -1;
// Independent batches of each stage, by default, and at most.
inline constexpr int kDefaultBatches = 8;
inline constexpr int kMaxBatches = 64;
// Window parts per side, at most.
inline constexpr int kMaxWindowPartsPerSide = 16;
// The outdoor matrix in memory with its batches, its mean and its standard error, at most:
// (window cells + 292) x 146 entries of 8 bytes each, batches + 2 times [bytes]. The default
// sampling (288 direction cells, 4 x 3 parts, 8 batches) needs 41 MB.
inline constexpr int64_t kMaxOutdoorMatrixBytes = int64_t{4} << 30;

struct OutdoorOptions {
  // In total, evenly over the window cells; >= cells x batches
  int64_t paths = kDefaultOutdoorPaths;
  int max_bounces = kDefaultOutdoorBounces;  // surface reflections; < 0 = unlimited (roulette)
  uint64_t seed = kDefaultSeed;
  int threads = 0;  // CPU threads; 0 = every hardware thread
  int basis_cells = 288;
  WindowParts parts;
  bool russian_roulette = true;
  double roulette_threshold = 1.0;  // as OneStageOptions
  // Independent batches of every window cell's paths; the indoor stage's batches pair
  // with them (CombineStages), so both must have the same count.
  int batches = kDefaultBatches;
  Sequence sequence = kDefaultSequence;  // as OneStageOptions
};

// O: per unit radiance of each sky bin [-], rows part * basis_cells + direction cell: the
// mean radiance arriving at the window part from the direction cell where its view meets an
// outdoor surface; then per block of I's direct columns (IndoorColumnCount) one row per sky
// bin, the identity. The mean
// of independent batch estimates, with the standard error of that mean.
struct OutdoorResult {
  Matrix coefficients;               // (window cells + 292) x 146
  Matrix standard_error;             // (window cells + 292) x 146
  std::vector<Matrix> batches;       // per batch: (window cells + 292) x 146
  DeviceMatrices batches_on_device;  // the batches where a GPU formed them, else empty
  // Per window cell: the fraction of its paths whose first segment reached the sky.
  Eigen::VectorXd sky_view;
  int basis_cells = 0;
  WindowParts parts;
  int64_t paths_per_cell = 0;  // in all batches
  uint64_t rays_traced = 0;
  size_t triangles = 0;  // outdoor triangles traced against
  double wall_seconds = 0;
  std::string backend;
};

struct IndoorOptions {
  int64_t paths_per_sensor = kDefaultIndoorPathsPerSensor;
  // Reflections whose light may reach a sensor; < 0 = unlimited (roulette)
  int max_bounces = kDefaultIndoorBounces;
  uint64_t seed = kDefaultSeed;
  int threads = 0;
  int basis_cells = 288;
  WindowParts parts;
  int batches = kDefaultBatches;  // independent batches of paths, as OutdoorOptions::batches
  bool russian_roulette = true;
  double roulette_threshold = 1.0;
  Sequence sequence = kDefaultSequence;  // as OneStageOptions
};

// I [sr]: irradiance at each sensor per unit radiance arriving at each window part from
// each direction cell where the view meets an outdoor surface (columns part * basis_cells
// + direction cell), then per unit radiance of each sky bin seen straight through the
// window (the direct part, one column per bin, 0 = ground); the mean of independent batch
// estimates.
struct IndoorResult {
  WindowParts parts;
  Matrix coefficients;          // sensors x (window cells + 292)
  Matrix standard_error;        // sensors x (window cells + 292), from the batches
  std::vector<Matrix> batches;  // per batch: sensors x (window cells + 292)
  int64_t paths_per_sensor = 0;
  uint64_t rays_traced = 0;
  size_t triangles = 0;      // indoor triangles traced against (blind included)
  double wall_seconds = 0;   // scene preparation included
  double trace_seconds = 0;  // the tracing itself (on a GPU: the kernel)
  std::string backend;
};

// D = I O as the mean of the batch products I_b O_b, with standard errors from their
// spread: both stages' noise and every covariance between entries included.
struct TwoStageResult {
  Matrix coefficients;          // sensors x 146 [sr]
  Matrix standard_error;        // sensors x 146 [sr]
  std::vector<Matrix> batches;  // I_b O_b, sensors x 146
  // Per sensor: the sum of D over the sky bins (1..145) [sr] and its standard error.
  Eigen::VectorXd sky_sum;
  Eigen::VectorXd sky_sum_standard_error;
};

// The basis of `cells` cells (288 or 1152), or InvalidArgument.
absl::StatusOr<HemisphereBasis> BasisFor(int cells);

// The outdoor stage of `scene`: its outdoor surfaces and window only. Traced by
// `backend`, or by the Embree CPU backend when null.
absl::StatusOr<OutdoorResult> ComputeOutdoorStage(const Scene& scene, const OutdoorOptions& options,
                                                  DcBackend* backend = nullptr);

// The indoor stage of `scene` at `design`: indoor surfaces and the blind, and the outdoor
// surfaces only to tell direct light from light through the window cells.
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
  // The sums of `design`'s paths in parts [first, last) of every batch (kDesignParts in
  // dc_backend.h), batch_paths the paths they hold; with those of the other parts added
  // (AddIndoorTally), IndoorResultFromTally gives Compute's I. InvalidArgument as Compute or
  // for parts outside 0 <= first < last <= kDesignParts; Unimplemented unless TracesInParts().
  virtual absl::StatusOr<IndoorTally> TraceParts(const BlindDesign& design, int first,
                                                 int last) const;
  virtual bool TracesInParts() const { return false; }
};

// Adds the sums, path counts and counters of `more` (other parts of the same batches) to
// `into`. InvalidArgument where their sensors, columns or batches differ.
absl::Status AddIndoorTally(const IndoorTally& more, IndoorTally& into);

// InvalidArgument unless 0 <= first < last <= kDesignParts.
absl::Status CheckDesignParts(int first, int last);

// For the indoor stage's tracers: the basis `options` ask for, or InvalidArgument for bad
// options; their per-path settings; I from the sums of a trace.
absl::StatusOr<HemisphereBasis> CheckIndoorOptions(const IndoorOptions& options);
// InvalidArgument unless O's batches pair with the indoor stage `options` ask for in `scene`:
// as many batches, each with a row per column of I.
absl::Status CheckOutdoorFitsIndoor(const std::vector<Matrix>& outdoor_batches, const Scene& scene,
                                    const IndoorOptions& options);
PathSettings IndoorPathSettings(const IndoorOptions& options);
IndoorResult IndoorResultFromTally(const IndoorTally& tally, const IndoorOptions& options);

// The outdoor surfaces of `scene`, prepared for tracing (empty when there are none): all of
// them for the outdoor stage; for the indoor stage's test whether a view from a window
// reaches the sky, only those with a point in front of some window's plane (no ray that
// leaves a window outwards can meet the others: the facade around the window, the
// building behind it), which makes the test about twice as fast.
absl::StatusOr<TraceGeometry> OutdoorGeometry(const Scene& scene);
absl::StatusOr<TraceGeometry> OutdoorViewGeometry(const Scene& scene);

// The offset of an OutdoorView: `outdoor`'s frame position of `indoor`'s frame origin.
Vec3f OutdoorOffset(const TraceGeometry& indoor, const TraceGeometry& outdoor);

// The window cells of an OutdoorView whose every view meets one of `outdoor`'s surfaces
// (core/trace/window_cells.h), for `windows` given in `indoor`'s frame, one window's cells
// after the other.
std::vector<uint8_t> OutdoorMetCells(const TraceGeometry& indoor, const TraceGeometry& outdoor,
                                     const std::vector<TraceWindow>& windows,
                                     const HemisphereBasis& basis);

// The window in `geometry`'s local frame, split into `parts`.
TraceWindow LocalWindow(const TraceGeometry& geometry, const Window& window, WindowParts parts);
// Every window of `scene` so, each split by PartsOfWindow, linked for TraceWindows
// (LinkWindows).
std::vector<TraceWindow> LocalWindows(const TraceGeometry& geometry, const Scene& scene,
                                      WindowParts parts, const HemisphereBasis& basis);

// D = I O, batch by batch. InvalidArgument when the bases, the window parts or the batch
// counts differ.
absl::StatusOr<TwoStageResult> CombineStages(const IndoorResult& indoor,
                                             const OutdoorResult& outdoor);

// The triangles of `mesh` on `side`.
TriangleMesh SelectSide(const TriangleMesh& mesh, Side side);

}  // namespace fenestra
