#pragma once

// CPU drivers of the two-stage modes (core/trace/two_stage_modes.h): chunks of paths on
// a thread pool, each chunk into its own tally, folded in a fixed order, so results are
// bitwise identical for any thread count.
#include <algorithm>
#include <array>
#include <chrono>
#include <cstdint>
#include <vector>

#include "core/common/thread_pool.h"
#include "core/geometry/hemisphere_basis.h"
#include "core/trace/one_stage_cpu.h"
#include "core/trace/path.h"
#include "core/trace/philox.h"
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

// Outdoor stage: paths_per_cell paths per window cell in `batches` equal, contiguous batches
// of path indices; per (batch, cell) a row of kOutdoorRowSize sums (OutdoorMode: the
// reflected light per sky bin, then the paths whose first segment reached the sky).
struct OutdoorTally {
  int cells = 0;
  int batches = 0;
  uint64_t paths_per_cell = 0;
  std::vector<uint64_t> batch_paths;  // paths of each cell in each batch
  std::vector<double> sum;            // [(batch * cells + cell) * kOutdoorRowSize + entry]
  TraceCounters counters;
  int threads = 0;
  double wall_seconds = 0;
};

// The batch sizes of `paths` split into `batches`.
inline std::vector<uint64_t> BatchSizes(uint64_t paths, int batches) {
  std::vector<uint64_t> sizes;
  for (int b = 0; b < batches; ++b) {
    sizes.push_back(BatchStart(paths, batches, b + 1) - BatchStart(paths, batches, b));
  }
  return sizes;
}

// Each batch split into `parts` parts of consecutive paths (the rounds of the indoor replays,
// core/dc/indoor_replay.h): part p of batch b starts at path PartStart(paths, batches, parts,
// b, p), the batches x parts batches of all paths, so a batch's parts are exactly its paths.
inline uint64_t PartStart(uint64_t paths, int batches, int parts, int b, int p) {
  return BatchStart(paths, batches * parts, b * parts + p);
}

// Per batch, the paths of its parts [first, last).
inline std::vector<uint64_t> PartPaths(uint64_t paths, int batches, int parts, int first,
                                       int last) {
  std::vector<uint64_t> sizes;
  for (int b = 0; b < batches; ++b) {
    sizes.push_back(PartStart(paths, batches, parts, b, last) -
                    PartStart(paths, batches, parts, b, first));
  }
  return sizes;
}

// The outdoor paths of window `w` of `windows` (LinkWindows).
template <class Intersector>
OutdoorTally TraceOutdoorCpu(const Intersector& scene, const SurfaceTable& surfaces,
                             const std::vector<TraceWindow>& windows, int w,
                             const HemisphereBasis& basis, uint64_t paths_per_cell, int batches,
                             uint64_t seed, const PathSettings& path, int threads) {
  const TraceWindow& window = windows[w];
  const TraceWindows all = ViewOfWindows(windows, basis);
  const uint32_t streams = kOutdoorStreamBase + static_cast<uint32_t>(w) * kOutdoorWindowStreams;
  struct Slot {
    double sum[kOutdoorRowSize] = {};
    TraceCounters counters;
    void Add(int bin, double value) { sum[bin] += value; }
    void AddFirstEscape() { sum[kFirstEscapeEntry] += 1.0; }
  };
  const auto start = std::chrono::steady_clock::now();
  OutdoorTally tally;
  tally.cells = WindowCellCount(window, basis);
  tally.batches = batches;
  tally.paths_per_cell = paths_per_cell;
  tally.batch_paths = BatchSizes(paths_per_cell, batches);
  tally.threads = ResolveThreadCount(threads);
  tally.sum.assign(static_cast<size_t>(batches) * tally.cells * kOutdoorRowSize, 0.0);
  // Chunks: (cell, batch, part of the batch)
  const uint64_t batch_paths = (paths_per_cell + batches - 1) / batches;
  const uint64_t parts = std::max<uint64_t>(1, std::min<uint64_t>(8, batch_paths / 4096));
  TraceChunksCpu<Slot>(
      static_cast<uint64_t>(tally.cells) * batches * parts, tally.threads,
      [&](uint64_t c, Slot& slot) {
        const int cell = static_cast<int>(c / (batches * parts));
        const int b = static_cast<int>((c / parts) % batches);
        const uint64_t part = c % parts;
        const uint64_t batch_first = BatchStart(paths_per_cell, batches, b);
        const uint64_t size = tally.batch_paths[b];
        OutdoorMode<Slot> mode{window, all, &basis, cell, &slot};
        for (uint64_t p = batch_first + part * size / parts;
             p < batch_first + (part + 1) * size / parts; ++p) {
          slot.counters.Add(
              TracePath(scene, surfaces, path,
                        PathRandom(seed, streams + cell, p, path.sequence, batch_first), mode));
        }
      },
      [&](uint64_t c, const Slot& slot) {
        const uint64_t cell = c / (batches * parts), b = (c / parts) % batches;
        double* row = &tally.sum[(b * tally.cells + cell) * kOutdoorRowSize];
        for (int e = 0; e < kOutdoorRowSize; ++e) row[e] += slot.sum[e];
        tally.counters.Add(slot.counters);
      });
  tally.wall_seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return tally;
}

// Indoor stage: paths_per_sensor paths per sensor in `batches` equal, contiguous batches of
// path indices; sums of the contributions per (batch, sensor, column): the window cells,
// then the sky bins' direct columns (IndoorColumnCount).
struct IndoorTally {
  int sensors = 0;
  int columns = 0;
  int batches = 0;
  uint64_t paths_per_sensor = 0;
  std::vector<double> sum;            // [(batch * sensors + sensor) * columns + column]
  std::vector<uint64_t> batch_paths;  // paths in each batch
  TraceCounters counters;
  int threads = 0;
  double wall_seconds = 0;
  double trace_seconds = 0;  // the tracing itself (on a GPU: the kernel)
};

template <class Intersector, class Outdoor>
IndoorTally TraceIndoorCpu(const Intersector& scene, const SurfaceTable& surfaces,
                           const Outdoor& outdoor, const std::vector<TraceSensor>& sensors,
                           const std::vector<TraceWindow>& windows, const HemisphereBasis& basis,
                           uint64_t paths_per_sensor, int batches, uint64_t seed,
                           const PathSettings& path, int threads) {
  struct Slot {
    std::vector<double> sum;
    TraceCounters counters;
    void Add(int cell, double value) { sum[cell] += value; }
  };
  const auto start = std::chrono::steady_clock::now();
  const TraceWindows all = ViewOfWindows(windows, basis);
  const int columns = IndoorColumnCount(all);
  IndoorTally tally;
  tally.sensors = static_cast<int>(sensors.size());
  tally.columns = columns;
  tally.batches = batches;
  tally.paths_per_sensor = paths_per_sensor;
  tally.threads = ResolveThreadCount(threads);
  tally.sum.assign(static_cast<size_t>(batches) * sensors.size() * columns, 0.0);
  tally.batch_paths = BatchSizes(paths_per_sensor, batches);
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
        slot.sum.assign(columns, 0.0);
        IndoorMode<Slot, Outdoor> mode{sensors[s].position, sensors[s].normal, all,  &basis,
                                       path.max_bounces,    &outdoor,          &slot};
        for (uint64_t p = first; p < last; ++p) {
          slot.counters.Add(TracePath(scene, surfaces, path,
                                      PathRandom(seed, s, p, path.sequence, batch_first), mode));
        }
      },
      [&](uint64_t c, const Slot& slot) {
        const uint64_t s = c / (batches * parts);
        const uint64_t b = (c / parts) % batches;
        double* row = &tally.sum[(b * sensors.size() + s) * columns];
        for (int k = 0; k < columns; ++k) row[k] += slot.sum[k];
        tally.counters.Add(slot.counters);
      });
  tally.wall_seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  tally.trace_seconds = tally.wall_seconds;
  return tally;
}

}  // namespace fenestra
