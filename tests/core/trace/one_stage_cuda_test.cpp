// The GPU one-stage tracer against the CPU running the same path code and intersector.
#include "core/trace/cuda/one_stage_cuda.h"

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "core/trace/brute_force_intersector.h"
#include "core/trace/one_stage_cpu.h"
#include "core/trace/trace_geometry.h"
#include "tests/core/trace/test_meshes.h"

namespace fenestra {
namespace {

TEST(OneStageCudaTest, MatchesTheCpuWithinRounding) {
  if (!CudaDeviceAvailable()) GTEST_SKIP() << "no CUDA device";
  // A room with an opening in the north wall, sensors facing up
  TriangleMesh mesh;
  using testing_meshes::AddQuad;
  AddQuad(mesh, {-1.5, -6, 0}, {1.5, -6, 0}, {1.5, 0, 0}, {-1.5, 0, 0}, 1);
  AddQuad(mesh, {-1.5, -6, 3}, {1.5, -6, 3}, {1.5, 0, 3}, {-1.5, 0, 3}, 0);
  AddQuad(mesh, {-1.5, -6, 0}, {1.5, -6, 0}, {1.5, -6, 3}, {-1.5, -6, 3}, 0);
  AddQuad(mesh, {-1.5, -6, 0}, {-1.5, 0, 0}, {-1.5, 0, 3}, {-1.5, -6, 3}, 0);
  AddQuad(mesh, {1.5, -6, 0}, {1.5, 0, 0}, {1.5, 0, 3}, {1.5, -6, 3}, 0);
  AddQuad(mesh, {-1.5, 0, 0}, {1.5, 0, 0}, {1.5, 0, 1}, {-1.5, 0, 1}, 0);
  const TraceGeometry geometry =
      *PrepareTraceGeometry(mesh, {{"wall", 0.8, -1}, {"floor", 0.2, -1}});
  const std::vector<TraceSensor> sensors = {{geometry.ToLocal({0, -1, 0.7}), {0, 0, 1}},
                                            {geometry.ToLocal({0, -5, 0.7}), {0, 0, 1}}};
  OneStageSettings settings;
  settings.paths_per_sensor = 200000;
  settings.seed = 17;
  settings.path = {29, true, 1.0f, 1u << 20};

  const BruteForceIntersector cpu_scene{geometry.vertices.data(),
                                        static_cast<uint32_t>(geometry.TriangleCount())};
  const OneStageTally cpu = TraceOneStageCpu(cpu_scene, geometry.Surfaces(), sensors, settings);

  CudaOneStageInput input;
  input.vertices = geometry.vertices.data();
  input.triangle_count = static_cast<uint32_t>(geometry.TriangleCount());
  input.triangle_material = geometry.triangle_material.data();
  input.materials = geometry.materials.data();
  input.material_count = static_cast<uint32_t>(geometry.materials.size());
  input.sensors = sensors.data();
  input.sensor_count = static_cast<uint32_t>(sensors.size());
  input.paths_per_sensor = settings.paths_per_sensor;
  input.seed = settings.seed;
  input.path = settings.path;
  std::vector<double> sum(sensors.size() * kTregenzaBinCount);
  std::vector<double> sum_squares(sum.size());
  uint64_t rays = 0;
  ASSERT_EQ(TraceOneStageCuda(input, sum.data(), sum_squares.data(), &rays), "");

  // Same streams, same code: the paths agree except where float rounding differs (FMA)
  EXPECT_NEAR(static_cast<double>(rays), static_cast<double>(cpu.rays), 1e-3 * cpu.rays);
  for (size_t s = 0; s < sensors.size(); ++s) {
    double cpu_total = 0, gpu_total = 0;
    for (int b = 0; b < kTregenzaBinCount; ++b) {
      cpu_total += cpu.sum[s * kTregenzaBinCount + b];
      gpu_total += sum[s * kTregenzaBinCount + b];
    }
    EXPECT_NEAR(gpu_total, cpu_total, 2e-3 * cpu_total) << "sensor " << s;
  }
}

}  // namespace
}  // namespace fenestra
