// The one-stage tracer on the GPU: the shared per-path code (core/trace/path.h) with the
// brute-force intersector, one thread per path. A first, simple device backend: it shows
// the shared code compiles and runs under nvcc; a BVH traversal replaces the intersector
// later without changing the path code.
#include <cuda_runtime.h>

#include <vector>

#include "core/trace/brute_force_intersector.h"
#include "core/trace/cuda/one_stage_cuda.h"
#include "core/trace/path.h"
#include "core/trace/philox.h"

namespace fenestra {
namespace {

// Accumulates escapes into global per-sensor bins. Squares are per escape, which is per
// path while weight windows (splitting) are off, as they are here.
struct GlobalSink {
  double* sum;
  double* sum_squares;
  FENESTRA_CPU_GPU void Add(int bin, double value) {
#if defined(__CUDA_ARCH__)
    atomicAdd(&sum[bin], value);
    atomicAdd(&sum_squares[bin], value * value);
#else
    sum[bin] += value;
    sum_squares[bin] += value * value;
#endif
  }
  FENESTRA_CPU_GPU void EndPath() {}
};

__global__ void OneStageKernel(BruteForceIntersector scene, SurfaceTable surfaces,
                               PathSettings settings, const TraceSensor* sensors,
                               uint32_t sensor_count, uint64_t paths_per_sensor, uint64_t seed,
                               double* sum, double* sum_squares, unsigned long long* rays) {
  const uint64_t total = paths_per_sensor * sensor_count;
  unsigned long long my_rays = 0;
  for (uint64_t g = blockIdx.x * static_cast<uint64_t>(blockDim.x) + threadIdx.x; g < total;
       g += static_cast<uint64_t>(gridDim.x) * blockDim.x) {
    const uint32_t s = static_cast<uint32_t>(g / paths_per_sensor);
    const uint64_t p = g % paths_per_sensor;
    GlobalSink sink{sum + s * kTregenzaBinCount, sum_squares + s * kTregenzaBinCount};
    OneStageMode<GlobalSink> mode{sensors[s].position, sensors[s].normal, &sink};
    my_rays += TracePath(scene, surfaces, settings, PathRandom(seed, s, p), mode).rays;
  }
  atomicAdd(rays, my_rays);
}

// A device allocation freed on scope exit.
template <typename T>
class DeviceBuffer {
 public:
  DeviceBuffer() = default;
  ~DeviceBuffer() {
    if (data_ != nullptr) cudaFree(data_);
  }
  DeviceBuffer(const DeviceBuffer&) = delete;
  DeviceBuffer& operator=(const DeviceBuffer&) = delete;

  cudaError_t Allocate(size_t count) {
    return cudaMalloc(reinterpret_cast<void**>(&data_), (count > 0 ? count : 1) * sizeof(T));
  }
  cudaError_t Upload(const T* host, size_t count) {
    cudaError_t e = Allocate(count);
    if (e != cudaSuccess || count == 0) return e;
    return cudaMemcpy(data_, host, count * sizeof(T), cudaMemcpyHostToDevice);
  }
  cudaError_t Download(T* host, size_t count) const {
    return cudaMemcpy(host, data_, count * sizeof(T), cudaMemcpyDeviceToHost);
  }
  T* get() const { return data_; }

 private:
  T* data_ = nullptr;
};

}  // namespace

bool CudaDeviceAvailable() {
  int count = 0;
  return cudaGetDeviceCount(&count) == cudaSuccess && count > 0;
}

std::string TraceOneStageCuda(const CudaOneStageInput& input, double* sum, double* sum_squares,
                              uint64_t* rays) {
  const size_t bins = static_cast<size_t>(input.sensor_count) * kTregenzaBinCount;
  DeviceBuffer<Vec3f> vertices;
  DeviceBuffer<uint32_t> triangle_material;
  DeviceBuffer<TraceMaterial> materials;
  DeviceBuffer<TraceSensor> sensors;
  DeviceBuffer<double> d_sum, d_sum_squares;
  DeviceBuffer<unsigned long long> d_rays;
  cudaError_t e = cudaSuccess;
  const auto ok = [&](cudaError_t result) {
    if (e == cudaSuccess) e = result;
    return e == cudaSuccess;
  };

  // Upload the scene and zero the bins
  ok(vertices.Upload(input.vertices, 3 * static_cast<size_t>(input.triangle_count)));
  ok(triangle_material.Upload(input.triangle_material, input.triangle_count));
  ok(materials.Upload(input.materials, input.material_count));
  ok(sensors.Upload(input.sensors, input.sensor_count));
  ok(d_sum.Allocate(bins));
  ok(d_sum_squares.Allocate(bins));
  ok(d_rays.Allocate(1));
  if (e == cudaSuccess) {
    ok(cudaMemset(d_sum.get(), 0, bins * sizeof(double)));
    ok(cudaMemset(d_sum_squares.get(), 0, bins * sizeof(double)));
    ok(cudaMemset(d_rays.get(), 0, sizeof(unsigned long long)));
  }

  // Trace, one thread per path
  if (e == cudaSuccess) {
    const BruteForceIntersector scene{vertices.get(), input.triangle_count};
    const SurfaceTable surfaces{materials.get(), triangle_material.get()};
    OneStageKernel<<<1024, 128>>>(scene, surfaces, input.path, sensors.get(), input.sensor_count,
                                  input.paths_per_sensor, input.seed, d_sum.get(),
                                  d_sum_squares.get(), d_rays.get());
    ok(cudaGetLastError());
    ok(cudaDeviceSynchronize());
  }

  // Download
  unsigned long long ray_count = 0;
  ok(d_sum.Download(sum, bins));
  ok(d_sum_squares.Download(sum_squares, bins));
  ok(d_rays.Download(&ray_count, 1));
  if (e != cudaSuccess) return cudaGetErrorString(e);
  *rays = ray_count;
  return "";
}

}  // namespace fenestra
