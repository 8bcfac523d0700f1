#pragma once

// CPU driver of the one-stage mode: chunks of paths on a thread pool, each chunk into its
// own slot, folded in a fixed order, so results are bitwise identical for any thread
// count. Optionally a pilot pass first learns an importance map for weight windows.
#include <algorithm>
#include <array>
#include <chrono>
#include <cstdint>
#include <map>
#include <vector>

#include "absl/container/flat_hash_map.h"
#include "core/common/thread_pool.h"
#include "core/common/vec3.h"
#include "core/trace/importance.h"
#include "core/trace/path.h"
#include "core/trace/philox.h"

namespace fenestra {

// Random streams of pilot paths: apart from the sensors' own.
inline constexpr uint32_t kPilotStreamBase = 0x40000000u;

// What one CPU trace of one-stage paths takes (TraceOneStageCpu), made from a request's
// OneStageOptions (core/dc/dc_backend.h) by the Embree backend.
struct OneStageCpuRun {
  uint64_t paths_per_sensor = 0;
  uint64_t seed = 0;
  int threads = 0;  // 0 = every hardware thread
  // Independent batches: each sensor's paths split into this many contiguous, equal ranges
  // whose sums are also reported (for jackknife errors downstream); 1 = no batches.
  int batches = 1;
  PathSettings path{-1, true, 0.25f, 1u << 20};
  // Per sensor, the weight windows' scale (path.importance set): the mean score of a path
  // from that sensor; 0 = plain roulette for that sensor.
  std::vector<float> window_scale;
};

// Sums over paths, per sensor and bin: sum[s * kOneStageBins + bin] of the path's
// score in that bin (pi * weight, summed over its branches) and sum_squares of its square:
// the per-path second moment. sky_sum_squares[s]: the square of each path's score over the
// sky bins (IsOneStageSkyBin), summed. Sums are in double, per fixed chunk of paths and then over
// chunks in order, so they are bitwise identical for any thread count.
struct OneStageTally {
  int sensor_count = 0;
  uint64_t paths_per_sensor = 0;
  std::vector<double> sum;
  std::vector<double> sum_squares;
  std::vector<double> sky_sum_squares;
  // With batches > 1: batch_sum[(s * batches + b) * kOneStageBins + bin] over the paths
  // [b N / batches, (b + 1) N / batches) of sensor s.
  int batches = 1;
  std::vector<double> batch_sum;
  uint64_t rays = 0;               // closest-hit queries
  uint64_t branches = 0;           // paths plus splits
  std::array<uint64_t, 6> ends{};  // branches by PathEnd
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

// A chunk's sums; a path's branches are gathered first, so squares are per path.
struct ChunkSink {
  double* sum;
  double* sum_squares;
  double sky_sum_squares = 0;
  double path_score[kOneStageBins] = {};
  int touched[kOneStageBins] = {};
  int touched_count = 0;

  void Add(int bin, double value) {
    if (path_score[bin] == 0.0) touched[touched_count++] = bin;
    path_score[bin] += value;
  }
  void EndPath() {
    double sky = 0;
    for (int i = 0; i < touched_count; ++i) {
      const int bin = touched[i];
      const double v = path_score[bin];
      sum[bin] += v;
      sum_squares[bin] += v * v;
      if (IsOneStageSkyBin(bin)) sky += v;
      path_score[bin] = 0.0;
    }
    sky_sum_squares += sky * sky;
    touched_count = 0;
  }
};

struct Chunk {
  uint32_t sensor;
  int batch;
  uint64_t first, last;  // paths [first, last)
  double sum[kOneStageBins];
  double sum_squares[kOneStageBins];
  double sky_sum_squares;
  uint64_t rays;
  uint64_t branches;
  std::array<uint64_t, 6> ends;
  float max_weight;
};

}  // namespace one_stage_internal

// Traces settings.paths_per_sensor one-stage paths from each sensor on CPU threads.
// Path p of sensor s uses the random stream (seed, s, p).
template <class Intersector>
OneStageTally TraceOneStageCpu(const Intersector& scene, const SurfaceTable& surfaces,
                               const std::vector<TraceSensor>& sensors,
                               const OneStageCpuRun& settings) {
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

  // Per-sensor path settings: weight windows scaled to the sensor, or plain roulette
  std::vector<PathSettings> path_settings(sensors.size(), settings.path);
  for (size_t s = 0; s < sensors.size(); ++s) {
    const float scale = s < settings.window_scale.size() ? settings.window_scale[s] : 0.0f;
    path_settings[s].window_scale = scale;
    if (!(scale > 0.0f)) path_settings[s].importance = nullptr;
  }

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
    const uint64_t batch_first = BatchStart(n, batches, chunk.batch);
    for (uint64_t p = chunk.first; p < chunk.last; ++p) {
      const PathStats stats =
          TracePath(scene, surfaces, path_settings[s],
                    PathRandom(settings.seed, s, p, path_settings[s].sequence, batch_first), mode);
      chunk.rays += stats.rays;
      chunk.branches += stats.branches;
      for (int e = 0; e < 6; ++e) chunk.ends[e] += stats.ends[e];
      chunk.max_weight = std::max(chunk.max_weight, stats.max_weight);
    }
    chunk.sky_sum_squares = sink.sky_sum_squares;
  });

  // Combine the chunks in a fixed order: into batches, then batches into the total
  const size_t bins = sensors.size() * kOneStageBins;
  tally.sum.assign(bins, 0.0);
  tally.sum_squares.assign(bins, 0.0);
  tally.sky_sum_squares.assign(sensors.size(), 0.0);
  std::vector<double> batch_sum(bins * batches, 0.0);
  for (const Chunk& chunk : chunks) {
    double* batch = &batch_sum[(chunk.sensor * batches + chunk.batch) * kOneStageBins];
    double* sum_squares = &tally.sum_squares[chunk.sensor * kOneStageBins];
    for (int b = 0; b < kOneStageBins; ++b) {
      batch[b] += chunk.sum[b];
      sum_squares[b] += chunk.sum_squares[b];
    }
    tally.sky_sum_squares[chunk.sensor] += chunk.sky_sum_squares;
    tally.rays += chunk.rays;
    tally.branches += chunk.branches;
    for (int e = 0; e < 6; ++e) tally.ends[e] += chunk.ends[e];
    tally.max_weight = std::max(tally.max_weight, chunk.max_weight);
  }
  for (size_t s = 0; s < sensors.size(); ++s) {
    for (int b = 0; b < batches; ++b) {
      for (int bin = 0; bin < kOneStageBins; ++bin) {
        tally.sum[s * kOneStageBins + bin] += batch_sum[(s * batches + b) * kOneStageBins + bin];
      }
    }
  }
  if (batches > 1) tally.batch_sum = std::move(batch_sum);
  tally.wall_seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return tally;
}

// What a pilot pass learned: the importance of the cells its paths visited, and the mean
// score of a path from each sensor.
struct ImportancePilot {
  ImportanceTable table;
  std::vector<double> mean_score;  // per sensor
  uint64_t paths = 0;              // all sensors
  uint64_t scoring_paths = 0;      // paths with a nonzero score, all sensors
  uint64_t rays = 0;
  double wall_seconds = 0;
};

namespace one_stage_internal {

// Records a pilot path's reflections (cell, weight leaving) and its score.
struct PilotMode {
  static constexpr int kMaxRecords = 64;
  Vec3f sensor_position;
  Vec3f sensor_normal;
  float inverse_cell_m;
  uint64_t keys[kMaxRecords] = {};
  float weights[kMaxRecords] = {};
  int records = 0;
  double score = 0;

  template <class Intersector>
  PathState Start(const Intersector& scene, const PathRandom& random) {
    records = 0;
    score = 0;
    return OneStageMode<PilotMode>{sensor_position, sensor_normal, nullptr}.Start(scene, random);
  }
  template <class Intersector>
  void AtReflection(const Intersector&, const PathState& path, const ReflectionVertex& vertex,
                    const PathRandom&) {
    if (records == kMaxRecords) return;
    keys[records] = CellKey(vertex.position, vertex.normal, inverse_cell_m);
    weights[records] = path.weight * vertex.scatter->total;
    ++records;
  }
  void Escape(const PathState& path) { score += kPi * static_cast<double>(path.weight); }
  void Finish(const PathStats&) {}
};

}  // namespace one_stage_internal

// Traces `paths_per_sensor` pilot paths from each sensor (streams kPilotStreamBase + s,
// weight windows off) and estimates the importance of every cell they reflect in: the
// mean of score / weight leaving the reflection, with the score the path's eventual
// pi * weight. Deterministic for any thread count.
template <class Intersector>
ImportancePilot TraceImportancePilotCpu(const Intersector& scene, const SurfaceTable& surfaces,
                                        const std::vector<TraceSensor>& sensors,
                                        uint64_t paths_per_sensor, uint64_t seed, PathSettings path,
                                        int threads, float cell_m) {
  const auto start = std::chrono::steady_clock::now();
  path.importance = nullptr;
  const float inverse_cell_m = 1.0f / cell_m;
  const uint64_t chunk_paths = OneStageChunkPaths(paths_per_sensor);
  const uint64_t chunks_per_sensor = (paths_per_sensor + chunk_paths - 1) / chunk_paths;
  struct Slot {
    absl::flat_hash_map<uint64_t, ImportanceCell> cells;
    double score = 0;
    uint64_t scoring = 0;
    uint64_t rays = 0;
  };
  std::vector<Slot> slots(chunks_per_sensor * sensors.size());
  ParallelFor(slots.size(), ResolveThreadCount(threads), [&](uint64_t c) {
    const uint32_t s = static_cast<uint32_t>(c / chunks_per_sensor);
    const uint64_t first = (c % chunks_per_sensor) * chunk_paths;
    const uint64_t last = std::min(paths_per_sensor, first + chunk_paths);
    Slot& slot = slots[c];
    one_stage_internal::PilotMode mode{sensors[s].position, sensors[s].normal, inverse_cell_m};
    for (uint64_t p = first; p < last; ++p) {
      slot.rays +=
          TracePath(scene, surfaces, path, PathRandom(seed, kPilotStreamBase + s, p), mode).rays;
      slot.score += mode.score;
      if (mode.score > 0) ++slot.scoring;
      for (int r = 0; r < mode.records; ++r) {
        ImportanceCell& cell = slot.cells[mode.keys[r]];
        cell.score_sum += mode.score / mode.weights[r];
        cell.visits += 1;
      }
    }
  });

  // Fold in order of chunks (each key once per chunk, so sums do not depend on the hash
  // maps' iteration order)
  ImportancePilot pilot;
  std::map<uint64_t, ImportanceCell> cells;
  pilot.mean_score.assign(sensors.size(), 0.0);
  for (uint64_t c = 0; c < slots.size(); ++c) {
    for (const auto& [key, cell] : slots[c].cells) {
      ImportanceCell& total = cells[key];
      total.score_sum += cell.score_sum;
      total.visits += cell.visits;
    }
    pilot.mean_score[c / chunks_per_sensor] += slots[c].score;
    pilot.rays += slots[c].rays;
    pilot.scoring_paths += slots[c].scoring;
  }
  for (double& score : pilot.mean_score) score /= static_cast<double>(paths_per_sensor);
  pilot.paths = paths_per_sensor * sensors.size();
  pilot.table = ImportanceTable::Build(cells, cell_m);
  pilot.wall_seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return pilot;
}

}  // namespace fenestra
