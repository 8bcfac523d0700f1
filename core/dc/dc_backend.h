#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "absl/status/statusor.h"
#include "core/common/radiance_matrix.h"
#include "core/dc/glare_tally.h"
#include "core/dc/sun_entry.h"
#include "core/geometry/hemisphere_basis.h"
#include "core/geometry/mesh.h"
#include "core/geometry/scene.h"
#include "core/metrics/annual_metrics.h"
#include "core/trace/trace_geometry.h"
#include "core/trace/two_stage_cpu.h"

namespace fenestra {

class DirectSun;
class IndoorStages;
struct IndoorOptions;

// Number of daylight-coefficient columns: bin 0 = ground, 1..145 = Tregenza sky patches.
inline constexpr int kDaylightBins = 146;
// Rows of a split sky (core/README.md, "Direct sun"): S, then -S_sun, the sun as the sky
// matrix spreads it over patches, which multiplies the coefficients' unreflected direct part
// D_0 (the last 146 columns of I, or of a one-stage [D | D_0]), so that E = D S - D_0 S_sun
// and the direct sun, traced to its position (SunEntry, core/dc/direct_sun.h), takes its
// place.
inline constexpr int kSplitSkyRows = 2 * kDaylightBins;

// Matrices a GPU holds, one after the other, each laid out as the host's copy of it: on GPU
// `device`, freed when the last holder lets go. A backend on that GPU takes them from there
// rather than uploading the host's copy they equal; `data` is null where there is none.
struct DeviceMatrices {
  std::shared_ptr<const double> data;
  int device = -1;
};

// The outdoor stage's matrix O in batches, as a backend forms it from its sums
// (FormOutdoorBatches): per batch (window cells + 292) x 146, the reflected light per window
// cell over its paths whose first segment met a surface, then the identity for the direct
// columns; their mean and its standard error.
struct OutdoorBatches {
  std::vector<Matrix> batches;
  Matrix mean;
  Matrix standard_error;
  // Per window cell: its paths (of all batches) whose first segment reached the sky.
  Eigen::VectorXd first_escapes;
  uint64_t paths_per_cell = 0;  // in all batches
  TraceCounters counters;
  // The batches where a GPU formed them (CUDA backends), else empty.
  DeviceMatrices batches_on_device;
};

// O's batches from the outdoor sums on the host.
OutdoorBatches FormOutdoorBatches(const OutdoorTally& tally);

// How to trace the one-stage daylight coefficients.
// The batches of a one-stage run with Sequence::kSobol that asks for fewer than 2.
inline constexpr int kSobolBatches = 8;

struct OneStageOptions {
  int64_t paths_per_sensor = 100000;  // at least 2
  // Surface reflections a path may make (Radiance's -ab is one more); 0 = none (the direct
  // component), kUnlimitedBounces = ended by Russian roulette only (unbiased).
  int max_bounces = kUnlimitedBounces;
  uint64_t seed =
      kDefaultSeed;  // a path's random stream is a function of (seed, sensor, path index)
  int threads = 0;   // CPU threads; 0 = every hardware thread
  // Russian roulette: required when unlimited; optional (still unbiased) with a limit.
  bool russian_roulette = true;
  // Path weight below which roulette plays, in (0, 1]: such a path survives with
  // probability weight / threshold and carries the threshold on, so no path ever carries
  // more than 1. 1 = survive each reflection with probability equal to the reflectance.
  // 0.25 was the most efficient (variance x time) on the lightwell (bench/README.md).
  double roulette_threshold = 0.25;
  // Weight windows (unbiased, weights <= 1): a pilot pass (plain roulette) learns how much
  // light paths leaving each region of the scene collect (cells of importance_cell_m,
  // split by the side a surface faces); then the roulette threshold follows that map and
  // paths split where they matter. Without enough light in the pilot
  // (kMinPilotScoringPaths), plain roulette is used.
  bool weight_windows = true;
  int64_t pilot_paths_per_sensor = 0;  // 0 = automatic (bench/README.md)
  double importance_cell_m = 0.5;
  // Also report D of this many independent batches (each sensor's paths split into equal,
  // contiguous ranges), for jackknife errors of non-linear results; 0 or 1 = none.
  int batches = 0;
  // How the paths' first draws are made (PathRandom, core/trace/philox.h). With kSobol the
  // standard errors come from the scatter of the batches (at least 2: kSobolBatches where
  // fewer are asked), the paths of one batch not being independent.
  Sequence sequence = kDefaultSequence;
};

// One-stage daylight coefficients with their Monte Carlo error.
struct OneStageResult {
  // D: sensors x 146, irradiance at the sensor per unit radiance of the bin [sr].
  Matrix coefficients;
  // Standard error of each coefficient, from the per-path second moment [sr].
  Matrix standard_error;
  Eigen::VectorXd sky_sum;                 // per sensor: sum of D over bins 1..145 [sr]
  Eigen::VectorXd sky_sum_standard_error;  // its standard error [sr]
  // With options.batches = B > 1: D of each batch; `coefficients` is their mean.
  std::vector<Matrix> batch_coefficients;
  // The part of D that reaches the sensor without a reflection (its direct component, which
  // the direct sun replaces; core/README.md, "Direct sun"), sensors x 146 [sr], and per batch
  // as batch_coefficients.
  Matrix direct_coefficients;
  std::vector<Matrix> batch_direct_coefficients;
  int64_t paths_per_sensor = 0;
  uint64_t rays_traced = 0;         // closest-hit queries, all sensors, pilot included
  uint64_t branches = 0;            // paths plus weight-window splits
  int64_t pilot_paths = 0;          // weight-window pilot paths, all sensors (not in D)
  size_t importance_cells = 0;      // cells the pilot learned; 0 = weight windows not used
  uint64_t escaped_paths = 0;       // branches that left the scene (scored)
  uint64_t roulette_paths = 0;      // branches ended by Russian roulette
  uint64_t bounce_limit_paths = 0;  // branches cut by the bounce limit (the bias it causes)
  uint64_t truncated_paths = 0;     // branches cut by the safety cap on interactions
  double max_path_weight = 0;       // largest throughput any path carried (<= 1)
  int threads = 0;
  double wall_seconds = 0;  // tracing time, scene preparation included
  std::string backend;      // which backend traced it
};

// The annual illuminance of a design's indoor batches through a fixed outdoor matrix and
// sky: E_b = (I_b O_b) S for each batch b, the outdoor stage's batch b paired with the
// indoor stage's (I_b sensors x columns, O_b columns x 146, core/dc/two_stage.h; S 146 x
// steps with the luminous efficacy folded in, so E is in lux). Made once per job by
// DcBackend::MakeAnnualProduct, applied once per design.
// S may be a split sky (kSplitSkyRows); the sun's entries a call passes (their columns S's)
// are then added to every batch's E.
class AnnualProduct {
 public:
  virtual ~AnnualProduct() = default;
  // InvalidArgument when a batch's columns are not O's rows, or the batch counts differ.
  absl::StatusOr<std::vector<Matrix>> Apply(const std::vector<Matrix>& indoor_batches) {
    return ApplyToSky(indoor_batches, Sky());
  }
  // Apply with `sky` (146 or kSplitSkyRows x any steps) in S's place for this call, the
  // sun's `entries` in its columns; S stays. InvalidArgument as Apply, or for a sky of other
  // rows.
  virtual absl::StatusOr<std::vector<Matrix>> ApplyToSky(const std::vector<Matrix>& indoor_batches,
                                                         const Matrix& sky,
                                                         std::span<const SunEntry> sun = {}) = 0;
  // The tallies of E of the mean of the B >= 2 batches, then of each leave-one-out mean
  // (TallyBatchVersions in core/metrics/metric_errors.h), every column of S an analysed hour;
  // a GPU tallies where E is. InvalidArgument as Apply, or B < 2.
  virtual absl::StatusOr<std::vector<HourTally>> Tally(const std::vector<Matrix>& indoor_batches,
                                                       const MetricOptions& options,
                                                       std::span<const SunEntry> sun = {}) = 0;
  // S as set.
  virtual const Matrix& Sky() const = 0;
};

// A design's indoor paths in rounds (racing, core/optimize/racing.h): each batch's paths
// split into this many parts of consecutive path indices, and a round traces more parts of
// every batch, so that the batches stay equal, independent and paired with the outdoor ones.
inline constexpr int kDesignParts = 8;

// A search's objective per design (core/optimize/job.cpp): the design's indoor stage, then
// the tallies of its E = (I O) S for the annual metrics (AnnualProduct::Tally). Made by
// DcBackend::MakeDesignTallies.
class DesignTallies {
 public:
  virtual ~DesignTallies() = default;
  // The tallies of `design`'s paths in parts [0, parts) of every batch (kDesignParts: all of
  // them). A call for the design of the call before, with more parts, traces only the parts
  // it adds. InvalidArgument for a design the stage refuses (IndoorStages::Compute), or
  // parts outside [1, kDesignParts]; Unimplemented for fewer than kDesignParts where
  // !TracesInParts().
  virtual absl::StatusOr<std::vector<HourTally>> Tally(const BlindDesign& design,
                                                       const MetricOptions& options,
                                                       int parts = kDesignParts) = 0;
  // The tallies of several designs, every part of each, in their order: each as Tally(design,
  // options) gives it (an error for one design leaves the others). By default one after the
  // other; the GPU's replay traces up to DesignsAtOnce() of them in one launch.
  virtual std::vector<absl::StatusOr<std::vector<HourTally>>> TallyDesigns(
      const std::vector<BlindDesign>& designs, const MetricOptions& options);
  // The design's I per batch (IndoorResult::batches), every part, as ComputeIndoorStage gives
  // it to rounding: by the tallies' replay where they have one, which spares building the
  // design's scene. Errors as Tally.
  virtual absl::StatusOr<std::vector<Matrix>> IndoorBatches(const BlindDesign& design) = 0;
  // E_b = (I_b O_b) `sky` (146 x any steps, as AnnualProduct::ApplyToSky takes it) of
  // `design`'s paths, every part: by default ApplyToSky(IndoorBatches(design), sky); the GPU
  // forms it where the replay's sums lie. After SetProduct; errors as IndoorBatches and
  // ApplyToSky.
  virtual absl::StatusOr<std::vector<Matrix>> DesignIlluminance(const BlindDesign& design,
                                                                const Matrix& sky);
  // E_b through the product's own S (SetProduct's sky) of several designs, every part of
  // each, in their order (an error for one design leaves the others): by default
  // DesignIlluminance(design, Product()->Sky()) one after the other; the GPU's replay traces
  // up to DesignsAtOnce() of them in one launch and forms each E with the S it holds.
  virtual std::vector<absl::StatusOr<std::vector<Matrix>>> DesignsIlluminance(
      const std::vector<BlindDesign>& designs);
  // What decides a glare step where the tallies' sensors are eyes (GlareDesigns): after
  // SetProduct, its columns the product's S's. InvalidArgument where they are not or the
  // threshold is outside (0, 1); FailedPrecondition before SetProduct.
  virtual absl::Status SetGlareSteps(GlareSteps steps);
  // The glare counts (glare_tally.h) of several designs, every part of each, in their order,
  // design k's beam at the eyes sun[k] (none where `sun` is shorter; an error for one design
  // leaves the others): by default CountGlare of DesignsIlluminance; the GPU's replay counts
  // where E lies, and only the counts come back. FailedPrecondition before SetGlareSteps.
  virtual std::vector<absl::StatusOr<GlareCounts>> GlareDesigns(
      const std::vector<BlindDesign>& designs, const std::vector<std::vector<SunEntry>>& sun);
  // Sets the annual product the tallies form E with (DcBackend::MakeAnnualProduct's O_b and
  // S); Tally and Product need it. InvalidArgument where O_b's rows are not the indoor
  // stage's columns or its batches not the stage's batches. `on_device`: the same O_b where
  // a GPU holds them (OutdoorBatches::batches_on_device), or empty.
  virtual absl::Status SetProduct(const std::vector<Matrix>& outdoor_batches, const Matrix& sky,
                                  const DeviceMatrices& on_device) = 0;
  // SetProduct from the host's O_b alone.
  absl::Status SetProduct(const std::vector<Matrix>& outdoor_batches, const Matrix& sky) {
    return SetProduct(outdoor_batches, sky, {});
  }
  // The annual product the tallies form E with: their O_b, already where they are used;
  // null before SetProduct.
  virtual AnnualProduct* Product() = 0;
  // How many designs TallyDesigns takes in one pass (more only cost proportionally more).
  virtual int DesignsAtOnce() const { return 1; }
  // Whether Tally takes fewer than kDesignParts (the replays do; full traces do not).
  virtual bool TracesInParts() const { return false; }
  // Whether a job races its candidates (traces them in rounds) where it does not say: a
  // round's annual product and tallies cost little beside the paths it may save (on the CPU).
  // On the GPU they cost more than the paths racing saves on the reference jobs
  // (bench/results/racing_h100.txt).
  virtual bool RacesByDefault() const { return TracesInParts(); }
  // Closest-hit queries of every Tally so far.
  virtual uint64_t RaysTraced() const = 0;

  // The direct sun every design's E gets (core/dc/direct_sun.h: its columns the product's),
  // with a split sky as the product's S; also each tally's sunlit hours (ASE). Null: none.
  void SetDirectSun(std::shared_ptr<const DirectSun> sun) { sun_ = std::move(sun); }
  const DirectSun* Sun() const { return sun_.get(); }

 protected:
  // `design`'s direct sun in the product's columns; empty without SetDirectSun.
  std::vector<SunEntry> SunOf(const BlindDesign& design) const;
  // SetGlareSteps' steps; null before it.
  const GlareSteps* GlareStepsSet() const { return glare_steps_.get(); }
  // `versions` (tallies of E) with the sunlit hours of `sun` (SunOf), where there is a sun.
  absl::StatusOr<std::vector<HourTally>> WithSunlitHours(
      absl::StatusOr<std::vector<HourTally>> versions, const std::vector<SunEntry>& sun,
      const MetricOptions& options) const;

 private:
  std::shared_ptr<const DirectSun> sun_;
  std::unique_ptr<const GlareSteps> glare_steps_;
};

// A tracer backend for daylight coefficients (Embree on the CPU, CUDA on a GPU), chosen at
// run time. Implementations are thread-compatible: one call at a time per object.
class DcBackend {
 public:
  virtual ~DcBackend() = default;
  virtual std::string Name() const = 0;
  // Designs a job evaluates at once by default (Sampling.candidates_at_once): one on the CPU,
  // whose one evaluation uses every core; kCandidatesPerGpu per GPU in use on CUDA.
  virtual int DefaultCandidatesAtOnce() const { return 1; }
  // The GPU this backend traces on; -1 on the CPU.
  virtual int Gpu() const { return -1; }

  // Traces options.paths_per_sensor paths from every sensor through `mesh` (materials
  // indexed by mesh.material). InvalidArgument for bad options, sensors or materials.
  virtual absl::StatusOr<OneStageResult> OneStage(const TriangleMesh& mesh,
                                                  const std::vector<Material>& materials,
                                                  const std::vector<Sensor>& sensors,
                                                  const OneStageOptions& options) = 0;

  // The two-stage method's stages (core/dc/two_stage.h) over prepared geometry: outdoor
  // paths from each window cell, indoor paths from each sensor, both in batches; the indoor
  // stage tests its window connections against `outdoor` (the outdoor stage's geometry).
  // The outdoor stage comes back as O's batches, formed where its sums lie. `threads`
  // applies to CPU backends.
  // The outdoor stage traces window `window` of `windows` (LinkWindows), the indoor stage all
  // of them.
  virtual absl::StatusOr<OutdoorBatches> Outdoor(const TraceGeometry& geometry,
                                                 const std::vector<TraceWindow>& windows,
                                                 int window, const HemisphereBasis& basis,
                                                 uint64_t paths_per_cell, int batches,
                                                 uint64_t seed, const PathSettings& path,
                                                 int threads) = 0;
  virtual absl::StatusOr<IndoorTally> Indoor(const TraceGeometry& geometry,
                                             const TraceGeometry& outdoor,
                                             const std::vector<TraceSensor>& sensors,
                                             const std::vector<TraceWindow>& windows,
                                             const HemisphereBasis& basis,
                                             uint64_t paths_per_sensor, int batches, uint64_t seed,
                                             const PathSettings& path, int threads) = 0;

  // The annual product with the outdoor batches O_b and `sky` (AnnualProduct), computed
  // where this backend computes: Eigen on the CPU by default, the GPU for CUDA. Must not
  // outlive the backend.
  virtual absl::StatusOr<std::unique_ptr<AnnualProduct>> MakeAnnualProduct(
      const std::vector<Matrix>& outdoor_batches, const Matrix& sky);
  // The annual product of `sky` alone, every O_b the identity: E_b = D_b S for one-stage
  // daylight coefficients D_b (sensors x 146, their columns the sky's bins already), in any
  // number of batches (at least 2 for Tally). Where MakeAnnualProduct computes; must not
  // outlive the backend.
  virtual absl::StatusOr<std::unique_ptr<AnnualProduct>> MakeSkyProduct(const Matrix& sky);

  // The indoor stage of `scene` for the designs within its blind's ranges, the way this
  // backend does it best (core/dc/two_stage.h, IndoorStages): by default each design
  // traced in full; the CPU records the paths once and replays them
  // (core/dc/indoor_replay.h). Must not outlive the backend.
  virtual absl::StatusOr<std::unique_ptr<IndoorStages>> MakeIndoorStages(
      const Scene& scene, const IndoorOptions& options);

  // A search's objective (DesignTallies) for the designs within `scene`'s blind ranges,
  // without its annual product (DesignTallies::SetProduct), so that the indoor stage's
  // records need not wait for the outdoor stage and the sky: by default MakeIndoorStages,
  // then MakeAnnualProduct at SetProduct; the GPU keeps I and E on the device. Must not
  // outlive the backend.
  virtual absl::StatusOr<std::unique_ptr<DesignTallies>> StartDesignTallies(
      const Scene& scene, const IndoorOptions& options);
  // StartDesignTallies, then SetProduct with `outdoor_batches` and `sky`.
  absl::StatusOr<std::unique_ptr<DesignTallies>> MakeDesignTallies(
      const Scene& scene, const IndoorOptions& options, const std::vector<Matrix>& outdoor_batches,
      const Matrix& sky);
};

// The Embree CPU backend (always available).
std::unique_ptr<DcBackend> MakeEmbreeBackend();

// The CUDA backend on GPU `device`: Unavailable on a build without CUDA or a host without
// that device.
absl::StatusOr<std::unique_ptr<DcBackend>> MakeCudaBackend(int device = 0);

// "cpu", "cuda" or "auto" (a GPU when there is one, else the CPU). Successive GPU backends
// take the GPUs in use in turn (NextCudaDevice).
absl::StatusOr<std::unique_ptr<DcBackend>> MakeBackend(const std::string& name);

// The GPU of lane `lane` (>= 0) of a job whose first lane is on GPU `first`: the lane-th GPU
// after it among those NextCudaDevice takes on this thread, so that a job's lanes take
// distinct GPUs while there are enough, whatever other jobs and stages take meanwhile;
// `first` itself when it is not among them.
int LaneCudaDevice(int first, int lane);

// The backend of lane `lane` (>= 1) of a job whose first lane is `first`: on a GPU, one on
// LaneCudaDevice(first.Gpu(), lane); on the CPU, MakeBackend(name).
absl::StatusOr<std::unique_ptr<DcBackend>> MakeLaneBackend(const std::string& name,
                                                           const DcBackend& first, int lane);

// Number of CUDA devices this build and host can use (0 without CUDA).
int CudaDevices();

// The GPU the next backend should use: the GPUs of this thread's ThreadCudaDevices in turn,
// else those of UseCudaDevices (by default every visible one) in turn across the process.
int NextCudaDevice();

// The GPUs of a "gpus" setting: "all" (every one of the `visible`) or comma-separated device
// indices, each below `visible` and listed once. InvalidArgument otherwise.
absl::StatusOr<std::vector<int>> ParseGpuList(const std::string& gpus, int visible);

// Makes NextCudaDevice take `devices` in turn (process-wide); empty: every visible GPU.
void UseCudaDevices(std::vector<int> devices);

// How many GPUs NextCudaDevice takes in turn on this thread.
int CudaDevicesInUse();

// The GPUs worker `worker` of `workers` takes (a daemon's worker threads share those of
// UseCudaDevices): with at least as many workers as GPUs each worker has one, the GPUs taken in
// turn; with fewer, worker w has every workers-th GPU from the w-th. Empty without a GPU.
std::vector<int> WorkerCudaDevices(int worker, int workers);

// While it lives, NextCudaDevice and CudaDevicesInUse on the thread that made it take `devices`
// (a worker's, WorkerCudaDevices) rather than the process's; empty changes nothing.
class ThreadCudaDevices {
 public:
  explicit ThreadCudaDevices(std::vector<int> devices);
  ~ThreadCudaDevices();
  ThreadCudaDevices(const ThreadCudaDevices&) = delete;
  ThreadCudaDevices& operator=(const ThreadCudaDevices&) = delete;

 private:
  std::vector<int> before_;
};

// Designs evaluated at once per GPU by default. Since the replay kernel's blocks fill the
// H100 to its last slot (its rows share them by their work), a second lane's kernel no longer
// runs beside the first's tallies: two at once took the four-variable job's 500 steps in the
// time of one (0.578-0.582 s against 0.582-0.586 s) while recording a second copy of the
// paths, and three or four took longer (bench/README.md, "Several GPUs").
inline constexpr int kCandidatesPerGpu = 1;

// Designs the GPU's replay traces in one launch (DesignTallies::DesignsAtOnce) when a search
// evaluates several at once without racing. A launch's last paths end one after another, so
// designs traced together share that tail: on the H100 the four-variable job's evaluations
// took 0.53-0.55 s with 2 per launch (30 of 530 dropped), 0.54 s with 3 (77 dropped), 0.72 s
// with 4 (118 dropped) and 0.58-0.59 s with 1 (bench/README.md, "Several designs in one
// launch"). With 3, the search takes 2 at once while it improves often (kBusyImprovements,
// core/optimize/vns.h), which drops fewer: on H200s the search took 0.436-0.460 s against
// 0.460-0.474 s with 2 per launch (bench/README.md, "Fewer designs at once while the search
// improves").
inline constexpr int kReplayDesignsAtOnce = 3;

}  // namespace fenestra
