#pragma once

#include <cstdint>
#include <vector>

#include "absl/status/status.h"
#include "core/dc/dc_backend.h"
#include "core/trace/one_stage_cpu.h"
#include "core/trace/path.h"
#include "core/trace/trace_geometry.h"

namespace fenestra {

// Shared by the DcBackend implementations.

// InvalidArgument unless the options and sensors can be traced.
absl::Status CheckOneStageInput(const std::vector<Sensor>& sensors, const OneStageOptions& options);

// The per-path settings the options ask for.
PathSettings PathSettingsFor(const OneStageOptions& options);

// The local frame's origin of a one-stage trace: the centre of the sensors' bounding box.
// Float coordinates are finest near the origin, and the fine parts of a scene (the blind's
// slats, millimetres apart when nearly closed) lie near the sensors, while a city's bounding
// box centres tens of metres away: there the 256-ulp ray offsets (core/trace/ray_offset.h)
// grow to half a millimetre and let light through gaps that are hardly wider.
Vec3d OneStageFrameOrigin(const std::vector<Sensor>& sensors);

// The sensors in `geometry`'s local frame, directions normalized.
std::vector<TraceSensor> LocalSensors(const TraceGeometry& geometry,
                                      const std::vector<Sensor>& sensors);

// The result of a one-stage trace of `paths` paths per sensor: coefficients, standard
// errors, sky sums and batches from the tally's sums, and its counts.
// With Sequence::kSobol the standard errors are those of the batches' scatter.
void FillOneStageResult(const OneStageTally& tally, int64_t paths, Sequence sequence,
                        OneStageResult* result);
// The batches a one-stage run traces (OneStageOptions::batches, sequence).
int OneStageBatches(const OneStageOptions& options);

// Weight windows need a pilot that saw light: with fewer scoring pilot paths than this
// (all sensors), the importance map is mostly noise and plain roulette is used instead.
inline constexpr uint64_t kMinPilotScoringPaths = 200;

// Pilot paths per sensor for weight windows: options.pilot_paths_per_sensor, or when 0,
// as many as the paths, at most max(20000, 600000 / sensors): the map's quality pays for
// a pilot that large (bench/README.md).
int64_t PilotPathsPerSensor(const OneStageOptions& options, size_t sensor_count);

// The indoor batches (each sensors x cells) one above the other, for the annual product;
// InvalidArgument unless every batch has the same rows and `cells` columns.
absl::StatusOr<Matrix> StackIndoorBatches(const std::vector<Matrix>& batches, Eigen::Index cells);

// A sky for the annual product: 146 sky bins as rows, or a split sky (kSplitSkyRows); or
// InvalidArgument.
absl::Status CheckSkyRows(const Matrix& sky);

// The rows through which a split sky's second block multiplies: the indoor rows' unreflected
// direct columns (the last kTregenzaBinCount of I, or of a one-stage [D | D_0]).
Matrix UnreflectedOf(const Matrix& stacked_indoor);

// The outdoor batches of an annual product: at least 2, of equal shape, 146 sky bins as
// columns like the sky's rows; or InvalidArgument.
absl::Status CheckOutdoorBatches(const std::vector<Matrix>& outdoor_batches, const Matrix& sky);

// FailedPrecondition unless a design tallies' annual product is set (DesignTallies::SetProduct).
absl::Status CheckProductSet(const AnnualProduct* product);

// Indoor batches that pair with the outdoor ones: as many, each with the same rows and as
// many columns as O_b has rows; or InvalidArgument.
absl::Status CheckPairs(const std::vector<Matrix>& indoor_batches,
                        const std::vector<Matrix>& outdoor_batches);

// The batches' light through the window, I_b O_b for every b, one above the other
// ((B x sensors) x 146), for batches that pair up (CheckPairs): a blocked matrix product per
// batch, the batches on all cores. With `unreflected`, their unreflected direct columns
// beside it ((B x sensors) x 292), for a split sky.
Matrix ThroughWindow(const std::vector<Matrix>& indoor_batches,
                     const std::vector<Matrix>& outdoor_batches, bool unreflected = false);

// a b, parts of b's columns on all cores. Eigen's own products are single-threaded here: its
// OpenMP threads, forking and joining for every small product, stalled whenever other
// processes held the cores (bench/README.md, "The annual products on the CPU").
Matrix ProductOnAllCores(const Matrix& a, const Matrix& b);

// The inverse: `count` batches of equal rows from a stacked matrix.
std::vector<Matrix> SplitBatches(const Matrix& stacked, size_t count);

}  // namespace fenestra
