#pragma once

#include <cstdint>
#include <vector>

#include "absl/status/status.h"
#include "core/dc/dc_backend.h"
#include "core/trace/path.h"
#include "core/trace/trace_geometry.h"

namespace fenestra {

// Shared by the DcBackend implementations.

// InvalidArgument unless the options and sensors can be traced.
absl::Status CheckOneStageInput(const std::vector<Sensor>& sensors, const OneStageOptions& options);

// The per-path settings the options ask for.
PathSettings PathSettingsFor(const OneStageOptions& options);

// The sensors in `geometry`'s local frame, directions normalized.
std::vector<TraceSensor> LocalSensors(const TraceGeometry& geometry,
                                      const std::vector<Sensor>& sensors);

// Coefficients, standard errors and sky sums from per-sensor, per-bin sums of path scores
// and of their squares, and per-sensor sums of the squared sky score of each path, over
// `paths` paths per sensor.
void FillFromSums(const std::vector<double>& sum, const std::vector<double>& sum_squares,
                  const std::vector<double>& sky_sum_squares, int sensor_count, int64_t paths,
                  OneStageResult* result);

// Weight windows need a pilot that saw light: with fewer scoring pilot paths than this
// (all sensors), the importance map is mostly noise and plain roulette is used instead.
inline constexpr uint64_t kMinPilotScoringPaths = 200;

// Pilot paths per sensor for weight windows: options.pilot_paths_per_sensor, or when 0,
// as many as the paths, at most max(20000, 600000 / sensors): the map's quality pays for
// a pilot that large (bench/README.md).
int64_t PilotPathsPerSensor(const OneStageOptions& options, size_t sensor_count);

// batch_coefficients from per-batch sums (batch_sum as OneStageTally), when batches > 1.
void FillBatches(const std::vector<double>& batch_sum, int sensor_count, int batches, int64_t paths,
                 OneStageResult* result);

// The indoor batches (each sensors x cells) one above the other, for the annual product;
// InvalidArgument unless every batch has the same rows and `cells` columns.
absl::StatusOr<Matrix> StackIndoorBatches(const std::vector<Matrix>& batches, Eigen::Index cells);

// The inverse: `count` batches of equal rows from a stacked matrix.
std::vector<Matrix> SplitBatches(const Matrix& stacked, size_t count);

// The path-end counts of a run (indexed by PathEnd) into `result`.
template <class Ends>
void FillEnds(const Ends& ends, OneStageResult* result) {
  result->escaped_paths = ends[static_cast<int>(PathEnd::kEscaped)];
  result->roulette_paths = ends[static_cast<int>(PathEnd::kRoulette)];
  result->bounce_limit_paths = ends[static_cast<int>(PathEnd::kBounceLimit)];
  result->truncated_paths = ends[static_cast<int>(PathEnd::kTruncated)];
}

}  // namespace fenestra
