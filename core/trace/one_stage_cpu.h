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
  // Independent batches: each sensor's paths split into this many contiguous, equal ranges
  // whose sums are also reported (for jackknife errors downstream); 1 = no batches.
  int batches = 1;
  PathSettings path{-1, true, 0.25f, 1u << 20};
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
  // With batches > 1: batch_sum[(s * batches + b) * kTregenzaBinCount + bin] over the paths
  // [b N / batches, (b + 1) N / batches) of sensor s.
  int batches = 1;
  std::vector<double> batch_sum;
  uint64_t rays = 0;               // closest-hit queries
  std::array<uint64_t, 6> ends{};  // paths by PathEnd
  float max_weight = 0;            // largest path throughput seen
  int threads = 0;                 // threads used
  double wall_seconds = 0;
};

// Paths per chunk for `paths_per_sensor`: at least 4096, at most about 256 chunks per
// sensor. Depends on the path count only, never on the thread count.
inline uint64_t OneStageChunkPaths(uint64_t paths_per_sensor) {
  constexpr uint64_t kMinChunk = 4096, kMaxChunks = 256;
  return std::max(kMinChunk, (paths_per_sensor + kMaxChunks - 1) / kMaxChunks);
}

// First path of batch `b` of `batches` over `paths` paths (b = batches gives `paths`).
inline uint64_t BatchStart(uint64_t paths, int batches, int b) {
  return static_cast<uint64_t>((static_cast<unsigned __int128>(paths) * b) / batches);
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
  uint32_t sensor;
  int batch;
  uint64_t first, last;  // paths [first, last)
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
  const int batches = std::max(1, settings.batches);
  const uint64_t chunk_paths = OneStageChunkPaths(n);
  OneStageTally tally;
  tally.sensor_count = static_cast<int>(sensors.size());
  tally.paths_per_sensor = n;
  tally.batches = batches;
  tally.threads = ResolveThreadCount(settings.threads);

  // Fixed chunks: each within one batch of one sensor
  std::vector<Chunk> chunks;
  for (uint32_t s = 0; s < sensors.size(); ++s) {
    for (int b = 0; b < batches; ++b) {
      const uint64_t end = BatchStart(n, batches, b + 1);
      for (uint64_t first = BatchStart(n, batches, b); first < end; first += chunk_paths) {
        Chunk chunk{};
        chunk.sensor = s;
        chunk.batch = b;
        chunk.first = first;
        chunk.last = std::min(end, first + chunk_paths);
        chunks.push_back(chunk);
      }
    }
  }

  // Trace the chunks in any order, each into its own slot
  ParallelFor(chunks.size(), tally.threads, [&](uint64_t c) {
    Chunk& chunk = chunks[c];
    const uint32_t s = chunk.sensor;
    one_stage_internal::ChunkSink sink{chunk.sum, chunk.sum_squares};
    OneStageMode<one_stage_internal::ChunkSink> mode{sensors[s].position, sensors[s].normal, &sink};
    for (uint64_t p = chunk.first; p < chunk.last; ++p) {
      const PathStats stats =
          TracePath(scene, surfaces, settings.path, PathRandom(settings.seed, s, p), mode);
      chunk.rays += stats.rays;
      ++chunk.ends[static_cast<int>(stats.end)];
      chunk.max_weight = std::max(chunk.max_weight, stats.max_weight);
    }
  });

  // Combine the chunks in a fixed order: into batches, then batches into the total
  const size_t bins = sensors.size() * kTregenzaBinCount;
  tally.sum.assign(bins, 0.0);
  tally.sum_squares.assign(bins, 0.0);
  std::vector<double> batch_sum(bins * batches, 0.0);
  for (const Chunk& chunk : chunks) {
    double* batch = &batch_sum[(chunk.sensor * batches + chunk.batch) * kTregenzaBinCount];
    double* sum_squares = &tally.sum_squares[chunk.sensor * kTregenzaBinCount];
    for (int b = 0; b < kTregenzaBinCount; ++b) {
      batch[b] += chunk.sum[b];
      sum_squares[b] += chunk.sum_squares[b];
    }
    tally.rays += chunk.rays;
    for (int e = 0; e < 6; ++e) tally.ends[e] += chunk.ends[e];
    tally.max_weight = std::max(tally.max_weight, chunk.max_weight);
  }
  for (size_t s = 0; s < sensors.size(); ++s) {
    for (int b = 0; b < batches; ++b) {
      for (int bin = 0; bin < kTregenzaBinCount; ++bin) {
        tally.sum[s * kTregenzaBinCount + bin] +=
            batch_sum[(s * batches + b) * kTregenzaBinCount + bin];
      }
    }
  }
  if (batches > 1) tally.batch_sum = std::move(batch_sum);
  tally.wall_seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return tally;
}

}  // namespace fenestra
