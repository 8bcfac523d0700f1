#pragma once

#include <algorithm>
#include <array>
#include <chrono>
#include <cstdint>
#include <vector>

#include "core/common/vec3.h"
#include "core/trace/path.h"
#include "core/trace/philox.h"
#include "core/trace/thread_pool.h"

namespace fenestra {

struct OneStageSettings {
  uint64_t paths_per_sensor = 0;
  uint64_t seed = 0;
  int threads = 0;  // 0 = every hardware thread
  PathSettings path{-1, true, 1.0f, 1u << 20};
};

// Sums over paths, per sensor and bin: sum[s * kTregenzaBinCount + bin] of pi * weight and
// sum_squares of its square (a path escapes through one bin, so this is the per-path second
// moment). Sums are in double, per fixed chunk of paths and then over chunks in order, so
// they are bitwise identical for any thread count.
struct OneStageTally {
  int sensor_count = 0;
  uint64_t paths_per_sensor = 0;
  std::vector<double> sum;
  std::vector<double> sum_squares;
  uint64_t rays = 0;               // closest-hit queries
  std::array<uint64_t, 6> ends{};  // paths by PathEnd
  float max_weight = 0;            // largest path throughput seen
  int threads = 0;                 // threads used
  double wall_seconds = 0;
};

// Paths per chunk for `paths_per_sensor`: at least 4096, at most 256 chunks per sensor.
// Depends on the path count only, never on the thread count.
inline uint64_t OneStageChunkPaths(uint64_t paths_per_sensor) {
  constexpr uint64_t kMinChunk = 4096, kMaxChunks = 256;
  return std::max(kMinChunk, (paths_per_sensor + kMaxChunks - 1) / kMaxChunks);
}

namespace one_stage_internal {

struct ChunkSink {
  double* sum;
  double* sum_squares;
  void Add(int bin, double value) {
    sum[bin] += value;
    sum_squares[bin] += value * value;
  }
};

struct Chunk {
  double sum[kTregenzaBinCount];
  double sum_squares[kTregenzaBinCount];
  uint64_t rays;
  std::array<uint64_t, 6> ends;
  float max_weight;
};

}  // namespace one_stage_internal

// Traces settings.paths_per_sensor one-stage paths from each sensor on CPU threads.
// Path p of sensor s uses the random stream (seed, s, p).
template <class Intersector>
OneStageTally TraceOneStageCpu(const Intersector& scene, const SurfaceTable& surfaces,
                               const std::vector<TraceSensor>& sensors,
                               const OneStageSettings& settings) {
  using one_stage_internal::Chunk;
  const auto start = std::chrono::steady_clock::now();
  const uint64_t n = settings.paths_per_sensor;
  const uint64_t chunk_paths = OneStageChunkPaths(n);
  const uint64_t chunks_per_sensor = (n + chunk_paths - 1) / chunk_paths;
  std::vector<Chunk> chunks(chunks_per_sensor * sensors.size());
  OneStageTally tally;
  tally.sensor_count = static_cast<int>(sensors.size());
  tally.paths_per_sensor = n;
  tally.threads = ResolveThreadCount(settings.threads);

  // Trace the chunks in any order, each into its own slot
  ParallelFor(chunks.size(), tally.threads, [&](uint64_t c) {
    const uint32_t s = static_cast<uint32_t>(c / chunks_per_sensor);
    const uint64_t first = (c % chunks_per_sensor) * chunk_paths;
    const uint64_t last = std::min(n, first + chunk_paths);
    Chunk& chunk = chunks[c];
    chunk = Chunk{};
    one_stage_internal::ChunkSink sink{chunk.sum, chunk.sum_squares};
    OneStageMode<one_stage_internal::ChunkSink> mode{sensors[s].position, sensors[s].normal, &sink};
    for (uint64_t p = first; p < last; ++p) {
      const PathStats stats =
          TracePath(scene, surfaces, settings.path, PathRandom(settings.seed, s, p), mode);
      chunk.rays += stats.rays;
      ++chunk.ends[static_cast<int>(stats.end)];
      chunk.max_weight = std::max(chunk.max_weight, stats.max_weight);
    }
  });

  // Combine the chunks in a fixed order
  tally.sum.assign(sensors.size() * kTregenzaBinCount, 0.0);
  tally.sum_squares.assign(sensors.size() * kTregenzaBinCount, 0.0);
  for (uint64_t c = 0; c < chunks.size(); ++c) {
    const Chunk& chunk = chunks[c];
    double* sum = &tally.sum[(c / chunks_per_sensor) * kTregenzaBinCount];
    double* sum_squares = &tally.sum_squares[(c / chunks_per_sensor) * kTregenzaBinCount];
    for (int b = 0; b < kTregenzaBinCount; ++b) {
      sum[b] += chunk.sum[b];
      sum_squares[b] += chunk.sum_squares[b];
    }
    tally.rays += chunk.rays;
    for (int e = 0; e < 6; ++e) tally.ends[e] += chunk.ends[e];
    tally.max_weight = std::max(tally.max_weight, chunk.max_weight);
  }
  tally.wall_seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return tally;
}

}  // namespace fenestra
