#pragma once

// CPU drivers of the two-stage modes (core/trace/two_stage_modes.h): chunks of paths on
// a thread pool, each chunk into its own tally, folded in a fixed order, so results are
// bitwise identical for any thread count.
#include <algorithm>
#include <array>
#include <chrono>
#include <cstdint>
#include <vector>

#include "core/geometry/hemisphere_basis.h"
#include "core/trace/one_stage_cpu.h"
#include "core/trace/path.h"
#include "core/trace/philox.h"
#include "core/trace/thread_pool.h"
#include "core/trace/two_stage_modes.h"

namespace fenestra {

// Counts shared by the stages.
struct TraceCounters {
  uint64_t rays = 0;               // closest-hit queries
  std::array<uint64_t, 6> ends{};  // paths by PathEnd
  float max_weight = 0;

  void Add(const PathStats& stats) {
    rays += stats.rays;
    ++ends[static_cast<int>(stats.end)];
    max_weight = std::max(max_weight, stats.max_weight);
  }
  void Add(const TraceCounters& other) {
    rays += other.rays;
    for (size_t e = 0; e < ends.size(); ++e) ends[e] += other.ends[e];
    max_weight = std::max(max_weight, other.max_weight);
  }
};

// Runs trace_chunk(c, slot_c) for c in [0, count) on `threads` threads, then
// fold(c, slot_c) in order of c.
template <class Slot, class TraceChunk, class Fold>
void TraceChunksCpu(uint64_t count, int threads, TraceChunk trace_chunk, Fold fold) {
  std::vector<Slot> slots(count);
  ParallelFor(count, threads, [&](uint64_t c) { trace_chunk(c, slots[c]); });
  for (uint64_t c = 0; c < count; ++c) fold(c, slots[c]);
}

// Outdoor stage: paths_per_cell paths per basis cell; O[cell, bin] sums of weight and
// weight² (a path escapes through one bin: the per-path second moment).
struct OutdoorTally {
  int cells = 0;
  uint64_t paths_per_cell = 0;
  std::vector<double> sum;          // cells x kTregenzaBinCount
  std::vector<double> sum_squares;  // cells x kTregenzaBinCount
  TraceCounters counters;
  int threads = 0;
  double wall_seconds = 0;
};

template <class Intersector>
OutdoorTally TraceOutdoorCpu(const Intersector& scene, const SurfaceTable& surfaces,
                             const TraceWindow& window, const HemisphereBasis& basis,
                             uint64_t paths_per_cell, uint64_t seed, const PathSettings& path,
                             int threads) {
  struct Slot {
    double sum[kTregenzaBinCount] = {};
    double sum_squares[kTregenzaBinCount] = {};
    TraceCounters counters;
    void Add(int bin, double value) {
      sum[bin] += value;
      sum_squares[bin] += value * value;
    }
  };
  const auto start = std::chrono::steady_clock::now();
  const uint64_t chunk_paths = std::max<uint64_t>(4096, (paths_per_cell + 63) / 64);
  const uint64_t chunks_per_cell = (paths_per_cell + chunk_paths - 1) / chunk_paths;
  OutdoorTally tally;
  tally.cells = WindowCellCount(window, basis);
  tally.paths_per_cell = paths_per_cell;
  tally.threads = ResolveThreadCount(threads);
  tally.sum.assign(static_cast<size_t>(tally.cells) * kTregenzaBinCount, 0.0);
  tally.sum_squares.assign(tally.sum.size(), 0.0);
  TraceChunksCpu<Slot>(
      chunks_per_cell * tally.cells, tally.threads,
      [&](uint64_t c, Slot& slot) {
        const int cell = static_cast<int>(c / chunks_per_cell);
        const uint64_t first = (c % chunks_per_cell) * chunk_paths;
        const uint64_t last = std::min(paths_per_cell, first + chunk_paths);
        OutdoorMode<Slot> mode{window, &basis, cell, &slot};
        for (uint64_t p = first; p < last; ++p) {
          slot.counters.Add(TracePath(scene, surfaces, path,
                                      PathRandom(seed, kOutdoorStreamBase + cell, p), mode));
        }
      },
      [&](uint64_t c, const Slot& slot) {
        const size_t row = (c / chunks_per_cell) * kTregenzaBinCount;
        for (int b = 0; b < kTregenzaBinCount; ++b) {
          tally.sum[row + b] += slot.sum[b];
          tally.sum_squares[row + b] += slot.sum_squares[b];
        }
        tally.counters.Add(slot.counters);
      });
  tally.wall_seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return tally;
}

// Indoor stage: paths_per_sensor paths per sensor in `batches` equal, contiguous batches of
// path indices; sums of the contributions per (batch, sensor, cell).
struct IndoorTally {
  int sensors = 0;
  int cells = 0;
  int batches = 0;
  uint64_t paths_per_sensor = 0;
  std::vector<double> sum;            // [(batch * sensors + sensor) * cells + cell]
  std::vector<uint64_t> batch_paths;  // paths in each batch
  TraceCounters counters;
  int threads = 0;
  double wall_seconds = 0;
  double trace_seconds = 0;  // the tracing itself (on a GPU: the kernel)
};

template <class Intersector>
IndoorTally TraceIndoorCpu(const Intersector& scene, const SurfaceTable& surfaces,
                           const std::vector<TraceSensor>& sensors, const TraceWindow& window,
                           const HemisphereBasis& basis, uint64_t paths_per_sensor, int batches,
                           uint64_t seed, const PathSettings& path, int threads) {
  struct Slot {
    std::vector<double> sum;
    TraceCounters counters;
    void Add(int cell, double value) { sum[cell] += value; }
  };
  const auto start = std::chrono::steady_clock::now();
  const int cells = WindowCellCount(window, basis);
  IndoorTally tally;
  tally.sensors = static_cast<int>(sensors.size());
  tally.cells = cells;
  tally.batches = batches;
  tally.paths_per_sensor = paths_per_sensor;
  tally.threads = ResolveThreadCount(threads);
  tally.sum.assign(static_cast<size_t>(batches) * sensors.size() * cells, 0.0);
  for (int b = 0; b < batches; ++b) {
    tally.batch_paths.push_back(BatchStart(paths_per_sensor, batches, b + 1) -
                                BatchStart(paths_per_sensor, batches, b));
  }
  // Chunks: (sensor, batch, part of the batch)
  const uint64_t batch_paths = (paths_per_sensor + batches - 1) / batches;
  const uint64_t parts = std::max<uint64_t>(1, std::min<uint64_t>(8, batch_paths / 2048));
  const uint64_t chunk_count = sensors.size() * batches * parts;
  TraceChunksCpu<Slot>(
      chunk_count, tally.threads,
      [&](uint64_t c, Slot& slot) {
        const uint32_t s = static_cast<uint32_t>(c / (batches * parts));
        const uint64_t b = (c / parts) % batches;
        const uint64_t part = c % parts;
        const uint64_t batch_first = BatchStart(paths_per_sensor, batches, static_cast<int>(b));
        const uint64_t batch_size = tally.batch_paths[b];
        const uint64_t first = batch_first + part * batch_size / parts;
        const uint64_t last = batch_first + (part + 1) * batch_size / parts;
        slot.sum.assign(cells, 0.0);
        IndoorMode<Slot> mode{
            sensors[s].position, sensors[s].normal, window, &basis, path.max_bounces, &slot};
        for (uint64_t p = first; p < last; ++p) {
          slot.counters.Add(TracePath(scene, surfaces, path, PathRandom(seed, s, p), mode));
        }
      },
      [&](uint64_t c, const Slot& slot) {
        const uint64_t s = c / (batches * parts);
        const uint64_t b = (c / parts) % batches;
        double* row = &tally.sum[(b * sensors.size() + s) * cells];
        for (int k = 0; k < cells; ++k) row[k] += slot.sum[k];
        tally.counters.Add(slot.counters);
      });
  tally.wall_seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  tally.trace_seconds = tally.wall_seconds;
  return tally;
}

}  // namespace fenestra
