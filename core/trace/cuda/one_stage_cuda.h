#pragma once

#include <cstdint>
#include <string>

#include "core/common/vec3.h"
#include "core/trace/path.h"

namespace fenestra {

// Host arrays describing one one-stage run on the GPU (brute-force intersection).
struct CudaOneStageInput {
  const Vec3f* vertices = nullptr;  // 3 per triangle, local frame
  uint32_t triangle_count = 0;
  const uint32_t* triangle_material = nullptr;
  const TraceMaterial* materials = nullptr;
  uint32_t material_count = 0;
  const TraceSensor* sensors = nullptr;
  uint32_t sensor_count = 0;
  uint64_t paths_per_sensor = 0;
  uint64_t seed = 0;
  PathSettings path{-1, true, 0.25f, 1u << 20};
};

// Whether a CUDA device is present.
bool CudaDeviceAvailable();

// Traces the run with the shared path code (TracePath, OneStageMode) and a brute-force
// intersector. `sum` and `sum_squares` receive sensor_count * kTregenzaBinCount doubles
// (as OneStageTally), `rays` the closest-hit queries. Returns "" or the CUDA error.
std::string TraceOneStageCuda(const CudaOneStageInput& input, double* sum, double* sum_squares,
                              uint64_t* rays);

}  // namespace fenestra
