#pragma once

// An optimization job end to end in one process: scene and weather -> sky matrix ->
// outdoor matrix (once) -> per candidate design: indoor matrix -> D = I O -> E = D S ->
// annual metrics with standard errors -> Variable Neighborhood Search. The command line's
// local mode and the service's workers run exactly this. The run is job.cpp; the door
// (ValidateJob) job_validation.cpp; reading a job file job_proto.cpp; the hashes
// job_hash.cpp; checkpoints job_checkpoint.cpp.
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "absl/status/statusor.h"
#include "core/common/radiance_matrix.h"
#include "core/dc/two_stage.h"
#include "core/geometry/scene.h"
#include "core/sky/epw.h"
#include "core/sky/sky_matrix.h"
#include "fenestra/v1/job.pb.h"

namespace fenestra {

// The outdoor matrix O of a site: (window cells, then one identity row per sky bin) x 146 sky
// bins [-], with its standard error, its batches and how it was made.
struct OutdoorMatrix {
  Matrix coefficients;  // O (core/dc/two_stage.h): window cells + 292 rows
  Matrix standard_error;
  std::vector<Matrix> batches;  // O_b, paired with the indoor batches
  // The batches where a GPU formed them, while the job that traced them uses them (see
  // ComputeOutdoorMatrix), else empty.
  DeviceMatrices batches_on_device;
  int basis_cells = 0;
  WindowParts parts;
  int64_t paths = 0;
  int bounces = 0;
  uint64_t seed = 0;
  double wall_seconds = 0;
  std::string backend;
  std::string key;  // OutdoorMatrixKey of what it was computed from
};

// Objective evaluations of a job whose budget leaves them open (job.proto).
inline constexpr int kDefaultMaxEvaluations = 150;
// The most designs a job evaluates at once (Sampling.candidates_at_once).
inline constexpr int kMaxCandidatesAtOnce = 16;

// A job checked and resolved: scene loaded, weather read, variables known, defaults filled
// in. Preparing does all validation, so a job that prepares runs.
struct PreparedJob {
  v1::Job job;  // with defaults filled in and paths resolved
  Scene scene;
  // The finishes of the job's finish variable, by index, as the scene's materials (empty
  // without one).
  std::vector<SlatFinish> finishes;
  std::string weather_file;
  EpwData weather;  // parsed (PrepareJob only)
  // The sky matrix of `weather` for this job (JobSkyMatrix) where the caller holds it already
  // (fenestrad keeps those of recent weather files); null: RunJob builds it.
  std::shared_ptr<const SkyMatrix> sky;
};

// The options of a job's sky matrix: the site's ground reflectance, the rest the defaults.
SkyMatrixOptions JobSkyOptions(const PreparedJob& job);

// The sky matrix of a job's weather (BuildSkyMatrix with JobSkyOptions).
absl::StatusOr<std::shared_ptr<const SkyMatrix>> JobSkyMatrix(const PreparedJob& job);

// Reads a job file (the JSON form of fenestra.v1.Job; unknown fields are errors).
absl::StatusOr<v1::Job> ReadJobFile(const std::string& path);

// The door for jobs: validates everything but the weather and fills in defaults. Every
// string (CheckMessageText), the scene (BuildScene; a relative scene_file is taken from
// `base_dir`), design variables (at least one) within a real blind's bounds (a finish
// variable: its finishes the scene's slat materials, its range their indices), budget,
// sampling, metric settings, objective and neighborhoods (finite, in range, known enum
// values), then the room (CheckRoom) with the blind at every design of the job's ranges.
// InvalidArgument naming the field and the reason.
absl::StatusOr<PreparedJob> ValidateJob(const v1::Job& job, const std::string& base_dir);

// The error of a job's field: InvalidArgument "job FIELD: REASON".
absl::Status InvalidJobField(const std::string& field, const std::string& reason);

// ValidateJob, then the weather: the job's weather_file (relative to `base_dir`), else the
// scene's site.weather_file, read and parsed (ReadEpw).
absl::StatusOr<PreparedJob> PrepareJob(const v1::Job& job, const std::string& base_dir);

// `scene` with its blind's ranges widened to the job's design variables: what the search
// may generate.
Scene WithJobRanges(const Scene& scene, const v1::Job& job);

// A content hash of everything the outdoor matrix depends on: the outdoor triangles and
// their materials, the window, and the outdoor sampling settings (paths, bounces, seed,
// basis). Equal keys mean an equal matrix (up to the backend's rounding). Indoor surfaces,
// the blind, sensors and the weather do not enter it.
std::string OutdoorMatrixKey(const Scene& scene, const v1::Sampling& sampling);

// The window parts `sampling` asks for (resolved), automatic ones for `window` if it
// leaves them open.
WindowParts SamplingWindowParts(const v1::Sampling& sampling, const Window& window);
// For the stages of `scene`: as above for a scene of one window; for several, a side left
// open stays 0, each window's own automatic split (PartsOfWindow).
WindowParts SamplingWindowParts(const v1::Sampling& sampling, const Scene& scene);

// Mean relative standard error of the window cells' entries of O (not the identity rows),
// over the entries above 1% of the matrix's largest.
double OutdoorMeanRelativeError(const OutdoorMatrix& matrix);

// Fills in the defaults of `sampling` (see job.proto) and checks its ranges.
absl::StatusOr<v1::Sampling> ResolveSampling(const v1::Sampling& sampling);

// Traces the outdoor stage: only the scene's outdoor surfaces and its window; `sampling`
// resolved (ResolveSampling). `cancelled` is polled between batches of paths. The batches a
// GPU formed stay on it (OutdoorMatrix::batches_on_device) only with `keep_on_device`, for a
// job's annual product on the same GPU; a matrix to be kept for later holds no GPU memory.
absl::StatusOr<OutdoorMatrix> ComputeOutdoorMatrix(const Scene& scene, const v1::Sampling& sampling,
                                                   const std::function<bool()>& cancelled = {},
                                                   bool keep_on_device = false);

// What a running job reports after each evaluation, and once more after its final check.
struct JobProgress {
  int evaluations = 0;
  int max_evaluations = 0;
  v1::Evaluation current;
  v1::Evaluation best;
  double elapsed_seconds = 0;
  double remaining_seconds = 0;  // estimate
  // Only in the report after the final check: its result.
  std::optional<v1::FinalCheck> final_check;
};

struct JobCallbacks {
  // A stage starts: "sky", "outdoor", "indoor paths", "search", "check" (the final check).
  // The sky matrix is made while the outdoor stage traces, so "outdoor" follows "sky" at once.
  std::function<void(const std::string& stage)> stage;
  std::function<void(const JobProgress&)> progress;
  // Polled between evaluations; true stops the search there.
  std::function<bool()> cancelled;
  // After each step of the search (an evaluation or a cache hit), before `progress`: what
  // continues the job from there (RunJob's `resume`). The search's state only, built step by
  // step (one evaluation appended); valid until the step's `progress` returns.
  std::function<void(const v1::SearchCheckpoint&)> checkpoint;
};

// The SearchCheckpoint format this build writes and reads.
inline constexpr uint32_t kSearchCheckpointFormat = 1;

// A content hash of the job as prepared, 32 hexadecimal digits: the job a SearchCheckpoint
// belongs to. It covers `job.job` with the prepared scene inline (serialized
// deterministically) and the weather's site and records: the same content gives the same
// hash whatever the files' paths, another scene or weather file under the same path another.
std::string JobContentHash(const PreparedJob& job);

// A checkpoint from the bytes a store kept (SerializeAsString). DataLoss for bytes that do
// not parse, InvalidArgument for a format other than kSearchCheckpointFormat.
absl::StatusOr<v1::SearchCheckpoint> ParseSearchCheckpoint(std::string_view bytes);

// Runs the job. `outdoor` may hold a cached outdoor matrix whose key equals
// OutdoorMatrixKey(job); otherwise (null) it is computed. After the search the best design
// is checked by the one-stage method (sampling.final_check, core/optimize/final_check.h),
// unless the job was cancelled; a cancel during the check leaves it out. A cancelled job
// returns its result so far with stop_reason "cancelled". `outdoor` with another key is an
// error.
//
// `resume`, a checkpoint of this job (JobCallbacks::checkpoint, from any process), continues
// its search after the last step: no step is done again, and the job's clock goes on from
// the checkpoint's (time between the checkpoint and the resume left out; the stages before
// the search are done again and counted). With a deterministic backend (cpu) the result is
// an uninterrupted run's, times aside. InvalidArgument, before any stage, for a checkpoint of
// another format, of another job (JobContentHash) or whose history this job's search does
// not make.
absl::StatusOr<v1::JobResult> RunJob(const PreparedJob& job, const OutdoorMatrix* outdoor,
                                     const JobCallbacks& callbacks = {},
                                     const v1::SearchCheckpoint* resume = nullptr);

// The final check (JobResult.final_check, core/optimize/final_check.h) of `design` (variable
// name -> value, as JobResult.best_design; a variable left out is at its start) against the
// two-stage estimate `two_stage` of the job's metric, with the job's sky, metric settings,
// batches, seed and backend: what RunJob does after its search (bench/final_check_bench.cpp).
absl::StatusOr<v1::FinalCheck> CheckJobDesign(
    const PreparedJob& job, const google::protobuf::Map<std::string, double>& design,
    const v1::Estimate& two_stage);

}  // namespace fenestra
