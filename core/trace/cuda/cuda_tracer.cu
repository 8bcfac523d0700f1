// The GPU tracer (see cuda_tracer.h). Each kernel gives every block one row of the result
// (a sensor, a window cell, or a sensor's batch) and accumulates that row in shared memory
// in double precision, then adds it to global memory once per block. A launch holds as
// many blocks as the device runs at once; the blocks of a row share its paths.
#include <cooperative_groups.h>
#include <cuda_runtime.h>

#include <algorithm>
#include <array>
#include <cstring>
#include <vector>

#include "absl/status/status.h"
#include "absl/strings/str_cat.h"
#include "core/common/batch_mean.h"
#include "core/common/status_macros.h"
#include "core/trace/bvh_intersector.h"
#include "core/trace/cuda/cuda_tracer.h"
#include "core/trace/cuda/device_buffer.cuh"
#include "core/trace/indoor_replay_modes.h"
#include "core/trace/path.h"
#include "core/trace/share_blocks.h"
#include "core/trace/two_stage_modes.h"

namespace fenestra {
namespace {

constexpr int kThreads = 256;
// Blocks per multiprocessor the register budget must allow (occupancy against spills).
#ifndef FENESTRA_CUDA_MIN_BLOCKS
#define FENESTRA_CUDA_MIN_BLOCKS 4
#endif
constexpr int kCounters = 7;  // rays, then paths by PathEnd
// Shared memory a block may use without opting in to more.
constexpr size_t kDefaultShared = 48 * 1024;

// Adds into a block's shared-memory row. Squares are taken per Add: right while a path
// scores once (no splitting on the GPU).
struct SharedSink {
  double* sum;
  double* sum_squares;  // may be null
  FENESTRA_CPU_GPU void Add(int bin, double value) {
#if defined(__CUDA_ARCH__)
    atomicAdd(&sum[bin], value);
    if (sum_squares != nullptr) atomicAdd(&sum_squares[bin], value * value);
#endif
  }
  FENESTRA_CPU_GPU void EndPath() {}
};

// OutdoorMode's sink on the device: adds into the shared row of the current path's batch, and
// counts the first segments that reached the sky per thread, added to that row when the
// thread moves to another batch or ends (one shared atomic per thread and batch instead of
// one per path, all of a block's on the same entry).
struct OutdoorSink {
  double* row;
  unsigned int first_escapes = 0;
  __device__ void Add(int bin, double value) { atomicAdd(&row[bin], value); }
  __device__ void AddFirstEscape() { ++first_escapes; }
  __device__ void Flush() {
    if (first_escapes != 0) atomicAdd(&row[kFirstEscapeEntry], static_cast<double>(first_escapes));
    first_escapes = 0;
  }
  __device__ void SetRow(double* next) {
    if (next == row) return;
    Flush();
    row = next;
  }
};

// Zeroes the block's shared row and counters.
__device__ void BeginRow(double* row, int size, unsigned long long* counters) {
  for (int i = threadIdx.x; i < size; i += blockDim.x) row[i] = 0.0;
  if (threadIdx.x < kCounters) counters[threadIdx.x] = 0;
  __syncthreads();
}

// Adds the block's row and counters to global memory.
__device__ void EndRow(const double* row, int size, double* global_row,
                       const unsigned long long* counters, unsigned long long* global_counters) {
  __syncthreads();
  for (int i = threadIdx.x; i < size; i += blockDim.x) {
    if (row[i] != 0.0) atomicAdd(&global_row[i], row[i]);
  }
  if (threadIdx.x < kCounters) atomicAdd(&global_counters[threadIdx.x], counters[threadIdx.x]);
}

// Per-thread tallies of paths, added to the block's counters once.
struct ThreadCounts {
  unsigned long long values[kCounters] = {};
  __device__ void Add(const PathStats& stats) {
    values[0] += stats.rays;
    ++values[1 + static_cast<int>(stats.end)];
  }
  __device__ void Flush(unsigned long long* counters) const {
    for (int i = 0; i < kCounters; ++i) {
      if (values[i] != 0) atomicAdd(&counters[i], values[i]);
    }
  }
};

// The first of batch b's paths when `paths` are split into `batches` contiguous batches
// (BatchStart on the host).
__device__ uint64_t BatchFirst(uint64_t paths, int batches, uint64_t b) {
  return b * paths / static_cast<uint64_t>(batches);
}

// The next path of a row for each calling lane: the lanes that ask together take
// consecutive indices with one atomic operation.
__device__ uint64_t NextPath(unsigned long long* next_path) {
  const cooperative_groups::coalesced_group lanes = cooperative_groups::coalesced_threads();
  unsigned long long base = 0;
  if (lanes.thread_rank() == 0) base = atomicAdd(next_path, lanes.size());
  return lanes.shfl(base, 0) + lanes.thread_rank();
}

// Traces the row's items i = 0, 1, ... below `count` as its lanes take them, one ray per
// turn of the loop: begin(i, &random, &path, &stats) sets up item i (a path from its start,
// or one resumed); a lane whose path ends takes the row's next item at once (path
// regeneration), so lanes and blocks stay busy until the row runs out of paths rather than
// wait for the longest path of their warp or the longest list of a thread; end(stats) is
// told of each item's path as it ends. No splitting (no weight windows on the GPU): small
// per-lane state.
template <class Scene, class Mode, class Begin, class End>
__device__ void TraceItems(const Scene& scene, const SurfaceTable& surfaces,
                           const PathSettings& settings, Mode& mode, uint64_t count,
                           unsigned long long* next_item, ThreadCounts& counts, Begin begin,
                           End end_item) {
  PathRandom random(0, 0, 0);
  PathState path;
  PathStats stats;
  uint32_t interactions = 0;
  for (bool live = false;;) {
    if (!live) {
      const uint64_t i = NextPath(next_item);
      if (i >= count) return;
      begin(i, &random, &path, &stats);
      interactions = path.vertex;
      live = true;
    }
    int pending_count = 0;
    PathEnd end;
    if (!path_internal::StepBranch(scene, surfaces, settings, random, mode, path, &interactions,
                                   nullptr, 0, &pending_count, &stats, &end) &&
        !path_internal::GoesOn(mode)) {
      path_internal::EndBranch(end, &stats);
      mode.Finish(stats);
      counts.Add(stats);
      end_item(stats);
      live = false;
    }
  }
}

// TraceItems without telling of the items' ends.
template <class Scene, class Mode, class Begin>
__device__ void TraceItems(const Scene& scene, const SurfaceTable& surfaces,
                           const PathSettings& settings, Mode& mode, uint64_t count,
                           unsigned long long* next_item, ThreadCounts& counts, Begin begin) {
  TraceItems(scene, surfaces, settings, mode, count, next_item, counts, begin,
             [](const PathStats&) {});
}

// Traces paths first + i of random stream `stream`, i below last - first (TraceItems); `first`
// is their batch's first path.
template <class Scene, class Mode>
__device__ void TracePaths(const Scene& scene, const SurfaceTable& surfaces,
                           const PathSettings& settings, Mode& mode, uint64_t seed, uint32_t stream,
                           uint64_t first, uint64_t last, unsigned long long* next_path,
                           ThreadCounts& counts) {
  TraceItems(scene, surfaces, settings, mode, last - first, next_path, counts,
             [&](uint64_t i, PathRandom* random, PathState* path, PathStats* stats) {
               *random = PathRandom(seed, stream, first + i, settings.sequence, first);
               *path = path_internal::StartPath(scene, *random, mode, stats);
             });
}

// Rows are (sensor, batch): row s * batches + b holds the paths [b N / batches,
// (b + 1) N / batches) of sensor s.
__global__ void __launch_bounds__(kThreads, FENESTRA_CUDA_MIN_BLOCKS)
    OneStageKernel(BvhIntersector scene, SurfaceTable surfaces, PathSettings settings,
                   const TraceSensor* sensors, uint64_t paths_per_sensor, int batches,
                   uint64_t seed, double* sum, double* sum_squares, unsigned long long* counters,
                   unsigned long long* next_path) {
  __shared__ double row[2 * kOneStageBins];
  __shared__ unsigned long long block_counters[kCounters];
  BeginRow(row, 2 * kOneStageBins, block_counters);
  const uint32_t s = blockIdx.y / batches;
  const uint32_t b = blockIdx.y % batches;
  const uint64_t first = BatchFirst(paths_per_sensor, batches, b);
  const uint64_t last = BatchFirst(paths_per_sensor, batches, b + 1);
  SharedSink sink{row, row + kOneStageBins};
  OneStageMode<SharedSink> mode{sensors[s].position, sensors[s].normal, &sink};
  ThreadCounts counts;
  TracePaths(scene, surfaces, settings, mode, seed, s, first, last, next_path + blockIdx.y, counts);
  counts.Flush(block_counters);
  const size_t offset = static_cast<size_t>(blockIdx.y) * kOneStageBins;
  EndRow(row, kOneStageBins, sum + offset, block_counters, counters);
  for (int i = threadIdx.x; i < kOneStageBins; i += blockDim.x) {
    if (row[kOneStageBins + i] != 0.0) {
      atomicAdd(&sum_squares[offset + i], row[kOneStageBins + i]);
    }
  }
}

// The batch of path i when `paths` are split into `batches` contiguous batches (BatchFirst).
__device__ int BatchOf(uint64_t paths, int batches, uint64_t i) {
  uint64_t b = i * static_cast<uint64_t>(batches) / paths;
  while (b > 0 && BatchFirst(paths, batches, b) > i) --b;
  while (b + 1 < static_cast<uint64_t>(batches) && BatchFirst(paths, batches, b + 1) <= i) ++b;
  return static_cast<int>(b);
}

// The blocks along y take window cells first_cell + blockIdx.y, each with all its paths, so
// that a block's lanes share thousands of short paths rather than one batch's hundreds (a
// block lasts as long as its longest path). The block holds a row per batch; row
// b * cells + cell of the sums holds the cell's paths [b N / batches, (b + 1) N / batches).
__global__ void __launch_bounds__(kThreads, FENESTRA_CUDA_MIN_BLOCKS)
    OutdoorKernel(BvhIntersector scene, SurfaceTable surfaces, PathSettings settings,
                  TraceWindow window, TraceWindows windows, unsigned int window_index,
                  HemisphereBasis basis, uint64_t paths_per_cell, int batches, uint64_t seed,
                  unsigned int first_cell, double* sum, unsigned long long* counters,
                  unsigned long long* next_path) {
  extern __shared__ double rows[];  // per batch, kOutdoorRowSize
  __shared__ unsigned long long block_counters[kCounters];
  __shared__ HemisphereBasis shared_basis;
  if (threadIdx.x == 0) shared_basis = basis;
  const int size = batches * kOutdoorRowSize;
  BeginRow(rows, size, block_counters);
  const unsigned int cell = first_cell + blockIdx.y;
  OutdoorSink sink{rows};
  OutdoorMode<OutdoorSink> mode{window, windows, &shared_basis, static_cast<int>(cell), &sink};
  const uint32_t streams = kOutdoorStreamBase + window_index * kOutdoorWindowStreams;
  ThreadCounts counts;
  TraceItems(scene, surfaces, settings, mode, paths_per_cell, next_path + cell, counts,
             [&](uint64_t i, PathRandom* random, PathState* path, PathStats* stats) {
               const int b = BatchOf(paths_per_cell, batches, i);
               sink.SetRow(rows + b * kOutdoorRowSize);
               const uint64_t batch_first = settings.sequence == Sequence::kSobol
                                                ? BatchFirst(paths_per_cell, batches, b)
                                                : 0;
               *random = PathRandom(seed, streams + cell, i, settings.sequence, batch_first);
               *path = path_internal::StartPath(scene, *random, mode, stats);
             });
  sink.Flush();
  counts.Flush(block_counters);
  __syncthreads();
  const int cells = WindowCellCount(window, basis);
  for (int i = threadIdx.x; i < size; i += blockDim.x) {
    const size_t b = static_cast<size_t>(i / kOutdoorRowSize);
    if (rows[i] != 0.0) {
      atomicAdd(&sum[(b * cells + cell) * kOutdoorRowSize + i % kOutdoorRowSize], rows[i]);
    }
  }
  if (threadIdx.x < kCounters) atomicAdd(&counters[threadIdx.x], block_counters[threadIdx.x]);
}

// O from the outdoor sums (CudaTracer::Outdoor), one thread per entry (row k, bin j) of the
// row-major OutdoorRowCount(cells) x kTregenzaBinCount matrices of `entries` values:
// each batch's at formed + b * entries, then their mean and its standard error, then per
// window cell its first segments that reached the sky, over all batches.
__global__ void FormOutdoorKernel(const double* sum, int cells, uint64_t paths_per_cell,
                                  int batches, double* formed) {
  const int rows = OutdoorRowCount(cells);
  const size_t entries = static_cast<size_t>(rows) * kTregenzaBinCount;
  const size_t e = blockIdx.x * static_cast<size_t>(blockDim.x) + threadIdx.x;
  if (e >= entries) return;
  const int k = static_cast<int>(e / kTregenzaBinCount);
  const int j = static_cast<int>(e % kTregenzaBinCount);
  // A window cell's row of batch b; below the cells, the identity for each block of direct
  // columns
  const auto value = [&](int b) {
    if (k >= cells) return (k - cells) % kTregenzaBinCount == j ? 1.0 : 0.0;
    const double paths = static_cast<double>(BatchFirst(paths_per_cell, batches, b + 1) -
                                             BatchFirst(paths_per_cell, batches, b));
    return OutdoorCoefficient(sum + (static_cast<size_t>(b) * cells + k) * kOutdoorRowSize, paths,
                              j);
  };
  for (int b = 0; b < batches; ++b) formed[b * entries + e] = value(b);
  BatchMeanAndError(batches, value, &formed[batches * entries + e],
                    &formed[(batches + 1) * entries + e]);
  if (j == 0 && k < cells) {
    double escapes = 0;
    for (int b = 0; b < batches; ++b) {
      escapes += sum[(static_cast<size_t>(b) * cells + k) * kOutdoorRowSize + kFirstEscapeEntry];
    }
    formed[(batches + 2) * entries + k] = escapes;
  }
}

__global__ void __launch_bounds__(kThreads, FENESTRA_CUDA_MIN_BLOCKS)
    IndoorKernel(BvhIntersector scene, SurfaceTable surfaces, PathSettings settings,
                 OutdoorView<BvhIntersector> outdoor, const TraceSensor* sensors, int sensor_count,
                 TraceWindows windows, HemisphereBasis basis, uint64_t paths_per_sensor,
                 int batches, uint64_t seed, double* sum, unsigned long long* counters,
                 unsigned long long* next_path) {
  extern __shared__ double row[];  // columns of I
  __shared__ unsigned long long block_counters[kCounters];
  __shared__ HemisphereBasis shared_basis;
  if (threadIdx.x == 0) shared_basis = basis;
  const int columns = IndoorColumnCount(windows);
  BeginRow(row, columns, block_counters);
  const int s = static_cast<int>(blockIdx.y) / batches;
  const int b = static_cast<int>(blockIdx.y) % batches;
  const uint64_t first = BatchFirst(paths_per_sensor, batches, b);
  const uint64_t last = BatchFirst(paths_per_sensor, batches, b + 1);
  SharedSink sink{row, nullptr};
  IndoorMode<SharedSink, OutdoorView<BvhIntersector>> mode{
      sensors[s].position,  sensors[s].normal, windows, &shared_basis,
      settings.max_bounces, &outdoor,          &sink};
  ThreadCounts counts;
  TracePaths(scene, surfaces, settings, mode, seed, s, first, last, next_path + blockIdx.y, counts);
  counts.Flush(block_counters);
  EndRow(row, columns, sum + (static_cast<size_t>(b) * sensor_count + s) * columns, block_counters,
         counters);
}

// The records of the indoor replay on the device: per row (sensor, batch; the indoor
// kernel's rows) a region of `crossing_capacity` connections that cross the envelope,
// `connection_capacity` others and `resume_capacity` resumes, and how many of each the row
// made (more than the capacity: they did not fit).
struct DeviceRecords {
  ReplayCrossing* crossings;
  ReplayConnection* connections;
  ReplayResume* resumes;
  unsigned long long* crossing_count;    // per row
  unsigned long long* connection_count;  // per row
  unsigned long long* resume_count;      // per row
  uint64_t crossing_capacity, connection_capacity, resume_capacity;
  // The order in which a replay of all parts takes a batch's resumed paths, longest first:
  // per (sensor, batch), entry i is the slot part * resume_capacity + k of its i-th path
  // (entries from the batch's first part's slot on). Null: as recorded, part after part.
  const uint32_t* order;
  // Where a replay of all parts writes the rays of design 0's resumed paths, per slot (at
  // most 255), to make `order` from; null: not written.
  uint8_t* lengths;
};

__device__ uint64_t Smaller(uint64_t a, uint64_t b) { return a < b ? a : b; }

// The slot of item i of the resumed paths of the record rows from `first_row` on: in `order`
// (of a replay of all parts, from the batch's first slot), else one part after the other.
__device__ size_t ResumeSlot(const DeviceRecords& records, const uint32_t* order,
                             unsigned int first_row, uint64_t i) {
  const size_t first_slot = static_cast<size_t>(first_row) * records.resume_capacity;
  if (order != nullptr) return first_slot + order[first_slot + i];
  unsigned int r = first_row;
  for (uint64_t n; i >= (n = Smaller(records.resume_count[r], records.resume_capacity)); ++r) {
    i -= n;
  }
  return static_cast<size_t>(r) * records.resume_capacity + i;
}

// Takes the records of a path of row `row` (core/trace/indoor_replay_modes.h): fixed light
// into the block's shared row, connections and resumes into the row's regions.
struct DeviceRecorder {
  double* fixed;
  DeviceRecords records;
  unsigned int row;
  const LocalEnvelopes* envelopes;
  FENESTRA_CPU_GPU void AddFixed(int column, double value) {
#if defined(__CUDA_ARCH__)
    atomicAdd(&fixed[column], value);
#endif
  }
  FENESTRA_CPU_GPU void AddConnection(const ReplayConnection& c) {
#if defined(__CUDA_ARCH__)
    ReplayCrossing crossing;
    const ConnectionKind kind = KindOf(*envelopes, c, &crossing);
    if (kind == ConnectionKind::kFixed) {
      atomicAdd(&fixed[c.column], c.value);
      return;
    }
    if (kind == ConnectionKind::kCrossing) {
      const uint64_t i = atomicAdd(&records.crossing_count[row], 1ull);
      if (i < records.crossing_capacity) {
        records.crossings[row * records.crossing_capacity + i] = crossing;
      }
      return;
    }
    const uint64_t i = atomicAdd(&records.connection_count[row], 1ull);
    if (i < records.connection_capacity) {
      records.connections[row * records.connection_capacity + i] = c;
    }
#endif
  }
  FENESTRA_CPU_GPU void BeginPath() {}
  // RecordKernel does not follow a path beyond an envelope: it is traced on from its touch
  // at every design (following paths on did not pay on the GPU: bench/README.md)
  FENESTRA_CPU_GPU void AddTouch(const ReplayTouch& touch) {
#if defined(__CUDA_ARCH__)
    const uint64_t i = atomicAdd(&records.resume_count[row], 1ull);
    if (i < records.resume_capacity) {
      records.resumes[row * records.resume_capacity + i] = ReplayResume{touch.state, touch.path};
    }
#endif
  }
};

// The indoor kernel's paths through the room without the blind, recorded for the replay
// (CudaTracer::RecordIndoor); the fixed light goes to `sum` in the indoor kernel's layout.
__global__ void __launch_bounds__(kThreads, FENESTRA_CUDA_MIN_BLOCKS)
    RecordKernel(BvhIntersector room, LocalEnvelopes envelopes, SurfaceTable surfaces,
                 PathSettings settings, OutdoorView<BvhIntersector> outdoor,
                 const TraceSensor* sensors, int sensor_count, TraceWindows windows,
                 HemisphereBasis basis, uint64_t paths_per_sensor, int batches, uint64_t seed,
                 DeviceRecords records, double* sum, unsigned long long* counters,
                 unsigned long long* next_path) {
  extern __shared__ double row[];  // columns of I
  __shared__ unsigned long long block_counters[kCounters];
  __shared__ HemisphereBasis shared_basis;
  if (threadIdx.x == 0) shared_basis = basis;
  const int columns = IndoorColumnCount(windows);
  BeginRow(row, columns, block_counters);
  const int s = static_cast<int>(blockIdx.y) / batches;
  const int b = static_cast<int>(blockIdx.y) % batches;
  RecordingIntersector<BvhIntersector> scene{room, envelopes};
  DeviceRecorder recorder{row, records, blockIdx.y, &scene.envelopes};
  RecordingSink<BvhIntersector, DeviceRecorder> sink{&scene, &recorder};
  RecordingMode<BvhIntersector, DeviceRecorder, OutdoorView<BvhIntersector>> mode{
      {sensors[s].position, sensors[s].normal, windows, &shared_basis, settings.max_bounces,
       &outdoor, &sink},
      &scene,
      &recorder};
  mode.follow = false;  // the records end at a path's first touch of an envelope
  ThreadCounts counts;
  TracePaths(scene, surfaces, settings, mode, seed, s, BatchFirst(paths_per_sensor, batches, b),
             BatchFirst(paths_per_sensor, batches, b + 1), next_path + blockIdx.y, counts);
  counts.Flush(block_counters);
  EndRow(row, columns, sum + (static_cast<size_t>(b) * sensor_count + s) * columns, block_counters,
         counters);
}

// The parts of the batches a replay traces (CudaTracer::ReplayIndoor): the records hold
// each batch's paths in `parts` parts; a replay traces parts [first, last).
struct ReplayParts {
  int batches, parts, first, last;
  uint64_t paths_per_sensor;  // of every batch together
};

// A design of a replay on the device: the room with its blinds (BVH, and per triangle its
// material), and their slats alone, shifted from the recorded envelopes' centres.
struct DeviceDesign {
  const BvhNode* nodes;
  const BvhTriangle* triangles;
  const uint32_t* triangle_material;
  ReplayBlinds blinds;
};

// Adds the window connections of record rows [first_row, first_row + count) that `blinds`
// leave clear to `row`, this block's share of them (block of `blocks`); returns how many paths
// of those rows resume at an envelope.
__device__ uint64_t TestConnections(const ReplayBlinds& blinds, const LocalEnvelopes& envelopes,
                                    const DeviceRecords& records, unsigned int first_row, int count,
                                    unsigned int block, unsigned int blocks, double* row,
                                    ThreadCounts& counts) {
  uint64_t resume_count = 0;
  const uint64_t stride = static_cast<uint64_t>(blocks) * blockDim.x;
  for (int p = 0; p < count; ++p) {
    const unsigned int r = first_row + p;
    const uint64_t crossing_count = Smaller(records.crossing_count[r], records.crossing_capacity);
    const ReplayCrossing* crossings = records.crossings + r * records.crossing_capacity;
    for (uint64_t i = block * static_cast<uint64_t>(blockDim.x) + threadIdx.x; i < crossing_count;
         i += stride) {
      const ReplayCrossing k = crossings[i];
      ++counts.values[0];
      if (Clear(blinds, envelopes, k)) atomicAdd(&row[k.column], k.value);
    }
    const uint64_t connection_count =
        Smaller(records.connection_count[r], records.connection_capacity);
    const ReplayConnection* connections = records.connections + r * records.connection_capacity;
    for (uint64_t i = block * static_cast<uint64_t>(blockDim.x) + threadIdx.x; i < connection_count;
         i += stride) {
      const ReplayConnection c = connections[i];
      ++counts.values[0];
      if (!blinds.Occluded(c.origin, c.direction, c.distance)) {
        atomicAdd(&row[c.column], c.value);
      }
    }
    resume_count += Smaller(records.resume_count[r], records.resume_capacity);
  }
  return resume_count;
}

// The designs one replay launch traces, passed by value.
struct ReplayDesigns {
  DeviceDesign design[CudaTracer::kMaxReplayDesigns];
  int count;
};

// Designs' indoor sums from the records (CudaTracer::ReplayIndoor, ReplayIndoorDesigns), one
// row per (design, sensor, batch) over the parts traced: their fixed light (first block of
// the row), their connections the design's blinds leave clear, and their resumed paths traced
// on through the room with those blinds. A row has as many blocks as its share of the work
// (row_blocks: ShareBlocks of Impl::ReplayRowWork), so that the rows end together. Design k's
// sums start at sum + k * design_sums.
__global__ void __launch_bounds__(kThreads, FENESTRA_CUDA_MIN_BLOCKS)
    ReplayKernel(const __grid_constant__ ReplayDesigns designs, const TraceMaterial* materials,
                 PathSettings settings, OutdoorView<BvhIntersector> outdoor,
                 const TraceSensor* sensors, int sensor_count, TraceWindows windows,
                 HemisphereBasis basis, ReplayParts parts, uint64_t seed,
                 const __grid_constant__ LocalEnvelopes envelopes, DeviceRecords records,
                 const unsigned int* row_blocks, const double* fixed, double* sum,
                 size_t design_sums, unsigned long long* counters, unsigned long long* next_item) {
  extern __shared__ double row[];  // columns of I
  __shared__ unsigned long long block_counters[kCounters];
  __shared__ HemisphereBasis shared_basis;
  if (threadIdx.x == 0) shared_basis = basis;
  const int columns = IndoorColumnCount(windows);
  // This block's row: blocks [row_blocks[y], row_blocks[y + 1]) work on row y
  const unsigned int design_rows = static_cast<unsigned int>(sensor_count * parts.batches);
  const unsigned int rows = design_rows * static_cast<unsigned int>(designs.count);
  unsigned int y = 0;
  for (unsigned int step = 1u << 30; step > 0; step >>= 1) {
    if (y + step < rows && row_blocks[y + step] <= blockIdx.x) y += step;
  }
  const DeviceDesign& design = designs.design[y / design_rows];
  // The design's slats and the envelopes, read by every lane at its own blind
  __shared__ ReplayBlinds blinds;
  __shared__ LocalEnvelopes shared_envelopes;
  if (threadIdx.x == 0) {
    blinds = design.blinds;
    shared_envelopes = envelopes;
  }
  BeginRow(row, columns, block_counters);
  const unsigned int block = blockIdx.x - row_blocks[y];
  const unsigned int blocks = row_blocks[y + 1] - row_blocks[y];
  const int s = static_cast<int>(y % design_rows) / parts.batches;
  const int b = static_cast<int>(y % design_rows) % parts.batches;
  const size_t offset =
      (y / design_rows) * design_sums + (static_cast<size_t>(b) * sensor_count + s) * columns;
  // The record rows of the parts, as RecordIndoor made them: (sensor, batch x parts + part)
  const unsigned int first_row =
      static_cast<unsigned int>((s * parts.batches + b) * parts.parts + parts.first);
  const int count = parts.last - parts.first;
  if (block == 0) {
    for (int i = threadIdx.x; i < columns; i += blockDim.x) {
      double light = 0;
      for (int p = 0; p < count; ++p) {
        const int sub_batch = b * parts.parts + parts.first + p;
        light += fixed[(static_cast<size_t>(sub_batch) * sensor_count + s) * columns + i];
      }
      row[i] = light;
    }
  }
  __syncthreads();
  ThreadCounts counts;
  const uint64_t resume_count = TestConnections(blinds, shared_envelopes, records, first_row, count,
                                                block, blocks, row, counts);
  const BvhIntersector scene{design.nodes, design.triangles};
  const SurfaceTable surfaces{materials, design.triangle_material};
  const bool all_parts = parts.first == 0 && parts.last == parts.parts;
  const uint32_t* order = all_parts ? records.order : nullptr;
  uint8_t* lengths = all_parts && y < design_rows ? records.lengths : nullptr;
  SharedSink sink{row, nullptr};
  IndoorMode<SharedSink, OutdoorView<BvhIntersector>> mode{
      sensors[s].position,  sensors[s].normal, windows, &shared_basis,
      settings.max_bounces, &outdoor,          &sink};
  size_t slot = 0;  // the lane's resumed path
  // The row's batch's first path, for the Sobol draws (a division: once per row)
  const uint64_t batch_first = settings.sequence == Sequence::kSobol
                                   ? BatchFirst(parts.paths_per_sensor, parts.batches, b)
                                   : 0;
  TraceItems(
      scene, surfaces, settings, mode, resume_count, next_item + y, counts,
      [&](uint64_t i, PathRandom* random, PathState* path, PathStats* stats) {
        slot = ResumeSlot(records, order, first_row, i);
        const ReplayResume resume = records.resumes[slot];
        *random =
            PathRandom(seed, static_cast<uint32_t>(s), resume.path, settings.sequence, batch_first);
        *path = resume.state;
        *stats = ResumedStats(resume.state);
      },
      [&](const PathStats& stats) {
        if (lengths != nullptr) lengths[slot] = static_cast<uint8_t>(Smaller(stats.rays, 255));
      });
  counts.Flush(block_counters);
  EndRow(row, columns, sum + offset, block_counters, counters);
}

// One closest-hit query per thread (CudaTracer::IntersectRays).
__global__ void IntersectKernel(BvhIntersector scene, const Vec3f* origins, const Vec3f* directions,
                                size_t count, bool same_ray_per_warp, float* distance) {
  const size_t i = blockIdx.x * static_cast<size_t>(blockDim.x) + threadIdx.x;
  const size_t ray = same_ray_per_warp ? i & ~static_cast<size_t>(31) : i;
  if (ray >= count || i >= count) return;
  SurfaceHit hit;
  const Vec3f origin = origins[ray];
  distance[i] =
      scene.Intersect(origin, directions[ray], &hit) ? Length(hit.position - origin) : INFINITY;
}

// Times kernel launches on this thread's stream with two events made once.
class KernelTimer {
 public:
  KernelTimer() = default;
  ~KernelTimer() {
    if (start_ != nullptr) cudaEventDestroy(start_);
    if (stop_ != nullptr) cudaEventDestroy(stop_);
  }
  KernelTimer(const KernelTimer&) = delete;
  KernelTimer& operator=(const KernelTimer&) = delete;

  // Runs `launch` (kernel launches), then `after` (copies queued behind them), and waits for
  // this thread's stream only: a device-wide wait would also wait for the kernels of other
  // lanes and jobs on the GPU. *seconds gets the launches' time on the device.
  template <class Launch, class After>
  cudaError_t Run(Launch launch, After after, double* seconds) {
    cudaError_t e = start_ != nullptr ? cudaSuccess : cudaEventCreate(&start_);
    if (e == cudaSuccess && stop_ == nullptr) e = cudaEventCreate(&stop_);
    if (e == cudaSuccess) e = cudaEventRecord(start_);
    if (e == cudaSuccess) {
      launch();
      e = cudaGetLastError();
    }
    if (e == cudaSuccess) e = cudaEventRecord(stop_);
    if (e == cudaSuccess) e = after();
    if (e == cudaSuccess) e = cudaStreamSynchronize(cudaStreamPerThread);
    float ms = 0;
    if (e == cudaSuccess) e = cudaEventElapsedTime(&ms, start_, stop_);
    *seconds = ms / 1000.0;
    return e;
  }
  template <class Launch>
  cudaError_t Run(Launch launch, double* seconds) {
    return Run(
        launch, [] { return cudaSuccess; }, seconds);
  }

 private:
  cudaEvent_t start_ = nullptr, stop_ = nullptr;
};

// Lets `kernel` keep a row of `columns` doubles in shared memory (beside its basis and
// counters), opting in to more than the default where needed. The error names
// what the columns hold and what to change where they do not fit.
template <class Kernel>
absl::Status AllowSharedRow(Kernel kernel, int columns,
                            const char* held = "columns of the indoor matrix",
                            const char* remedy = "use fewer window parts or the 288-cell basis") {
  const size_t shared = static_cast<size_t>(columns) * sizeof(double);
  if (shared <= kDefaultShared) return absl::OkStatus();
  int device = 0, limit = 0;
  FENESTRA_CUDA_RETURN_IF_ERROR(cudaGetDevice(&device));
  FENESTRA_CUDA_RETURN_IF_ERROR(
      cudaDeviceGetAttribute(&limit, cudaDevAttrMaxSharedMemoryPerBlockOptin, device));
  const size_t available =
      static_cast<size_t>(limit) - sizeof(HemisphereBasis) - kCounters * sizeof(unsigned long long);
  if (shared > available) {
    return absl::ResourceExhaustedError(absl::StrCat(
        "CUDA: ", columns, " ", held, " do not fit the kernel's shared memory (at most ",
        available / sizeof(double), " on this device): ", remedy));
  }
  FENESTRA_CUDA_RETURN_IF_ERROR(cudaFuncSetAttribute(
      kernel, cudaFuncAttributeMaxDynamicSharedMemorySize, static_cast<int>(shared)));
  return absl::OkStatus();
}

// A resumed path's share of the replay's work, in connection tests (ReplayRowWork): on the
// city office the replay kernel took 1.24 ms with blocks shared by connections alone, 1.14 ms
// with resumes weighing 2-4, 1.05 ms with 16, 1.00 ms with 32, 1.01-1.02 ms with 64-128 and
// 1.04 ms by resumes alone (bench/HISTORY.md).
constexpr double kResumeWork = 32;

// The room RecordIndoor first makes for the crossing connections of a row's paths, per path:
// a row that made more is traced again with room for all (the same paths make the same
// records). The city office's rows made 3.5 per path on average, 4.0 at most (room for 3
// traced every four-variable job's records twice); records that would not fit the replay's
// memory leave the designs traced in full.
constexpr double kCrossingsPerPath = 4.5;

// `windows` (LinkWindows) in `buffer`, and their view with the list on the device.
absl::StatusOr<TraceWindows> UploadWindows(DeviceBuffer<TraceWindow>& buffer,
                                           const std::vector<TraceWindow>& windows,
                                           const HemisphereBasis& basis) {
  if (windows.empty()) return absl::InvalidArgumentError("CUDA tracer: no window");
  FENESTRA_CUDA_RETURN_IF_ERROR(buffer.Upload(windows.data(), windows.size()));
  TraceWindows view = ViewOfWindows(windows, basis);
  view.list = buffer.get();
  return view;
}

}  // namespace

struct CudaTracer::Impl {
  int device = 0;
  int multiprocessors = 1;
  std::string name;
  DeviceBuffer<BvhNode> nodes, outdoor_nodes;
  DeviceBuffer<BvhTriangle> triangles, outdoor_triangles;
  DeviceBuffer<uint8_t> outdoor_met;  // per window cell (OutdoorView::met)
  // The windows of the last stage traced, and of the recorded replay (TraceWindows::list)
  DeviceBuffer<TraceWindow> windows, recorded_windows;
  DeviceBuffer<uint32_t> triangle_material;
  DeviceBuffer<TraceMaterial> materials;
  DeviceBuffer<TraceSensor> sensors;
  DeviceBuffer<Vec3f> ray_origins, ray_directions;
  DeviceBuffer<float> ray_distances;
  DeviceBuffer<double> sum, sum_squares;
  DeviceBuffer<double> formed;  // O formed from the outdoor sums
  DeviceBuffer<unsigned long long> counters;
  DeviceBuffer<unsigned long long> next_path;                  // per row: paths taken so far
  PinnedBuffer staging;                                        // large transfers
  Allocation<unsigned long long, PinnedMemory> host_counters;  // downloaded with the launch
  KernelTimer timer;
  bool has_scene = false, has_outdoor = false;
  // The indoor replay: the records, their fixed light, and what they were recorded for;
  // the blind of the design replayed
  DeviceBuffer<ReplayCrossing> crossings;
  DeviceBuffer<ReplayConnection> connections;
  DeviceBuffer<ReplayResume> resumes;
  DeviceBuffer<unsigned long long> record_counts;  // per row: see Recorded::counts
  DeviceBuffer<double> fixed;
  DeviceBuffer<TraceSensor> replay_sensors;
  // The resumed paths' order (DeviceRecords::order), made from their lengths in the first
  // replay of all parts after recording
  DeviceBuffer<uint32_t> resume_order;
  DeviceBuffer<uint8_t> resume_lengths;
  bool resume_order_made = false;
  DeviceBuffer<unsigned int> row_blocks;          // each row's first block, for row_blocks_key
  std::array<int, 3> row_blocks_key{-1, -1, -1};  // parts [first, last) of this many designs
  // The scenes of ReplayIndoorDesigns' designs, one after the other
  DeviceBuffer<BvhNode> design_nodes;
  DeviceBuffer<BvhTriangle> design_triangles;
  DeviceBuffer<uint32_t> design_triangle_material;
  DeviceBuffer<TraceMaterial> design_materials;
  std::vector<TraceMaterial> design_materials_held;  // what design_materials holds
  unsigned int row_blocks_total = 0;
  struct Recorded {
    bool valid = false;
    int sensor_count = 0, batches = 0, parts = 0;  // rows: sensors x batches x parts
    uint64_t paths_per_sensor = 0, seed = 0, crossing_capacity = 0, connection_capacity = 0,
             resume_capacity = 0;
    // Per row: the other connections, then the resumes, then the crossings
    std::vector<unsigned long long> counts;
    LocalEnvelopes envelopes;
    TraceWindows windows;  // in recorded_windows
    HemisphereBasis basis;
    Vec3f outdoor_offset;
    PathSettings path;
  } recorded;

  // The indoor stage's paths (CudaTracer::Indoor); the sums stay on the device without
  // host_sum.
  absl::Status TraceIndoor(const TraceSensor* host_sensors, int sensor_count,
                           const std::vector<TraceWindow>& host_windows, Vec3f outdoor_offset,
                           const HemisphereBasis& basis, uint64_t paths_per_sensor, int batches,
                           uint64_t seed, const PathSettings& path, double* host_sum,
                           CudaCounters* out);
  // Runs RecordKernel for `recorded`, its record capacities grown and the kernel run once
  // more when a row made more records than there was room for; each row's record counts
  // into `counts` (3 per row, as Recorded::counts).
  absl::Status TraceRecords(int columns, size_t max_bytes, std::vector<unsigned long long>& counts,
                            CudaCounters* counters);
  // The designs' indoor sums of parts [first, last) from the records (CudaTracer::ReplayIndoor,
  // ReplayIndoorDesigns), added to those of parts [0, first) already in `sum` (one design).
  absl::Status Replay(const ReplayDesigns& designs, const TraceMaterial* materials, int first,
                      int last, double* host_sum, CudaCounters* out);
  size_t DesignSums() const {
    return static_cast<size_t>(recorded.batches) * recorded.sensor_count *
           IndoorColumnCount(recorded.windows);
  }
  // Parts [0, replayed_parts) of the last replay are in `sum`; 0 once `sum` holds other sums.
  int replayed_parts = 0;
  DeviceRecords Records() {
    const size_t rows =
        static_cast<size_t>(recorded.sensor_count) * recorded.batches * recorded.parts;
    return {crossings.get(),
            connections.get(),
            resumes.get(),
            record_counts.get() + 2 * rows,
            record_counts.get(),
            record_counts.get() + rows,
            recorded.crossing_capacity,
            recorded.connection_capacity,
            recorded.resume_capacity};
  }

  // Per (sensor, batch), its resumed paths longest first (DeviceRecords::order) from the
  // lengths the last replay wrote: a counting sort by length, ties as recorded.
  absl::Status OrderResumes() {
    const Recorded& r = recorded;
    const size_t record_rows = r.counts.size() / 3;
    const size_t slots = record_rows * r.resume_capacity;
    std::vector<uint8_t> lengths(slots);
    FENESTRA_CUDA_RETURN_IF_ERROR(resume_lengths.Download(lengths.data(), slots));
    std::vector<uint32_t> order(slots, 0);
    for (size_t y = 0; y < record_rows / r.parts; ++y) {
      const size_t first_slot = y * r.parts * r.resume_capacity;
      // Paths per length, then where each length's paths begin (the longest first)
      std::array<uint32_t, 257> start{};
      const auto each_path = [&](const auto& visit) {
        for (int p = 0; p < r.parts; ++p) {
          const size_t count =
              std::min<uint64_t>(r.counts[record_rows + y * r.parts + p], r.resume_capacity);
          for (size_t k = 0; k < count; ++k) {
            const uint32_t slot = static_cast<uint32_t>(p * r.resume_capacity + k);
            visit(slot, 255 - lengths[first_slot + slot]);
          }
        }
      };
      each_path([&](uint32_t, int key) { ++start[key + 1]; });
      for (size_t k = 1; k < start.size(); ++k) start[k] += start[k - 1];
      each_path([&](uint32_t slot, int key) { order[first_slot + start[key]++] = slot; });
    }
    FENESTRA_CUDA_RETURN_IF_ERROR(resume_order.Upload(order.data(), slots));
    resume_order_made = true;
    return absl::OkStatus();
  }

  // The replay's work per row (design, sensor, batch) over parts [first, last) of the
  // records, for `designs` designs: a connection is one query, a resumed path kResumeWork of
  // them.
  std::vector<double> ReplayRowWork(int first, int last, int designs) const {
    const Recorded& r = recorded;
    const size_t record_rows = r.counts.size() / 3;
    const size_t design_rows = static_cast<size_t>(r.sensor_count) * r.batches;
    std::vector<double> work(design_rows, 0.0);
    for (size_t y = 0; y < design_rows; ++y) {
      for (int p = first; p < last; ++p) {
        const size_t i = y * r.parts + p;
        work[y] += static_cast<double>(
                       std::min<uint64_t>(r.counts[i], r.connection_capacity) +
                       std::min<uint64_t>(r.counts[2 * record_rows + i], r.crossing_capacity)) +
                   kResumeWork * static_cast<double>(std::min<uint64_t>(r.counts[record_rows + i],
                                                                        r.resume_capacity));
      }
    }
    // Every design's rows have the same records
    std::vector<double> all;
    all.reserve(design_rows * designs);
    for (int k = 0; k < designs; ++k) all.insert(all.end(), work.begin(), work.end());
    return all;
  }

  BvhIntersector Scene() const { return {nodes.get(), triangles.get()}; }
  OutdoorView<BvhIntersector> Outdoor(Vec3f offset) const {
    return {{outdoor_nodes.get(), outdoor_triangles.get()}, offset, outdoor_met.get()};
  }
  SurfaceTable Surfaces() const { return {materials.get(), triangle_material.get()}; }

  // Blocks along x for `rows` rows of `paths` paths: as many as the device holds at once
  // (each thread then loops over paths, starting the next as soon as one ends), or fewer
  // where there are not that many paths.
  template <class Kernel>
  unsigned int BlocksPerRow(Kernel kernel, size_t shared, uint64_t paths, unsigned int rows) const {
    int resident = 0;
    if (cudaOccupancyMaxActiveBlocksPerMultiprocessor(&resident, kernel, kThreads, shared) !=
        cudaSuccess) {
      resident = 1;
    }
    const uint64_t wanted = (paths + kThreads - 1) / kThreads;
    const uint64_t fill = std::max<uint64_t>(
        1, static_cast<uint64_t>(std::max(1, resident)) * multiprocessors / std::max(1u, rows));
    return static_cast<unsigned int>(std::max<uint64_t>(1, std::min(wanted, fill)));
  }

  // Zeroes the outputs (the sums unless adding to them), runs `launch`, times it, downloads
  // (the sums only where host_sum is given: else they stay in `sum`).
  template <class Launch>
  absl::Status Run(size_t rows, size_t sum_size, bool squares, Launch launch, double* host_sum,
                   double* host_sum_squares, CudaCounters* out, bool add_to_sums = false) {
    if (!has_scene) return absl::FailedPreconditionError("CUDA tracer: no scene uploaded");
    FENESTRA_CUDA_RETURN_IF_ERROR(cudaSetDevice(device));
    if (!add_to_sums) {
      replayed_parts = 0;
      FENESTRA_CUDA_RETURN_IF_ERROR(sum.Zero(sum_size));
    }
    if (squares) FENESTRA_CUDA_RETURN_IF_ERROR(sum_squares.Zero(sum_size));
    FENESTRA_CUDA_RETURN_IF_ERROR(counters.Zero(kCounters));
    FENESTRA_CUDA_RETURN_IF_ERROR(next_path.Zero(rows));
    double seconds = 0;
    FENESTRA_CUDA_RETURN_IF_ERROR(host_counters.Reserve(kCounters));
    FENESTRA_CUDA_RETURN_IF_ERROR(timer.Run(
        launch,
        [&] {
          return cudaMemcpyAsync(host_counters.get(), counters.get(),
                                 kCounters * sizeof(unsigned long long), cudaMemcpyDeviceToHost,
                                 cudaStreamPerThread);
        },
        &seconds));
    if (host_sum != nullptr) {
      FENESTRA_CUDA_RETURN_IF_ERROR(staging.Download(sum.get(), host_sum, sum_size));
    }
    if (squares) {
      FENESTRA_CUDA_RETURN_IF_ERROR(
          staging.Download(sum_squares.get(), host_sum_squares, sum_size));
    }
    out->rays = host_counters.get()[0];
    for (int i = 0; i < 6; ++i) out->ends[i] = host_counters.get()[1 + i];
    out->kernel_seconds = seconds;
    return absl::OkStatus();
  }
};

int CudaDeviceCount() {
  int count = 0;
  if (cudaGetDeviceCount(&count) != cudaSuccess) return 0;
  return count;
}

std::string CudaDeviceName(int device) {
  cudaDeviceProp properties;
  if (device >= CudaDeviceCount() || cudaGetDeviceProperties(&properties, device) != cudaSuccess) {
    return std::string();
  }
  return properties.name;
}

CudaTracer::CudaTracer(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
CudaTracer::~CudaTracer() = default;

absl::StatusOr<std::unique_ptr<CudaTracer>> CudaTracer::Create(int device) {
  FENESTRA_RETURN_IF_ERROR(CheckCudaDevice(device));
  auto impl = std::make_unique<Impl>();
  impl->device = device;
  cudaDeviceProp properties;
  cudaError_t e = cudaGetDeviceProperties(&properties, device);
  if (e == cudaSuccess) e = cudaSetDevice(device);
  FENESTRA_CUDA_RETURN_IF_ERROR(e);
  impl->multiprocessors = properties.multiProcessorCount;
  impl->name = properties.name;
  return std::unique_ptr<CudaTracer>(new CudaTracer(std::move(impl)));
}

std::string CudaTracer::device_name() const { return impl_->name; }

absl::Status CudaTracer::SetScene(const BvhLayout& bvh, const uint32_t* triangle_material,
                                  size_t triangle_count, const TraceMaterial* materials,
                                  size_t material_count) {
  Impl& d = *impl_;
  d.replayed_parts = 0;  // the sums were another scene's
  d.has_scene = false;
  FENESTRA_CUDA_RETURN_IF_ERROR(cudaSetDevice(d.device));
  FENESTRA_CUDA_RETURN_IF_ERROR(d.nodes.Upload(bvh.nodes.data(), bvh.nodes.size()));
  FENESTRA_CUDA_RETURN_IF_ERROR(d.triangles.Upload(bvh.triangles.data(), bvh.triangles.size()));
  FENESTRA_CUDA_RETURN_IF_ERROR(d.triangle_material.Upload(triangle_material, triangle_count));
  FENESTRA_CUDA_RETURN_IF_ERROR(d.materials.Upload(materials, material_count));
  d.has_scene = true;
  return absl::OkStatus();
}

absl::Status CudaTracer::IntersectRays(const Vec3f* origins, const Vec3f* directions, size_t count,
                                       bool same_ray_per_warp, float* distance,
                                       double* kernel_seconds) {
  Impl& d = *impl_;
  if (!d.has_scene) return absl::FailedPreconditionError("CUDA tracer: no scene uploaded");
  FENESTRA_CUDA_RETURN_IF_ERROR(cudaSetDevice(d.device));
  FENESTRA_CUDA_RETURN_IF_ERROR(d.ray_origins.Upload(origins, count));
  FENESTRA_CUDA_RETURN_IF_ERROR(d.ray_directions.Upload(directions, count));
  FENESTRA_CUDA_RETURN_IF_ERROR(d.ray_distances.Reserve(count));
  const unsigned int blocks = static_cast<unsigned int>((count + kThreads - 1) / kThreads);
  FENESTRA_CUDA_RETURN_IF_ERROR(d.timer.Run(
      [&] {
        IntersectKernel<<<std::max(1u, blocks), kThreads>>>(
            d.Scene(), d.ray_origins.get(), d.ray_directions.get(), count, same_ray_per_warp,
            d.ray_distances.get());
      },
      kernel_seconds));
  FENESTRA_CUDA_RETURN_IF_ERROR(d.ray_distances.Download(distance, count));
  return absl::OkStatus();
}

absl::Status CudaTracer::OneStage(const TraceSensor* sensors, int sensor_count,
                                  uint64_t paths_per_sensor, int batches, uint64_t seed,
                                  const PathSettings& path, double* sum, double* sum_squares,
                                  CudaCounters* counters) {
  Impl& d = *impl_;
  FENESTRA_CUDA_RETURN_IF_ERROR(d.sensors.Upload(sensors, sensor_count));
  const unsigned int rows = static_cast<unsigned int>(sensor_count * batches);
  const dim3 grid(d.BlocksPerRow(OneStageKernel, 0, paths_per_sensor / batches + 1, rows), rows);
  return d.Run(
      rows, static_cast<size_t>(rows) * kOneStageBins, true,
      [&] {
        OneStageKernel<<<grid, kThreads>>>(
            d.Scene(), d.Surfaces(), path, d.sensors.get(), paths_per_sensor, batches, seed,
            d.sum.get(), d.sum_squares.get(), d.counters.get(), d.next_path.get());
      },
      sum, sum_squares, counters);
}

absl::Status CudaTracer::Outdoor(const std::vector<TraceWindow>& windows, int w,
                                 const HemisphereBasis& basis, uint64_t paths_per_cell, int batches,
                                 uint64_t seed, const PathSettings& path, const OutdoorOutput& out,
                                 CudaCounters* counters) {
  Impl& d = *impl_;
  FENESTRA_ASSIGN_OR_RETURN(all, UploadWindows(d.windows, windows, basis));
  const TraceWindow& window = windows[w];
  const int cells = WindowCellCount(window, basis);
  const int row_size = batches * kOutdoorRowSize;
  FENESTRA_RETURN_IF_ERROR(AllowSharedRow(
      OutdoorKernel, row_size, "outdoor sums (the batches of a cell)", "use fewer batches"));
  const size_t shared = static_cast<size_t>(row_size) * sizeof(double);
  const unsigned int per_cell =
      d.BlocksPerRow(OutdoorKernel, shared, paths_per_cell, static_cast<unsigned int>(cells));
  constexpr unsigned int kMaxGridRows = 65535;
  FENESTRA_RETURN_IF_ERROR(d.Run(
      cells, static_cast<size_t>(cells) * batches * kOutdoorRowSize, false,
      [&] {
        for (unsigned int first = 0; first < static_cast<unsigned int>(cells);
             first += kMaxGridRows) {
          const dim3 grid(per_cell,
                          std::min(kMaxGridRows, static_cast<unsigned int>(cells) - first));
          OutdoorKernel<<<grid, kThreads, shared>>>(
              d.Scene(), d.Surfaces(), path, window, all, static_cast<unsigned int>(w), basis,
              paths_per_cell, batches, seed, first, d.sum.get(), d.counters.get(),
              d.next_path.get());
        }
      },
      nullptr, nullptr, counters));
  // O formed where the sums lie; each part downloaded straight to its place
  const size_t entries = static_cast<size_t>(OutdoorRowCount(cells)) * kTregenzaBinCount;
  FENESTRA_CUDA_RETURN_IF_ERROR(d.formed.Reserve((batches + 2) * entries + cells));
  FormOutdoorKernel<<<static_cast<unsigned int>((entries + kThreads - 1) / kThreads), kThreads>>>(
      d.sum.get(), cells, paths_per_cell, batches, d.formed.get());
  FENESTRA_CUDA_RETURN_IF_ERROR(cudaGetLastError());
  const auto download = [&](double* host, size_t offset, size_t count) {
    return cudaMemcpy(host, d.formed.get() + offset, count * sizeof(double),
                      cudaMemcpyDeviceToHost);
  };
  for (int b = 0; b < batches; ++b) {
    FENESTRA_CUDA_RETURN_IF_ERROR(download(out.batches[b], b * entries, entries));
  }
  FENESTRA_CUDA_RETURN_IF_ERROR(download(out.mean, batches * entries, entries));
  FENESTRA_CUDA_RETURN_IF_ERROR(download(out.standard_error, (batches + 1) * entries, entries));
  FENESTRA_CUDA_RETURN_IF_ERROR(download(out.first_escapes, (batches + 2) * entries, cells));
  if (out.batches_on_device != nullptr) *out.batches_on_device = HandOver(d.formed, d.device);
  return absl::OkStatus();
}

absl::Status CudaTracer::SetOutdoorScene(const BvhLayout& bvh, const std::vector<uint8_t>& met) {
  Impl& d = *impl_;
  d.replayed_parts = 0;
  d.has_outdoor = false;
  FENESTRA_CUDA_RETURN_IF_ERROR(cudaSetDevice(d.device));
  FENESTRA_CUDA_RETURN_IF_ERROR(d.outdoor_nodes.Upload(bvh.nodes.data(), bvh.nodes.size()));
  FENESTRA_CUDA_RETURN_IF_ERROR(
      d.outdoor_triangles.Upload(bvh.triangles.data(), bvh.triangles.size()));
  FENESTRA_CUDA_RETURN_IF_ERROR(d.outdoor_met.Upload(met.data(), met.size()));
  d.has_outdoor = true;
  return absl::OkStatus();
}

absl::Status CudaTracer::Impl::TraceIndoor(const TraceSensor* host_sensors, int sensor_count,
                                           const std::vector<TraceWindow>& host_windows,
                                           Vec3f outdoor_offset, const HemisphereBasis& basis,
                                           uint64_t paths_per_sensor, int batches, uint64_t seed,
                                           const PathSettings& path, double* host_sum,
                                           CudaCounters* out) {
  Impl& d = *this;
  if (!d.has_outdoor)
    return absl::FailedPreconditionError("CUDA tracer: no outdoor scene uploaded");
  FENESTRA_CUDA_RETURN_IF_ERROR(d.sensors.Upload(host_sensors, sensor_count));
  FENESTRA_ASSIGN_OR_RETURN(windows, UploadWindows(d.windows, host_windows, basis));
  const unsigned int rows = static_cast<unsigned int>(sensor_count * batches);
  const int cells = IndoorColumnCount(windows);
  const size_t shared = static_cast<size_t>(cells) * sizeof(double);
  FENESTRA_RETURN_IF_ERROR(AllowSharedRow(IndoorKernel, cells));
  const dim3 grid(d.BlocksPerRow(IndoorKernel, shared, paths_per_sensor / batches + 1, rows), rows);
  return d.Run(
      rows, static_cast<size_t>(batches) * sensor_count * cells, false,
      [&] {
        IndoorKernel<<<grid, kThreads, shared>>>(
            d.Scene(), d.Surfaces(), path, d.Outdoor(outdoor_offset), d.sensors.get(), sensor_count,
            windows, basis, paths_per_sensor, batches, seed, d.sum.get(), d.counters.get(),
            d.next_path.get());
      },
      host_sum, nullptr, out);
}

absl::Status CudaTracer::Indoor(const TraceSensor* sensors, int sensor_count,
                                const std::vector<TraceWindow>& windows, Vec3f outdoor_offset,
                                const HemisphereBasis& basis, uint64_t paths_per_sensor,
                                int batches, uint64_t seed, const PathSettings& path, double* sum,
                                CudaCounters* counters) {
  return impl_->TraceIndoor(sensors, sensor_count, windows, outdoor_offset, basis, paths_per_sensor,
                            batches, seed, path, sum, counters);
}

absl::Status CudaTracer::RecordIndoor(const LocalEnvelopes& envelopes, const TraceSensor* sensors,
                                      int sensor_count, const std::vector<TraceWindow>& windows,
                                      Vec3f outdoor_offset, const HemisphereBasis& basis,
                                      uint64_t paths_per_sensor, int batches, int parts,
                                      uint64_t seed, const PathSettings& path, size_t max_bytes,
                                      CudaReplayStats* stats) {
  Impl& d = *impl_;
  if (!d.has_outdoor)
    return absl::FailedPreconditionError("CUDA tracer: no outdoor scene uploaded");
  d.recorded.valid = false;
  d.resume_order_made = false;
  FENESTRA_CUDA_RETURN_IF_ERROR(cudaSetDevice(d.device));
  FENESTRA_CUDA_RETURN_IF_ERROR(d.replay_sensors.Upload(sensors, sensor_count));
  FENESTRA_ASSIGN_OR_RETURN(recorded_windows, UploadWindows(d.recorded_windows, windows, basis));
  const int columns = IndoorColumnCount(recorded_windows);
  FENESTRA_RETURN_IF_ERROR(AllowSharedRow(RecordKernel, columns));
  FENESTRA_RETURN_IF_ERROR(AllowSharedRow(ReplayKernel, columns));
  if (parts < 1)
    return absl::FailedPreconditionError("CUDA tracer: no parts of the batches to record");
  // Rows (sensor, part of a batch): the indoor kernel's rows of batches x parts batches
  const int row_batches = batches * parts;
  const unsigned int rows = static_cast<unsigned int>(sensor_count * row_batches);
  const uint64_t row_paths = paths_per_sensor / row_batches + 1;
  Impl::Recorded& r = d.recorded;
  d.row_blocks_key = {-1, -1, -1};
  // Room for kCrossingsPerPath connections per path, nearly all of which cross the envelope
  r = {false,
       sensor_count,
       batches,
       parts,
       paths_per_sensor,
       seed,
       static_cast<uint64_t>(kCrossingsPerPath * static_cast<double>(row_paths)) + 64,
       row_paths / 16 + 64,
       row_paths,
       {},
       envelopes,
       recorded_windows,
       basis,
       outdoor_offset,
       path};
  std::vector<unsigned long long> counts(3 * static_cast<size_t>(rows));
  CudaCounters counters;
  FENESTRA_RETURN_IF_ERROR(d.TraceRecords(columns, max_bytes, counts, &counters));
  FENESTRA_CUDA_RETURN_IF_ERROR(d.fixed.Reserve(static_cast<size_t>(rows) * columns));
  FENESTRA_CUDA_RETURN_IF_ERROR(cudaMemcpy(d.fixed.get(), d.sum.get(),
                                           static_cast<size_t>(rows) * columns * sizeof(double),
                                           cudaMemcpyDeviceToDevice));
  r.valid = true;
  r.counts = counts;
  stats->paths = paths_per_sensor * sensor_count;
  stats->connections = stats->resumes = 0;
  for (unsigned int i = 0; i < rows; ++i) {
    stats->connections += counts[i] + counts[2 * rows + i];
    stats->resumes += counts[rows + i];
  }
  stats->rays = counters.rays;
  stats->kernel_seconds = counters.kernel_seconds;
  return absl::OkStatus();
}

absl::Status CudaTracer::Impl::TraceRecords(int columns, size_t max_bytes,
                                            std::vector<unsigned long long>& counts,
                                            CudaCounters* counters) {
  Impl& d = *this;
  Recorded& r = d.recorded;
  const int row_batches = r.batches * r.parts;
  const unsigned int rows = static_cast<unsigned int>(r.sensor_count * row_batches);
  const size_t shared = static_cast<size_t>(columns) * sizeof(double);
  const uint64_t row_paths = r.paths_per_sensor / row_batches + 1;
  // Connections per row are not known in advance: a row that made more than there was room
  // for is traced again with room for all (the same paths make the same records)
  for (int attempt = 0;; ++attempt) {
    const size_t bytes =
        rows * (r.crossing_capacity * sizeof(ReplayCrossing) +
                r.connection_capacity * sizeof(ReplayConnection) +
                r.resume_capacity * sizeof(ReplayResume) + 2 * columns * sizeof(double));
    if (bytes > max_bytes) {
      return absl::ResourceExhaustedError(
          absl::StrCat("CUDA tracer: the indoor paths' records would take more device memory "
                       "than allowed (",
                       bytes >> 20, " MiB, at most ", max_bytes >> 20, " MiB)"));
    }
    FENESTRA_CUDA_RETURN_IF_ERROR(d.crossings.Reserve(rows * r.crossing_capacity));
    FENESTRA_CUDA_RETURN_IF_ERROR(d.connections.Reserve(rows * r.connection_capacity));
    FENESTRA_CUDA_RETURN_IF_ERROR(d.resumes.Reserve(rows * r.resume_capacity));
    FENESTRA_CUDA_RETURN_IF_ERROR(d.record_counts.Zero(3 * static_cast<size_t>(rows)));
    const DeviceRecords records = d.Records();
    const dim3 grid(d.BlocksPerRow(RecordKernel, shared, row_paths, rows), rows);
    FENESTRA_RETURN_IF_ERROR(d.Run(
        rows, static_cast<size_t>(rows) * columns, false,
        [&] {
          RecordKernel<<<grid, kThreads, shared>>>(
              d.Scene(), r.envelopes, d.Surfaces(), r.path, d.Outdoor(r.outdoor_offset),
              d.replay_sensors.get(), r.sensor_count, r.windows, r.basis, r.paths_per_sensor,
              row_batches, r.seed, records, d.sum.get(), d.counters.get(), d.next_path.get());
        },
        nullptr, nullptr, counters));
    FENESTRA_CUDA_RETURN_IF_ERROR(d.record_counts.Download(counts.data(), counts.size()));
    const unsigned long long most = *std::max_element(counts.begin(), counts.begin() + rows);
    const unsigned long long most_crossing =
        *std::max_element(counts.begin() + 2 * rows, counts.end());
    if (most <= r.connection_capacity && most_crossing <= r.crossing_capacity)
      return absl::OkStatus();
    if (attempt > 0)
      return absl::InternalError(
          "CUDA tracer: the indoor paths' records changed between two traces");
    r.connection_capacity = std::max<uint64_t>(most, r.connection_capacity);
    r.crossing_capacity = std::max<uint64_t>(most_crossing, r.crossing_capacity);
  }
}

absl::Status CudaTracer::Impl::Replay(const ReplayDesigns& designs, const TraceMaterial* materials,
                                      int first, int last, double* host_sum, CudaCounters* out) {
  Impl& d = *this;
  if (!d.recorded.valid)
    return absl::FailedPreconditionError("CUDA tracer: no indoor paths recorded");
  if (!d.has_outdoor)
    return absl::FailedPreconditionError("CUDA tracer: no outdoor scene uploaded");
  const Recorded& r = d.recorded;
  if (first < 0 || first >= last || last > r.parts) {
    return absl::InvalidArgumentError(
        absl::StrCat("CUDA tracer: parts [", first, ", ", last, ") of ", r.parts, " recorded"));
  }
  if (first > 0 && (d.replayed_parts != first || designs.count != 1)) {
    return absl::FailedPreconditionError(absl::StrCat("CUDA tracer: the sums of the parts before ",
                                                      first, " are no longer on the device"));
  }
  FENESTRA_CUDA_RETURN_IF_ERROR(cudaSetDevice(d.device));
  const ReplayParts parts{r.batches, r.parts, first, last, r.paths_per_sensor};
  const unsigned int rows = static_cast<unsigned int>(r.sensor_count * r.batches * designs.count);
  const int columns = IndoorColumnCount(r.windows);
  const size_t shared = static_cast<size_t>(columns) * sizeof(double);
  if (d.row_blocks_key != std::array<int, 3>{first, last, designs.count}) {
    int resident = 0;
    FENESTRA_CUDA_RETURN_IF_ERROR(
        cudaOccupancyMaxActiveBlocksPerMultiprocessor(&resident, ReplayKernel, kThreads, shared));
    const std::vector<unsigned int> blocks =
        ShareBlocks(d.ReplayRowWork(first, last, designs.count),
                    static_cast<unsigned int>(std::max(1, resident) * d.multiprocessors));
    FENESTRA_CUDA_RETURN_IF_ERROR(d.row_blocks.Upload(blocks.data(), blocks.size()));
    d.row_blocks_key = {first, last, designs.count};
    d.row_blocks_total = blocks.back();
  }
  // The first replay of all parts measures how long the resumed paths are; the later ones
  // take the longest first, so that the launch does not wait for paths begun at its end
  DeviceRecords records = d.Records();
  const bool all_parts = first == 0 && last == r.parts;
  const bool measure = all_parts && !d.resume_order_made;
  if (measure) {
    FENESTRA_CUDA_RETURN_IF_ERROR(
        d.resume_lengths.Reserve(r.counts.size() / 3 * r.resume_capacity));
    records.lengths = d.resume_lengths.get();
  } else if (all_parts) {
    records.order = d.resume_order.get();
  }
  absl::Status status = d.Run(
      rows, d.DesignSums() * designs.count, false,
      [&] {
        ReplayKernel<<<d.row_blocks_total, kThreads, shared>>>(
            designs, materials, r.path, d.Outdoor(r.outdoor_offset), d.replay_sensors.get(),
            r.sensor_count, r.windows, r.basis, parts, r.seed, r.envelopes, records,
            d.row_blocks.get(), d.fixed.get(), d.sum.get(), d.DesignSums(), d.counters.get(),
            d.next_path.get());
      },
      host_sum, nullptr, out, first > 0);
  if (measure && status.ok()) status = d.OrderResumes();
  d.replayed_parts = status.ok() && designs.count == 1 ? last : 0;
  return status;
}

int CudaTracer::ReplayedParts() const { return impl_->replayed_parts; }

absl::Status CudaTracer::ReplayIndoor(const ReplayBlinds& blinds, int first, int last, double* sum,
                                      CudaCounters* counters) {
  Impl& d = *impl_;
  ReplayDesigns designs{};
  designs.design[0] = {d.nodes.get(), d.triangles.get(), d.triangle_material.get(), blinds};
  designs.count = 1;
  return d.Replay(designs, d.materials.get(), first, last, sum, counters);
}

absl::Status CudaTracer::ReplayIndoorDesigns(const std::vector<DesignScene>& scenes,
                                             const std::vector<TraceMaterial>& materials,
                                             CudaCounters* counters) {
  Impl& d = *impl_;
  if (scenes.empty() || scenes.size() > kMaxReplayDesigns) {
    return absl::InvalidArgumentError(absl::StrCat(
        "CUDA tracer: ", scenes.size(), " designs in one replay (1 to ", kMaxReplayDesigns, ")"));
  }
  // The designs' scenes one after the other; each design's BVH indexes its own part
  std::vector<BvhNode> nodes;
  std::vector<BvhTriangle> triangles;
  std::vector<uint32_t> triangle_material;
  std::vector<std::array<size_t, 3>> starts;
  for (const DesignScene& scene : scenes) {
    starts.push_back({nodes.size(), triangles.size(), triangle_material.size()});
    nodes.insert(nodes.end(), scene.bvh->nodes.begin(), scene.bvh->nodes.end());
    triangles.insert(triangles.end(), scene.bvh->triangles.begin(), scene.bvh->triangles.end());
    triangle_material.insert(triangle_material.end(), scene.triangle_material->begin(),
                             scene.triangle_material->end());
  }
  d.replayed_parts = 0;
  FENESTRA_CUDA_RETURN_IF_ERROR(cudaSetDevice(d.device));
  FENESTRA_CUDA_RETURN_IF_ERROR(d.design_nodes.Upload(nodes.data(), nodes.size()));
  FENESTRA_CUDA_RETURN_IF_ERROR(d.design_triangles.Upload(triangles.data(), triangles.size()));
  FENESTRA_CUDA_RETURN_IF_ERROR(
      d.design_triangle_material.Upload(triangle_material.data(), triangle_material.size()));
  // The materials change with the job, not with its designs
  const auto same = [](const TraceMaterial& a, const TraceMaterial& b) {
    return a.reflectance == b.reflectance && a.transmittance == b.transmittance &&
           a.specular == b.specular && a.roughness == b.roughness && a.through == b.through &&
           a.glass == b.glass && a.straight_scatters == b.straight_scatters;
  };
  if (!std::equal(materials.begin(), materials.end(), d.design_materials_held.begin(),
                  d.design_materials_held.end(), same)) {
    FENESTRA_CUDA_RETURN_IF_ERROR(d.design_materials.Upload(materials.data(), materials.size()));
    d.design_materials_held = materials;
  }
  ReplayDesigns designs{};
  designs.count = static_cast<int>(scenes.size());
  for (size_t k = 0; k < scenes.size(); ++k) {
    designs.design[k] = {d.design_nodes.get() + starts[k][0],
                         d.design_triangles.get() + starts[k][1],
                         d.design_triangle_material.get() + starts[k][2], scenes[k].blinds};
  }
  return d.Replay(designs, d.design_materials.get(), 0, d.recorded.parts, nullptr, counters);
}

size_t CudaTracer::DesignSums() const { return impl_->recorded.valid ? impl_->DesignSums() : 0; }

const double* CudaTracer::DeviceSums() const { return impl_->sum.get(); }

}  // namespace fenestra
