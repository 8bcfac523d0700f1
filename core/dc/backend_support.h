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

// Coefficients, standard errors and sky sums from per-sensor, per-bin sums of path values
// and of their squares (each path scores at most one bin), over `paths` paths per sensor.
void FillFromSums(const std::vector<double>& sum, const std::vector<double>& sum_squares,
                  int sensor_count, int64_t paths, OneStageResult* result);

// batch_coefficients from per-batch sums (batch_sum as OneStageTally), when batches > 1.
void FillBatches(const std::vector<double>& batch_sum, int sensor_count, int batches, int64_t paths,
                 OneStageResult* result);

}  // namespace fenestra
