#pragma once

// The GPU tracer: the shared per-path code (core/trace/path.h, two_stage_modes.h) with the
// BVH traversal of core/trace/bvh_intersector.h; each thread traces paths one ray at a time
// and starts its row's next path as soon as one ends. Host-only
// declarations (no CUDA headers), so C++ code includes it. Errors are statuses: CUDA's own
// errors INTERNAL (RESOURCE_EXHAUSTED where device memory ran out), a call out of order
// FAILED_PRECONDITION, arguments the tracer cannot take INVALID_ARGUMENT.
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "core/geometry/hemisphere_basis.h"
#include "core/trace/bvh_layout.h"
#include "core/trace/indoor_replay_modes.h"
#include "core/trace/local_slats.h"
#include "core/trace/path.h"
#include "core/trace/two_stage_modes.h"

namespace fenestra {

// What the kernels counted.
struct CudaCounters {
  uint64_t rays = 0;      // closest-hit queries
  uint64_t ends[6] = {};  // paths by PathEnd
  double kernel_seconds = 0;
};

// What CudaTracer::RecordIndoor recorded.
struct CudaReplayStats {
  uint64_t paths = 0;        // indoor paths traced
  uint64_t resumes = 0;      // of them, those that reached the envelope
  uint64_t connections = 0;  // next-event connections that passed the room
  uint64_t rays = 0;         // closest-hit queries
  double kernel_seconds = 0;
};

// Name of CUDA device `device`, or "" when there is none.
std::string CudaDeviceName(int device = 0);

// Number of visible CUDA devices (0 without a driver or device).
int CudaDeviceCount();

class CudaTracer {
 public:
  // A tracer on `device`; UNAVAILABLE where the host has no CUDA device, INVALID_ARGUMENT
  // where it has no device `device`.
  static absl::StatusOr<std::unique_ptr<CudaTracer>> Create(int device);
  ~CudaTracer();
  CudaTracer(const CudaTracer&) = delete;
  CudaTracer& operator=(const CudaTracer&) = delete;

  // Uploads the scene to trace next: its BVH, and per triangle an index into `materials`.
  absl::Status SetScene(const BvhLayout& bvh, const uint32_t* triangle_material,
                        size_t triangle_count, const TraceMaterial* materials,
                        size_t material_count);

  // Closest hits of `count` rays (origins and unit directions in the scene's frame) in the
  // uploaded scene: distance[i] gets the distance to ray i's hit, INFINITY on a miss. With
  // same_ray_per_warp, every lane of a warp traces the warp's first ray: the traversal's
  // cost without divergence or scattered memory reads, a yardstick for benchmarks.
  absl::Status IntersectRays(const Vec3f* origins, const Vec3f* directions, size_t count,
                             bool same_ray_per_warp, float* distance, double* kernel_seconds);

  // One-stage paths of each sensor in `batches` contiguous batches; sum and sum_squares
  // get [(sensor * batches + batch) * kOneStageBins + bin] (OneStageBin).
  absl::Status OneStage(const TraceSensor* sensors, int sensor_count, uint64_t paths_per_sensor,
                        int batches, uint64_t seed, const PathSettings& path, double* sum,
                        double* sum_squares, CudaCounters* counters);

  // Where Outdoor puts O: each batch, their mean and its standard error, row-major
  // OutdoorRowCount(window cells) x kTregenzaBinCount as FormOutdoorBatches makes them
  // (core/dc/dc_backend.h), and per window cell its paths whose first segment reached the sky.
  struct OutdoorOutput {
    std::vector<double*> batches;
    double* mean;
    double* standard_error;
    double* first_escapes;
    // Where not null: O's batches also left on the device for the caller, one after the
    // other as `batches` get them, freed when the last holder lets go (the tracer forms its
    // next outdoor stage elsewhere).
    std::shared_ptr<const double>* batches_on_device = nullptr;
  };
  // Outdoor paths, paths_per_cell from each window cell in `batches` batches, the same
  // streams as TraceOutdoorCpu; O formed from their sums on the device, then downloaded.
  // Of window `window` of `windows` (LinkWindows).
  absl::Status Outdoor(const std::vector<TraceWindow>& windows, int window,
                       const HemisphereBasis& basis, uint64_t paths_per_cell, int batches,
                       uint64_t seed, const PathSettings& path, const OutdoorOutput& out,
                       CudaCounters* counters);

  // Uploads the outdoor surfaces' BVH, which the indoor stage tests its window connections
  // against (OutdoorView), and per window cell whether all its views meet them
  // (WindowCellsMeetingSurfaces, for the next indoor stages' parts and basis).
  absl::Status SetOutdoorScene(const BvhLayout& bvh, const std::vector<uint8_t>& met);

  // Indoor paths in `batches` contiguous batches per sensor, as TraceIndoorCpu, against the
  // uploaded scene and outdoor scene (`outdoor_offset`: OutdoorView::offset); sum gets
  // [(batch * sensors + sensor) * columns + column], or, null, leaves them on the device.
  absl::Status Indoor(const TraceSensor* sensors, int sensor_count,
                      const std::vector<TraceWindow>& windows, Vec3f outdoor_offset,
                      const HemisphereBasis& basis, uint64_t paths_per_sensor, int batches,
                      uint64_t seed, const PathSettings& path, double* sum, CudaCounters* counters);

  // The indoor replay (core/dc/indoor_replay.h) on the device. RecordIndoor traces the
  // indoor paths, as Indoor, through the uploaded scene (the room without the blinds) up to
  // where they could first meet a blind inside one of `envelopes`, and keeps on the device what
  // no blind changes, the next-event connections that cleared the room and the paths that
  // reached an envelope (RESOURCE_EXHAUSTED, and nothing recorded, where that would take
  // more than `max_bytes` or more device memory than there is). ReplayIndoor then gives Indoor's
  // sums for the uploaded scene, a room with blinds inside the envelopes in the recorded frame,
  // from the records: the connections tested against `blinds` (their slats alone), the paths
  // that reached an envelope traced on. Each batch's paths are recorded in `parts` parts of
  // consecutive paths, and ReplayIndoor replays parts [first, last) of every batch, added to the
  // sums of parts [0, first) that the replay before it left on the device (an error where they are
  // no longer there: FAILED_PRECONDITION).
  absl::Status RecordIndoor(const LocalEnvelopes& envelopes, const TraceSensor* sensors,
                            int sensor_count, const std::vector<TraceWindow>& windows,
                            Vec3f outdoor_offset, const HemisphereBasis& basis,
                            uint64_t paths_per_sensor, int batches, int parts, uint64_t seed,
                            const PathSettings& path, size_t max_bytes, CudaReplayStats* stats);
  absl::Status ReplayIndoor(const ReplayBlinds& blinds, int first, int last, double* sum,
                            CudaCounters* counters);

  // ReplayIndoor for several designs in one launch, every part of each (a launch's last
  // paths end one after another, so designs traced together share that tail): design k's
  // room with its blinds (`scenes[k]`, its triangles' materials indexed into `materials`)
  // and their slats alone (`scenes[k].blinds`). The sums stay on the device, design k's at
  // DeviceSums() + k * DesignSums(). At most kMaxReplayDesigns.
  struct DesignScene {
    const BvhLayout* bvh;
    const std::vector<uint32_t>* triangle_material;
    ReplayBlinds blinds;
  };
  absl::Status ReplayIndoorDesigns(const std::vector<DesignScene>& scenes,
                                   const std::vector<TraceMaterial>& materials,
                                   CudaCounters* counters);
  static constexpr int kMaxReplayDesigns = 8;
  // Doubles of one design's sums in a replay (batches x sensors x columns); 0 with no records.
  size_t DesignSums() const;

  // The sums of the last Indoor or ReplayIndoor on the device, in their layout (valid until
  // the next trace): where `sum` was null, they stay there for the annual product
  // (core/dc/cuda/annual_tally.h).
  const double* DeviceSums() const;

  // How many parts of a replay's sums the device holds (ReplayIndoor's `first`
  // may be this); 0 when it holds none.
  int ReplayedParts() const;

  std::string device_name() const;

 private:
  struct Impl;
  explicit CudaTracer(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

}  // namespace fenestra
