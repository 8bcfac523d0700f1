// The CUDA backend: the same path code and random streams as the Embree backend, traced
// on a GPU over a BVH built on the host (core/trace/bvh.h). Weight windows (the one-stage
// importance map) are CPU-only: on the GPU the one-stage method uses plain roulette.
#include <algorithm>
#include <chrono>
#include <functional>
#include <memory>

#include "absl/strings/str_cat.h"
#include "core/common/huge_pages.h"
#include "core/common/seconds.h"
#include "core/common/status_macros.h"
#include "core/dc/backend_support.h"
#include "core/dc/dc_backend.h"
#include "core/dc/direct_sun.h"
#include "core/dc/two_stage.h"
#include "core/metrics/metric_errors.h"
#include "core/trace/one_stage_cpu.h"

#if FENESTRA_WITH_CUDA
#include "absl/strings/match.h"
#include "core/dc/cuda/annual_tally.h"
#include "core/dc/indoor_replay.h"
#include "core/metrics/glare.h"
#include "core/trace/bvh.h"
#include "core/trace/cuda/cuda_tracer.h"
#include "core/trace/window_cells.h"
#endif

namespace fenestra {

#if FENESTRA_WITH_CUDA
namespace {

// `status` with its message prefixed by what it kept from happening.
absl::Status CannotUseGpu(const absl::Status& status) {
  return absl::Status(status.code(), absl::StrCat("cannot use the GPU: ", status.message()));
}

// Device memory the indoor replay's records may take; a job whose records would take more
// traces every design in full (CudaTracer::RecordIndoor's RESOURCE_EXHAUSTED).
constexpr size_t kMaxReplayBytes = size_t{4} << 30;

// Builds the geometry's BVH and hands it to the tracer to trace next.
absl::Status UploadScene(CudaTracer& tracer, const TraceGeometry& geometry, BvhQuality quality) {
  FENESTRA_ASSIGN_OR_RETURN(bvh, BuildBvh(geometry, quality));
  return tracer.SetScene(bvh, geometry.triangle_material.data(), geometry.triangle_material.size(),
                         geometry.materials.data(), geometry.materials.size());
}

// Host buffers for the tallies the GPU reduces E to (CudaAnnualTally::TallyRequest).
struct DeviceTallies {
  DeviceTallies(int batches, int sensors, const MetricOptions& options)
      : batches(batches),
        sensors(sensors),
        counts(3 * static_cast<size_t>(batches + 1) * sensors),
        hours(4 * static_cast<size_t>(batches + 1)),
        sums(2 * static_cast<size_t>(batches + 1) * sensors),
        request{options.udi_lower_lux, options.udi_upper_lux, options.da_threshold_lux,
                counts.data(),         sums.data(),           hours.data()} {}
  // `request` points into the buffers
  DeviceTallies(const DeviceTallies&) = delete;
  DeviceTallies& operator=(const DeviceTallies&) = delete;

  // The versions as HourTally, each over `steps` hours; InvalidArgument for a non-finite E.
  absl::StatusOr<std::vector<HourTally>> Versions(int64_t steps) const {
    std::vector<HourTally> versions(batches + 1);
    for (int v = 0; v <= batches; ++v) {
      if (hours[4 * v + 3] > 0) {
        return absl::InvalidArgumentError("illuminance has a non-finite value");
      }
      HourTally& tally = versions[v];
      tally.hours = steps;
      tally.all_in = hours[4 * v];
      tally.any_below = hours[4 * v + 1];
      tally.any_above = hours[4 * v + 2];
      tally.sensors.resize(sensors);
      for (int i = 0; i < sensors; ++i) {
        const size_t k = static_cast<size_t>(v) * sensors + i;
        tally.sensors[i] = {counts[3 * k], counts[3 * k + 1], counts[3 * k + 2], sums[2 * k],
                            sums[2 * k + 1]};
      }
    }
    return versions;
  }

  int batches, sensors;
  std::vector<int64_t> counts, hours;
  std::vector<double> sums;
  CudaAnnualTally::TallyRequest request;
};

PathSettings WithoutImportance(PathSettings path) {
  path.importance = nullptr;
  return path;
}

// The kernels' counters as the backends report them.
void CopyCounters(const CudaCounters& counters, TraceCounters* out) {
  out->rays = counters.rays;
  for (int e = 0; e < 6; ++e) out->ends[e] = counters.ends[e];
  out->max_weight = 1.0f;
}

// An indoor tally of zeros for the sums of a trace to be downloaded into.
IndoorTally ZeroIndoorTally(int sensors, int columns, int batches, uint64_t paths_per_sensor) {
  IndoorTally tally;
  tally.sensors = sensors;
  tally.columns = columns;
  tally.batches = batches;
  tally.paths_per_sensor = paths_per_sensor;
  tally.batch_paths = BatchSizes(paths_per_sensor, batches);
  tally.sum.resize(static_cast<size_t>(batches) * sensors * columns);
  return tally;
}

// What the tracer holds one of at a time (an outdoor scene, indoor records), shared by the objects
// of one backend that use it: each object takes a generation when made, and uploads its own again
// when another one replaced it.
struct TracerSlot {
  int current = 0;  // the generation the tracer holds
  int made = 0;     // generations handed out
};

// The annual product on the GPU: its O_b and S uploaded once, on the device for as long as
// the product lives.
class CudaAnnualProduct : public AnnualProduct {
 public:
  // O_b from `on_device` where it lies on `device`, else from the host.
  static absl::StatusOr<std::unique_ptr<CudaAnnualProduct>> Make(int device,
                                                                 const std::vector<Matrix>& outdoor,
                                                                 const Matrix& sky,
                                                                 const DeviceMatrices& on_device) {
    FENESTRA_RETURN_IF_ERROR(CheckOutdoorBatches(outdoor, sky));
    FENESTRA_ASSIGN_OR_RETURN(annual, NewTally(device));
    const bool from_device = on_device.data != nullptr && on_device.device == device;
    std::vector<const double*> batches;
    for (size_t b = 0; b < outdoor.size(); ++b) {
      batches.push_back(from_device ? on_device.data.get() + b * outdoor[b].size()
                                    : outdoor[b].data());
    }
    FENESTRA_RETURN_IF_ERROR(annual->SetProduct(batches, static_cast<int>(outdoor[0].rows()),
                                                sky.data(), static_cast<int>(sky.cols()),
                                                static_cast<int>(sky.rows()), from_device));
    return std::unique_ptr<CudaAnnualProduct>(new CudaAnnualProduct(
        std::move(annual), static_cast<int>(outdoor.size()), outdoor[0].rows(), sky));
  }
  // The product of the sky alone (DcBackend::MakeSkyProduct).
  static absl::StatusOr<std::unique_ptr<CudaAnnualProduct>> MakeSky(int device, const Matrix& sky) {
    FENESTRA_RETURN_IF_ERROR(CheckSkyRows(sky));
    FENESTRA_ASSIGN_OR_RETURN(annual, NewTally(device));
    FENESTRA_RETURN_IF_ERROR(annual->SetSkyProduct(sky.data(), static_cast<int>(sky.cols()),
                                                   static_cast<int>(sky.rows())));
    return std::unique_ptr<CudaAnnualProduct>(
        new CudaAnnualProduct(std::move(annual), kAnyBatches, sky.rows(), sky));
  }

  absl::StatusOr<std::vector<Matrix>> ApplyToSky(const std::vector<Matrix>& indoor_batches,
                                                 const Matrix& sky,
                                                 std::span<const SunEntry> sun) override {
    FENESTRA_RETURN_IF_ERROR(CheckSkyRows(sky));
    if (sky.rows() != sky_.rows()) {
      return absl::InvalidArgumentError("the sky of a call has other rows than the product's");
    }
    FENESTRA_RETURN_IF_ERROR(CheckSunEntries(sun, indoor_batches, sky));
    FENESTRA_ASSIGN_OR_RETURN(e, Illuminance(indoor_batches, &sky));
    return WithSun(std::move(e), sun);
  }

  // E is formed and tallied on the device; only the tallies come back.
  absl::StatusOr<std::vector<HourTally>> Tally(const std::vector<Matrix>& indoor_batches,
                                               const MetricOptions& options,
                                               std::span<const SunEntry> sun) override {
    const int batches = static_cast<int>(indoor_batches.size());
    FENESTRA_RETURN_IF_ERROR(CheckBatchCount(batches));
    FENESTRA_RETURN_IF_ERROR(CheckErrorBatches(batches));
    FENESTRA_RETURN_IF_ERROR(CheckSunEntries(sun, indoor_batches, sky_));
    FENESTRA_ASSIGN_OR_RETURN(stacked, StackIndoorBatches(indoor_batches, rows_));
    const int sensors = static_cast<int>(indoor_batches[0].rows());
    DeviceTallies tallies(batches, sensors, options);
    FENESTRA_RETURN_IF_ERROR(annual_->Tally(stacked.data(), batches, sensors, tallies.request,
                                            {sun.data(), sun.size()}));
    return tallies.Versions(sky_.cols());
  }
  const Matrix& Sky() const override { return sky_; }

  // E_b through `sky` (as ApplyToSky; null: S, which the device holds) of one design's
  // indoor sums on the device (CudaTracer::DeviceSums), batch b's divided by batch_paths[b].
  absl::StatusOr<std::vector<Matrix>> ApplyToSkySums(const double* device_sums, int sensors,
                                                     const std::vector<uint64_t>& batch_paths,
                                                     const Matrix* sky,
                                                     std::span<const SunEntry> sun) {
    const Matrix& through = sky != nullptr ? *sky : sky_;
    FENESTRA_RETURN_IF_ERROR(CheckSkyRows(through));
    if (through.rows() != sky_.rows()) {
      return absl::InvalidArgumentError("the sky of a call has other rows than the product's");
    }
    FENESTRA_RETURN_IF_ERROR(
        CheckSunEntries(sun, std::vector<Matrix>{Matrix(sensors, 0)}, through));
    Matrix illuminance(Eigen::Index{batches_} * sensors, through.cols());
    FENESTRA_RETURN_IF_ERROR(annual_->IlluminanceOfSums(
        device_sums, batches_, sensors, batch_paths.data(), sky != nullptr ? sky->data() : nullptr,
        static_cast<int>(through.cols()), illuminance.data()));
    AddSunEntries(sun, sensors, illuminance);
    return SplitBatches(illuminance, batches_);
  }

  // The tallies of `designs` designs' indoor sums on the device (CudaTracer::DeviceSums),
  // design k's at device_sums + k * design_sums, batch b's divided by batch_paths[b].
  // Design k's direct sun is sun[k] (none where `sun` is shorter).
  std::vector<absl::StatusOr<std::vector<HourTally>>> TallySums(
      const double* device_sums, size_t design_sums, int designs, int sensors,
      const std::vector<uint64_t>& batch_paths, const MetricOptions& options,
      const std::vector<std::vector<SunEntry>>& sun) {
    std::vector<std::unique_ptr<DeviceTallies>> tallies;
    std::vector<CudaAnnualTally::TallyRequest> requests;
    std::vector<SunEntries> entries(designs);
    for (int k = 0; k < designs; ++k) {
      tallies.push_back(std::make_unique<DeviceTallies>(batches_, sensors, options));
      requests.push_back(tallies.back()->request);
      if (k < static_cast<int>(sun.size())) entries[k] = {sun[k].data(), sun[k].size()};
    }
    const absl::Status tallied =
        annual_->TallySums(device_sums, design_sums, designs, batches_, sensors, batch_paths.data(),
                           requests.data(), entries.data());
    std::vector<absl::StatusOr<std::vector<HourTally>>> out;
    for (int k = 0; k < designs; ++k) {
      out.push_back(tallied.ok() ? tallies[k]->Versions(sky_.cols()) : tallied);
    }
    return out;
  }

  // Uploads `steps` (checked against S: DesignTallies::SetGlareSteps) for GlareSums.
  absl::Status SetGlare(const GlareSteps& steps) {
    const Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor> factor =
        steps.sun_factor;
    const std::vector<uint8_t> occupied(steps.occupied.begin(), steps.occupied.end());
    FENESTRA_RETURN_IF_ERROR(annual_->SetGlare(factor.data(), occupied.data(),
                                               static_cast<int>(factor.rows()), steps.threshold,
                                               EyeLuxAtDgp(steps.threshold)));
    glare_views_ = static_cast<int>(factor.rows());
    return absl::OkStatus();
  }

  // The glare counts of `designs` designs' indoor sums on the device, as TallySums takes
  // them (the sensors the eyes of SetGlare), design k's beam at the eyes sun[k] (none where
  // `sun` is shorter).
  std::vector<absl::StatusOr<GlareCounts>> GlareSums(
      const double* device_sums, size_t design_sums, int designs,
      const std::vector<uint64_t>& batch_paths, const std::vector<std::vector<SunEntry>>& sun) {
    std::vector<SunEntries> entries(designs);
    for (int k = 0; k < designs && k < static_cast<int>(sun.size()); ++k) {
      entries[k] = {sun[k].data(), sun[k].size()};
    }
    const int versions = batches_ + 1;
    const size_t views = static_cast<size_t>(glare_views_);
    std::vector<int64_t> counts(static_cast<size_t>(std::max(designs, 0)) * versions * (views + 1));
    const absl::Status counted =
        annual_->GlareSums(device_sums, design_sums, designs, batches_, batch_paths.data(),
                           entries.data(), counts.data());
    std::vector<absl::StatusOr<GlareCounts>> out;
    for (int k = 0; k < designs; ++k) {
      if (!counted.ok()) {
        out.push_back(counted);
        continue;
      }
      GlareCounts c;
      for (int v = 0; v < versions; ++v) {
        const int64_t* row = counts.data() + (static_cast<size_t>(k) * versions + v) * (views + 1);
        c.view_steps.emplace_back(row, row + views);
        c.any_steps.push_back(row[views]);
      }
      out.push_back(std::move(c));
    }
    return out;
  }

 private:
  // batches_ of the product of the sky alone: its O_b, the identity, pair with any count
  static constexpr int kAnyBatches = 0;

  static absl::StatusOr<std::unique_ptr<CudaAnnualTally>> NewTally(int device) {
    absl::StatusOr<std::unique_ptr<CudaAnnualTally>> annual = CudaAnnualTally::Create(device);
    if (!annual.ok()) return CannotUseGpu(annual.status());
    return annual;
  }

  CudaAnnualProduct(std::unique_ptr<CudaAnnualTally> annual, int batches, Eigen::Index rows,
                    Matrix sky)
      : annual_(std::move(annual)), batches_(batches), rows_(rows), sky_(std::move(sky)) {}

  // E's batches with the direct sun added on the host.
  static std::vector<Matrix> WithSun(std::vector<Matrix> e, std::span<const SunEntry> sun) {
    for (Matrix& batch : e) AddSunEntries(sun, static_cast<int>(batch.rows()), batch);
    return e;
  }

  absl::Status CheckBatchCount(size_t batches) const {
    if (batches_ == kAnyBatches || static_cast<int>(batches) == batches_) return absl::OkStatus();
    return absl::InvalidArgumentError(absl::StrCat("the indoor stage has ", batches,
                                                   " batches, the outdoor matrix ", batches_,
                                                   "; they pair up"));
  }

  // E through S, or through `other_sky` where it is not null.
  absl::StatusOr<std::vector<Matrix>> Illuminance(const std::vector<Matrix>& indoor_batches,
                                                  const Matrix* other_sky) {
    FENESTRA_RETURN_IF_ERROR(CheckBatchCount(indoor_batches.size()));
    FENESTRA_ASSIGN_OR_RETURN(stacked, StackIndoorBatches(indoor_batches, rows_));
    const Eigen::Index steps = other_sky != nullptr ? other_sky->cols() : sky_.cols();
    Matrix illuminance(stacked.rows(), steps);
    FENESTRA_RETURN_IF_ERROR(annual_->Illuminance(
        stacked.data(), static_cast<int>(stacked.rows()), illuminance.data(),
        other_sky != nullptr ? other_sky->data() : nullptr, static_cast<int>(steps)));
    return SplitBatches(illuminance, indoor_batches.size());
  }

  std::unique_ptr<CudaAnnualTally> annual_;
  int batches_;
  Eigen::Index rows_;    // of each O_b
  Matrix sky_;           // S, as uploaded
  int glare_views_ = 0;  // SetGlare's
};

// The tracer's outdoor scene (TracerSlot), shared by the indoor stages of one backend.
class OutdoorHolder {
 public:
  static absl::StatusOr<OutdoorHolder> Make(CudaTracer* tracer, TracerSlot* slot,
                                            const Scene& scene, WindowParts parts,
                                            const HemisphereBasis& basis) {
    FENESTRA_ASSIGN_OR_RETURN(geometry, OutdoorViewGeometry(scene));
    FENESTRA_ASSIGN_OR_RETURN(bvh, BuildBvh(geometry, BvhQuality::kHigh));
    std::vector<uint8_t> met =
        OutdoorMetCells(geometry, geometry, LocalWindows(geometry, scene, parts, basis), basis);
    return OutdoorHolder(tracer, slot, std::move(geometry), std::move(bvh), std::move(met));
  }
  // Makes the tracer hold this outdoor scene.
  absl::Status Hold() {
    if (slot_->current == generation_) return absl::OkStatus();
    FENESTRA_RETURN_IF_ERROR(tracer_->SetOutdoorScene(bvh_, met_));
    slot_->current = generation_;
    return absl::OkStatus();
  }
  const TraceGeometry& geometry() const { return geometry_; }

 private:
  OutdoorHolder(CudaTracer* tracer, TracerSlot* slot, TraceGeometry geometry, BvhLayout bvh,
                std::vector<uint8_t> met)
      : tracer_(tracer),
        slot_(slot),
        generation_(++slot->made),
        geometry_(std::move(geometry)),
        bvh_(std::move(bvh)),
        met_(std::move(met)) {}
  CudaTracer* tracer_;
  TracerSlot* slot_;
  int generation_;
  TraceGeometry geometry_;
  BvhLayout bvh_;
  std::vector<uint8_t> met_;
};

// The indoor replay on the GPU (core/dc/indoor_replay.h): the room without the blinds is
// traced once up to the blinds' envelopes; per design, the tracer replays the records
// against the room with the design's slats (their BVH put beside the room's) and the
// slats' layout alone, all in the room's frame.
class CudaReplay {
 public:
  // Records `scene`'s indoor paths; Unavailable where the records would take more than
  // kMaxReplayBytes, InvalidArgument for a scene without a blind, Unimplemented for one of
  // more blinds than a replay follows.
  static absl::StatusOr<std::unique_ptr<CudaReplay>> Make(CudaTracer* tracer, TracerSlot* slot,
                                                          const Scene& scene,
                                                          const IndoorOptions& options,
                                                          const HemisphereBasis& basis,
                                                          OutdoorHolder* outdoor) {
    FENESTRA_ASSIGN_OR_RETURN(
        room, PrepareTraceGeometry(SelectSide(scene.fixed, Side::kIndoor), scene.materials));
    FENESTRA_ASSIGN_OR_RETURN(envelopes, LocalEnvelopesOfBlinds(room, scene));
    auto replay = std::unique_ptr<CudaReplay>(
        new CudaReplay(tracer, slot, scene, options, basis, outdoor, std::move(room), envelopes));
    FENESTRA_RETURN_IF_ERROR(replay->Record());
    return replay;
  }

  // A design's scene for the replay: the recorded room with its slats (BvhWithSlats: no
  // build per design), its triangles' materials, and the slats' layout alone, for the
  // shadow rays. InvalidArgument for a design outside the recorded ranges.
  absl::StatusOr<CudaTracer::DesignScene> MakeScene(const BlindDesign& design, BvhLayout* bvh,
                                                    std::vector<uint32_t>* triangle_material) {
    FENESTRA_RETURN_IF_ERROR(CheckReplayDesign(scene_, design));
    std::vector<int> slats_per_blind;
    const std::vector<Vec3f> corners = LocalSlatCorners(room_, scene_, design, &slats_per_blind);
    *bvh = BvhWithSlats(room_bvh_, corners, static_cast<uint32_t>(room_.TriangleCount()),
                        slats_per_blind);
    *triangle_material = room_.triangle_material;
    triangle_material->reserve(room_.TriangleCount() + kTrianglesPerSlat * corners.size() / 8);
    size_t blind = 0;
    for (const SceneWindow& w : scene_.windows) {
      if (!w.blind) continue;
      const SlatFinish finish = FinishOf(*w.blind, design);
      for (int slat = 0; slat < slats_per_blind[blind]; ++slat) {
        for (int t = 0; t < kTrianglesPerSlat; ++t) {
          triangle_material->push_back(SlatTriangleMaterial(finish, t));
        }
      }
      ++blind;
    }
    triangles_ = triangle_material->size();
    return CudaTracer::DesignScene{bvh, triangle_material,
                                   ReplayBlindsOf(room_, scene_, design, envelopes_)};
  }

  // Makes the tracer hold the records and the recorded room with `design`'s slats; `blinds`
  // gets the slats' layout. InvalidArgument for a design outside the recorded ranges.
  absl::Status Prepare(const BlindDesign& design, ReplayBlinds* blinds) {
    BvhLayout bvh;
    std::vector<uint32_t> triangle_material;
    FENESTRA_ASSIGN_OR_RETURN(scene, MakeScene(design, &bvh, &triangle_material));
    FENESTRA_RETURN_IF_ERROR(Hold());
    *blinds = scene.blinds;
    return tracer_->SetScene(bvh, triangle_material.data(), triangle_material.size(),
                             room_.materials.data(), room_.materials.size());
  }

  // Every part of `design`, its sums downloaded (IndoorResultFromTally gives its I).
  absl::StatusOr<IndoorTally> Sums(const BlindDesign& design) {
    const auto start = std::chrono::steady_clock::now();
    ReplayBlinds blinds;
    FENESTRA_RETURN_IF_ERROR(Prepare(design, &blinds));
    IndoorTally tally = ZeroIndoorTally(sensors(), columns(), options_.batches,
                                        static_cast<uint64_t>(options_.paths_per_sensor));
    CudaCounters counters;
    FENESTRA_RETURN_IF_ERROR(
        tracer_->ReplayIndoor(blinds, 0, kDesignParts, tally.sum.data(), &counters));
    CopyCounters(counters, &tally.counters);
    tally.trace_seconds = counters.kernel_seconds;
    tally.wall_seconds = SecondsSince(start);
    return tally;
  }

  // Every part of the designs of `scenes` (MakeScene) in one launch
  // (CudaTracer::ReplayIndoorDesigns).
  absl::Status ReplayDesigns(const std::vector<CudaTracer::DesignScene>& scenes,
                             CudaCounters* counters) {
    FENESTRA_RETURN_IF_ERROR(Hold());
    return tracer_->ReplayIndoorDesigns(scenes, room_.materials, counters);
  }

  size_t triangles() const { return triangles_; }
  int sensors() const { return static_cast<int>(scene_.sensors.size()); }
  int columns() const {
    return WindowCellsOf(scene_, options_.parts, basis_.cell_count) + kIndoorDirectColumns;
  }
  const CudaReplayStats& stats() const { return stats_; }

 private:
  CudaReplay(CudaTracer* tracer, TracerSlot* slot, const Scene& scene, const IndoorOptions& options,
             const HemisphereBasis& basis, OutdoorHolder* outdoor, TraceGeometry room,
             const LocalEnvelopes& envelopes)
      : tracer_(tracer),
        slot_(slot),
        generation_(++slot->made),
        scene_(scene),
        options_(options),
        basis_(basis),
        outdoor_(outdoor),
        room_(std::move(room)),
        envelopes_(envelopes) {}

  // Makes the tracer hold the records (recording again after another replay of the tracer)
  // and the outdoor scene.
  absl::Status Hold() {
    if (slot_->current != generation_) FENESTRA_RETURN_IF_ERROR(Record());
    return outdoor_->Hold();
  }

  absl::Status Record() {
    if (room_bvh_.nodes.empty()) {
      FENESTRA_ASSIGN_OR_RETURN(bvh, BuildBvh(room_, BvhQuality::kHigh));
      room_bvh_ = std::move(bvh);
    }
    FENESTRA_RETURN_IF_ERROR(tracer_->SetScene(room_bvh_, room_.triangle_material.data(),
                                               room_.triangle_material.size(),
                                               room_.materials.data(), room_.materials.size()));
    FENESTRA_RETURN_IF_ERROR(outdoor_->Hold());
    const std::vector<TraceSensor> sensors = LocalSensors(room_, scene_.sensors);
    PathSettings path = IndoorPathSettings(options_);
    path.importance = nullptr;
    FENESTRA_RETURN_IF_ERROR(
        tracer_->RecordIndoor(envelopes_, sensors.data(), static_cast<int>(sensors.size()),
                              LocalWindows(room_, scene_, options_.parts, basis_),
                              OutdoorOffset(room_, outdoor_->geometry()), basis_,
                              static_cast<uint64_t>(options_.paths_per_sensor), options_.batches,
                              kDesignParts, options_.seed, path, kMaxReplayBytes, &stats_));
    slot_->current = generation_;
    return absl::OkStatus();
  }

  CudaTracer* tracer_;
  TracerSlot* slot_;
  int generation_;
  Scene scene_;
  IndoorOptions options_;
  HemisphereBasis basis_;
  OutdoorHolder* outdoor_;
  TraceGeometry room_;  // the room without the blinds; its frame is every design's
  LocalEnvelopes envelopes_;
  BvhLayout room_bvh_;
  CudaReplayStats stats_;
  size_t triangles_ = 0;
};

// IndoorStages by the GPU's replay.
class CudaReplayStages : public IndoorStages {
 public:
  CudaReplayStages(std::string backend, const IndoorOptions& options,
                   std::unique_ptr<OutdoorHolder> outdoor, std::unique_ptr<CudaReplay> replay)
      : backend_(std::move(backend)),
        options_(options),
        outdoor_(std::move(outdoor)),
        replay_(std::move(replay)) {}

  absl::StatusOr<IndoorResult> Compute(const BlindDesign& design) const override {
    const auto start = std::chrono::steady_clock::now();
    FENESTRA_ASSIGN_OR_RETURN(tally, replay_->Sums(design));
    IndoorResult result = IndoorResultFromTally(tally, options_);
    result.triangles = replay_->triangles();
    result.backend = backend_ + " (replay)";
    result.wall_seconds = SecondsSince(start);
    return result;
  }

 private:
  std::string backend_;
  IndoorOptions options_;
  std::unique_ptr<OutdoorHolder> outdoor_;
  std::unique_ptr<CudaReplay> replay_;
};

// A search's objective on the GPU: per design the room and blind are uploaded, then the
// indoor kernel's sums become I, E and E's tallies on the device.
class CudaDesignTallies : public DesignTallies {
 public:
  // `replay` may be null: every design is then traced in full.
  CudaDesignTallies(int device, CudaTracer* tracer, Scene scene, const IndoorOptions& options,
                    const HemisphereBasis& basis, std::unique_ptr<OutdoorHolder> outdoor,
                    std::unique_ptr<CudaReplay> replay)
      : device_(device),
        tracer_(tracer),
        scene_(std::move(scene)),
        options_(options),
        basis_(basis),
        outdoor_(std::move(outdoor)),
        replay_(std::move(replay)) {}

  absl::Status SetProduct(const std::vector<Matrix>& outdoor_batches, const Matrix& sky,
                          const DeviceMatrices& on_device) override {
    FENESTRA_RETURN_IF_ERROR(CheckOutdoorFitsIndoor(outdoor_batches, scene_, options_));
    FENESTRA_ASSIGN_OR_RETURN(product,
                              CudaAnnualProduct::Make(device_, outdoor_batches, sky, on_device));
    product_ = std::move(product);
    // The glare steps go with the product's columns
    if (GlareStepsSet() != nullptr &&
        static_cast<Eigen::Index>(GlareStepsSet()->occupied.size()) == sky.cols()) {
      FENESTRA_RETURN_IF_ERROR(product_->SetGlare(*GlareStepsSet()));
    }
    return absl::OkStatus();
  }
  absl::Status SetGlareSteps(GlareSteps steps) override {
    FENESTRA_RETURN_IF_ERROR(DesignTallies::SetGlareSteps(std::move(steps)));
    return product_->SetGlare(*GlareStepsSet());
  }
  std::vector<absl::StatusOr<GlareCounts>> GlareDesigns(
      const std::vector<BlindDesign>& designs,
      const std::vector<std::vector<SunEntry>>& sun) override {
    if (replay_ == nullptr || product_ == nullptr || GlareStepsSet() == nullptr) {
      return DesignTallies::GlareDesigns(designs, sun);
    }
    return InReplayGroups<GlareCounts>(designs, [&](const std::vector<size_t>& group) {
      std::vector<std::vector<SunEntry>> group_sun;
      for (const size_t i : group) {
        group_sun.push_back(i < sun.size() ? sun[i] : std::vector<SunEntry>{});
      }
      return product_->GlareSums(tracer_->DeviceSums(), tracer_->DesignSums(),
                                 static_cast<int>(group.size()), FullBatchPaths(), group_sun);
    });
  }
  absl::StatusOr<std::vector<HourTally>> Tally(const BlindDesign& design,
                                               const MetricOptions& options, int parts) override {
    FENESTRA_RETURN_IF_ERROR(CheckDesignParts(0, parts));
    FENESTRA_RETURN_IF_ERROR(CheckProductSet(product_.get()));
    const int sensor_count = static_cast<int>(scene_.sensors.size());
    const std::vector<uint64_t> batch_paths = PartPaths(
        static_cast<uint64_t>(options_.paths_per_sensor), options_.batches, kDesignParts, 0, parts);
    if (replay_ != nullptr) {
      FENESTRA_RETURN_IF_ERROR(Replay(design, parts));
    } else if (parts != kDesignParts) {
      return absl::UnimplementedError("designs traced in full are traced in one round");
    } else {
      FENESTRA_RETURN_IF_ERROR(TraceInFull(design, nullptr));
    }
    const std::vector<SunEntry> sun = SunOf(design);
    return WithSunlitHours(std::move(product_->TallySums(tracer_->DeviceSums(), 0, 1, sensor_count,
                                                         batch_paths, options, {sun})[0]),
                           sun, options);
  }
  absl::StatusOr<std::vector<Matrix>> IndoorBatches(const BlindDesign& design) override {
    held_parts_ = 0;  // the tracer's sums become this design's
    IndoorTally tally;
    if (replay_ != nullptr) {
      FENESTRA_ASSIGN_OR_RETURN(sums, replay_->Sums(design));
      tally = std::move(sums);
      rays_ += tally.counters.rays;
    } else {
      FENESTRA_RETURN_IF_ERROR(TraceInFull(design, &tally));
    }
    return IndoorResultFromTally(tally, options_).batches;
  }
  std::vector<absl::StatusOr<std::vector<HourTally>>> TallyDesigns(
      const std::vector<BlindDesign>& designs, const MetricOptions& options) override {
    if (replay_ == nullptr || designs.size() < 2 || product_ == nullptr) {
      return DesignTallies::TallyDesigns(designs, options);
    }
    return InReplayGroups<std::vector<HourTally>>(designs, [&](const std::vector<size_t>& group) {
      std::vector<std::vector<SunEntry>> sun;
      for (const size_t i : group) sun.push_back(SunOf(designs[i]));
      std::vector<absl::StatusOr<std::vector<HourTally>>> tallies = product_->TallySums(
          tracer_->DeviceSums(), tracer_->DesignSums(), static_cast<int>(group.size()),
          static_cast<int>(scene_.sensors.size()), FullBatchPaths(), options, sun);
      for (size_t k = 0; k < group.size(); ++k) {
        tallies[k] = WithSunlitHours(std::move(tallies[k]), sun[k], options);
      }
      return tallies;
    });
  }
  // The replay's sums stay on the device for the product
  absl::StatusOr<std::vector<Matrix>> DesignIlluminance(const BlindDesign& design,
                                                        const Matrix& sky) override {
    if (replay_ == nullptr) return DesignTallies::DesignIlluminance(design, sky);
    FENESTRA_RETURN_IF_ERROR(CheckProductSet(product_.get()));
    FENESTRA_RETURN_IF_ERROR(Replay(design, kDesignParts));
    // The product's own S is on the device already
    return product_->ApplyToSkySums(tracer_->DeviceSums(), static_cast<int>(scene_.sensors.size()),
                                    FullBatchPaths(), &sky == &product_->Sky() ? nullptr : &sky,
                                    {});
  }
  std::vector<absl::StatusOr<std::vector<Matrix>>> DesignsIlluminance(
      const std::vector<BlindDesign>& designs) override {
    if (replay_ == nullptr || designs.size() < 2 || product_ == nullptr) {
      return DesignTallies::DesignsIlluminance(designs);
    }
    return InReplayGroups<std::vector<Matrix>>(designs, [&](const std::vector<size_t>& group) {
      std::vector<absl::StatusOr<std::vector<Matrix>>> out;
      for (size_t k = 0; k < group.size(); ++k) {
        out.push_back(product_->ApplyToSkySums(tracer_->DeviceSums() + k * tracer_->DesignSums(),
                                               static_cast<int>(scene_.sensors.size()),
                                               FullBatchPaths(), nullptr, {}));
      }
      return out;
    });
  }
  AnnualProduct* Product() override { return product_.get(); }
  int DesignsAtOnce() const override { return replay_ != nullptr ? kReplayDesignsAtOnce : 1; }
  bool TracesInParts() const override { return replay_ != nullptr; }
  bool RacesByDefault() const override { return false; }
  uint64_t RaysTraced() const override { return rays_; }

 private:
  // Traces every path of `design` against the room with its blind; `tally`, unless null,
  // gets the sums (else they stay on the device).
  absl::Status TraceInFull(const BlindDesign& design, IndoorTally* tally) {
    FENESTRA_ASSIGN_OR_RETURN(
        geometry, PrepareTraceGeometry(SelectSide(AssembleMesh(scene_, design), Side::kIndoor),
                                       scene_.materials));
    FENESTRA_RETURN_IF_ERROR(UploadScene(*tracer_, geometry, BvhQuality::kMedium));
    FENESTRA_RETURN_IF_ERROR(outdoor_->Hold());
    const std::vector<TraceSensor> sensors = LocalSensors(geometry, scene_.sensors);
    const std::vector<TraceWindow> windows = LocalWindows(geometry, scene_, options_.parts, basis_);
    const uint64_t paths = static_cast<uint64_t>(options_.paths_per_sensor);
    if (tally != nullptr) {
      *tally = ZeroIndoorTally(static_cast<int>(sensors.size()),
                               IndoorColumnCount(ViewOfWindows(windows, basis_)), options_.batches,
                               paths);
    }
    CudaCounters counters;
    FENESTRA_RETURN_IF_ERROR(tracer_->Indoor(
        sensors.data(), static_cast<int>(sensors.size()), windows,
        OutdoorOffset(geometry, outdoor_->geometry()), basis_, paths, options_.batches,
        options_.seed, WithoutImportance(IndoorPathSettings(options_)),
        tally != nullptr ? tally->sum.data() : nullptr, &counters));
    if (tally != nullptr) CopyCounters(counters, &tally->counters);
    rays_ += counters.rays;
    return absl::OkStatus();
  }

  // Replays parts [0, parts) of `design`'s paths into the tracer's sums: only the parts not
  // traced yet where the tracer still holds the earlier ones of the same design.
  absl::Status Replay(const BlindDesign& design, int parts) {
    const bool goes_on = held_parts_ > 0 && design == held_design_ && parts > held_parts_ &&
                         tracer_->ReplayedParts() == held_parts_;
    if (!goes_on) {
      held_parts_ = 0;
      FENESTRA_RETURN_IF_ERROR(replay_->Prepare(design, &blinds_));
    }
    CudaCounters counters;
    FENESTRA_RETURN_IF_ERROR(
        tracer_->ReplayIndoor(blinds_, held_parts_, parts, nullptr, &counters));
    rays_ += counters.rays;
    held_design_ = design;
    held_parts_ = parts;
    return absl::OkStatus();
  }

  // `designs` replayed in launches of up to kMaxReplayDesigns, in order: per launch,
  // `take(group)` (the indices into `designs` of its designs; design k of the group's sums at
  // DeviceSums() + k * DesignSums()) gives their results. A design the replay refuses gets
  // the refusal, a failed launch its error.
  template <typename Result>
  std::vector<absl::StatusOr<Result>> InReplayGroups(
      const std::vector<BlindDesign>& designs,
      const std::function<std::vector<absl::StatusOr<Result>>(const std::vector<size_t>&)>& take) {
    std::vector<absl::StatusOr<Result>> out(designs.size(), absl::UnknownError("not traced"));
    // The designs the replay takes (in order), each with its scene
    std::vector<size_t> traced;
    std::vector<CudaTracer::DesignScene> scenes;
    std::vector<BvhLayout> bvhs(designs.size());
    std::vector<std::vector<uint32_t>> materials(designs.size());
    for (size_t i = 0; i < designs.size(); ++i) {
      absl::StatusOr<CudaTracer::DesignScene> scene =
          replay_->MakeScene(designs[i], &bvhs[i], &materials[i]);
      if (!scene.ok()) {
        out[i] = scene.status();
        continue;
      }
      traced.push_back(i);
      scenes.push_back(*scene);
    }
    held_parts_ = 0;  // the tracer's sums are now these designs'
    for (size_t first = 0; first < scenes.size(); first += CudaTracer::kMaxReplayDesigns) {
      const size_t count = std::min<size_t>(CudaTracer::kMaxReplayDesigns, scenes.size() - first);
      CudaCounters counters;
      const absl::Status replayed = replay_->ReplayDesigns(
          {scenes.begin() + first, scenes.begin() + first + count}, &counters);
      rays_ += counters.rays;
      const std::vector<size_t> group(traced.begin() + first, traced.begin() + first + count);
      std::vector<absl::StatusOr<Result>> results =
          replayed.ok() ? take(group) : std::vector<absl::StatusOr<Result>>(count, replayed);
      for (size_t k = 0; k < count; ++k) out[group[k]] = std::move(results[k]);
    }
    return out;
  }

  // Paths per batch of a design traced in full
  std::vector<uint64_t> FullBatchPaths() const {
    return PartPaths(static_cast<uint64_t>(options_.paths_per_sensor), options_.batches,
                     kDesignParts, 0, kDesignParts);
  }

  int device_;
  CudaTracer* tracer_;
  Scene scene_;
  IndoorOptions options_;
  HemisphereBasis basis_;
  std::unique_ptr<OutdoorHolder> outdoor_;
  std::unique_ptr<CudaReplay> replay_;
  std::unique_ptr<CudaAnnualProduct> product_;
  // The replay's last design, its blinds, and how many parts of it the tracer holds
  BlindDesign held_design_;
  ReplayBlinds blinds_;
  int held_parts_ = 0;
  uint64_t rays_ = 0;
};

class CudaBackend : public DcBackend {
 public:
  CudaBackend(int device, std::unique_ptr<CudaTracer> tracer)
      : device_(device), tracer_(std::move(tracer)) {}

  std::string Name() const override { return absl::StrCat("cuda (", tracer_->device_name(), ")"); }
  int Gpu() const override { return device_; }
  int DefaultCandidatesAtOnce() const override {
    return kCandidatesPerGpu * std::max(1, CudaDevicesInUse());
  }

  absl::StatusOr<std::unique_ptr<AnnualProduct>> MakeAnnualProduct(
      const std::vector<Matrix>& outdoor_batches, const Matrix& sky) override {
    FENESTRA_ASSIGN_OR_RETURN(product, CudaAnnualProduct::Make(device_, outdoor_batches, sky, {}));
    return std::unique_ptr<AnnualProduct>(std::move(product));
  }
  absl::StatusOr<std::unique_ptr<AnnualProduct>> MakeSkyProduct(const Matrix& sky) override {
    FENESTRA_ASSIGN_OR_RETURN(product, CudaAnnualProduct::MakeSky(device_, sky));
    return std::unique_ptr<AnnualProduct>(std::move(product));
  }

  absl::StatusOr<std::unique_ptr<DesignTallies>> StartDesignTallies(
      const Scene& scene, const IndoorOptions& options) override {
    FENESTRA_ASSIGN_OR_RETURN(basis, CheckIndoorOptions(options));
    FENESTRA_ASSIGN_OR_RETURN(outdoor, MakeOutdoor(scene, options.parts, basis));
    FENESTRA_ASSIGN_OR_RETURN(replay, MaybeReplay(scene, options, basis, outdoor.get()));
    return std::make_unique<CudaDesignTallies>(device_, tracer_.get(), scene, options, basis,
                                               std::move(outdoor), std::move(replay));
  }

  // The replay where the scene has a blind and its records fit; else every design traced.
  absl::StatusOr<std::unique_ptr<IndoorStages>> MakeIndoorStages(
      const Scene& scene, const IndoorOptions& options) override {
    FENESTRA_ASSIGN_OR_RETURN(basis, CheckIndoorOptions(options));
    FENESTRA_ASSIGN_OR_RETURN(outdoor, MakeOutdoor(scene, options.parts, basis));
    FENESTRA_ASSIGN_OR_RETURN(replay, MaybeReplay(scene, options, basis, outdoor.get()));
    if (replay == nullptr) return DcBackend::MakeIndoorStages(scene, options);
    return std::make_unique<CudaReplayStages>(Name(), options, std::move(outdoor),
                                              std::move(replay));
  }

  absl::StatusOr<OneStageResult> OneStage(const TriangleMesh& mesh,
                                          const std::vector<Material>& materials,
                                          const std::vector<Sensor>& sensors,
                                          const OneStageOptions& options) override {
    const auto start = std::chrono::steady_clock::now();
    FENESTRA_RETURN_IF_ERROR(CheckOneStageInput(sensors, options));
    const Vec3d origin = OneStageFrameOrigin(sensors);
    FENESTRA_ASSIGN_OR_RETURN(geometry, PrepareTraceGeometry(mesh, materials, &origin));
    FENESTRA_RETURN_IF_ERROR(Upload(geometry));
    const std::vector<TraceSensor> local = LocalSensors(geometry, sensors);
    const int sensor_count = static_cast<int>(local.size());
    const int batches = OneStageBatches(options);
    PathSettings path = PathSettingsFor(options);
    path.importance = nullptr;

    // Trace per (sensor, batch), then fold the batches
    const size_t rows = static_cast<size_t>(sensor_count) * batches;
    std::vector<double> batch_sum(rows * kOneStageBins), batch_squares(rows * kOneStageBins);
    CudaCounters counters;
    FENESTRA_RETURN_IF_ERROR(tracer_->OneStage(
        local.data(), sensor_count, static_cast<uint64_t>(options.paths_per_sensor), batches,
        options.seed, path, batch_sum.data(), batch_squares.data(), &counters));
    OneStageTally tally;
    tally.sensor_count = sensor_count;
    tally.batches = batches;
    tally.sum.assign(sensor_count * kOneStageBins, 0.0);
    tally.sum_squares.assign(tally.sum.size(), 0.0);
    tally.sky_sum_squares.assign(sensor_count, 0.0);
    for (int s = 0; s < sensor_count; ++s) {
      for (int b = 0; b < batches; ++b) {
        for (int bin = 0; bin < kOneStageBins; ++bin) {
          const size_t k = (static_cast<size_t>(s) * batches + b) * kOneStageBins + bin;
          tally.sum[s * kOneStageBins + bin] += batch_sum[k];
          tally.sum_squares[s * kOneStageBins + bin] += batch_squares[k];
          // A path scores one bin, so its sky total's square is its bin's square
          if (IsOneStageSkyBin(bin)) tally.sky_sum_squares[s] += batch_squares[k];
        }
      }
    }
    tally.batch_sum = std::move(batch_sum);
    tally.rays = counters.rays;
    tally.branches = static_cast<uint64_t>(options.paths_per_sensor) * sensor_count;
    for (int e = 0; e < 6; ++e) tally.ends[e] = counters.ends[e];
    tally.max_weight = 1.0f;  // plain roulette: no path carries more than 1
    OneStageResult result;
    FillOneStageResult(tally, options.paths_per_sensor, options.sequence, &result);
    result.backend = Name();
    result.wall_seconds = SecondsSince(start);
    return result;
  }

  absl::StatusOr<OutdoorBatches> Outdoor(const TraceGeometry& geometry,
                                         const std::vector<TraceWindow>& windows, int window,
                                         const HemisphereBasis& basis, uint64_t paths_per_cell,
                                         int batches, uint64_t seed, const PathSettings& path,
                                         int) override {
    FENESTRA_RETURN_IF_ERROR(Upload(geometry));
    const int cells = WindowCellCount(windows[window], basis);
    OutdoorBatches o;
    o.paths_per_cell = paths_per_cell;
    CudaTracer::OutdoorOutput out;
    o.batches.reserve(batches);
    for (int b = 0; b < batches; ++b) {
      o.batches.emplace_back(OutdoorRowCount(cells), kDaylightBins);
      out.batches.push_back(o.batches.back().data());
    }
    o.mean.resize(OutdoorRowCount(cells), kDaylightBins);
    o.standard_error.resize(o.mean.rows(), o.mean.cols());
    o.first_escapes.resize(cells);
    out.mean = o.mean.data();
    out.standard_error = o.standard_error.data();
    out.first_escapes = o.first_escapes.data();
    out.batches_on_device = &o.batches_on_device.data;
    // O's matrices (44 MB on the city office), written by the download: in huge pages where
    // whole ones fit, and first touched on every core (their page faults on the download's
    // one thread took 0.02 s of a 0.03 s stage on the H200's host)
    std::vector<FreshBuffer> fresh;
    for (Matrix* m : {&o.mean, &o.standard_error}) {
      fresh.push_back({m->data(), static_cast<size_t>(m->size()) * sizeof(double)});
    }
    for (Matrix& m : o.batches) {
      fresh.push_back({m.data(), static_cast<size_t>(m.size()) * sizeof(double)});
    }
    ReadyFreshBuffers(fresh);
    CudaCounters counters;
    FENESTRA_RETURN_IF_ERROR(tracer_->Outdoor(windows, window, basis, paths_per_cell, batches, seed,
                                              WithoutImportance(path), out, &counters));
    CopyCounters(counters, &o.counters);
    o.batches_on_device.device = device_;
    return o;
  }

  absl::StatusOr<IndoorTally> Indoor(const TraceGeometry& geometry, const TraceGeometry& outdoor,
                                     const std::vector<TraceSensor>& sensors,
                                     const std::vector<TraceWindow>& windows,
                                     const HemisphereBasis& basis, uint64_t paths_per_sensor,
                                     int batches, uint64_t seed, const PathSettings& path,
                                     int) override {
    const auto start = std::chrono::steady_clock::now();
    // A room and its blind, built anew for every design of a search; the outdoor surfaces
    FENESTRA_RETURN_IF_ERROR(Upload(geometry, BvhQuality::kMedium));
    FENESTRA_ASSIGN_OR_RETURN(outdoor_bvh, BuildBvh(outdoor, BvhQuality::kHigh));
    FENESTRA_RETURN_IF_ERROR(
        tracer_->SetOutdoorScene(outdoor_bvh, OutdoorMetCells(geometry, outdoor, windows, basis)));
    outdoor_slot_.current = 0;
    IndoorTally tally = ZeroIndoorTally(static_cast<int>(sensors.size()),
                                        IndoorColumnCount(ViewOfWindows(windows, basis)), batches,
                                        paths_per_sensor);
    CudaCounters counters;
    FENESTRA_RETURN_IF_ERROR(tracer_->Indoor(
        sensors.data(), tally.sensors, windows, OutdoorOffset(geometry, outdoor), basis,
        paths_per_sensor, batches, seed, WithoutImportance(path), tally.sum.data(), &counters));
    CopyCounters(counters, &tally.counters);
    tally.wall_seconds = SecondsSince(start);
    tally.trace_seconds = counters.kernel_seconds;
    return tally;
  }

 private:
  absl::StatusOr<std::unique_ptr<OutdoorHolder>> MakeOutdoor(const Scene& scene, WindowParts parts,
                                                             const HemisphereBasis& basis) {
    FENESTRA_ASSIGN_OR_RETURN(
        outdoor, OutdoorHolder::Make(tracer_.get(), &outdoor_slot_, scene, parts, basis));
    return std::make_unique<OutdoorHolder>(std::move(outdoor));
  }

  // The replay of `scene`'s indoor paths; null for a scene without a blind, with more blinds
  // than a replay follows (ReplayFollows) or with records that would not fit the device
  // (RESOURCE_EXHAUSTED).
  absl::StatusOr<std::unique_ptr<CudaReplay>> MaybeReplay(const Scene& scene,
                                                          const IndoorOptions& options,
                                                          const HemisphereBasis& basis,
                                                          OutdoorHolder* outdoor) {
    if (!ReplayFollows(scene)) return nullptr;
    absl::StatusOr<std::unique_ptr<CudaReplay>> replay =
        CudaReplay::Make(tracer_.get(), &replay_slot_, scene, options, basis, outdoor);
    if (absl::IsResourceExhausted(replay.status())) return nullptr;
    return replay;
  }

  absl::Status Upload(const TraceGeometry& geometry, BvhQuality quality = BvhQuality::kHigh) {
    return UploadScene(*tracer_, geometry, quality);
  }

  int device_;
  std::unique_ptr<CudaTracer> tracer_;
  TracerSlot outdoor_slot_;  // outdoor scenes
  TracerSlot replay_slot_;   // indoor records
};

}  // namespace

int CudaDevices() { return CudaDeviceCount(); }

absl::StatusOr<std::unique_ptr<DcBackend>> MakeCudaBackend(int device) {
  absl::StatusOr<std::unique_ptr<CudaTracer>> tracer = CudaTracer::Create(device);
  if (!tracer.ok()) return CannotUseGpu(tracer.status());
  return std::unique_ptr<DcBackend>(std::make_unique<CudaBackend>(device, *std::move(tracer)));
}

#else

int CudaDevices() { return 0; }

absl::StatusOr<std::unique_ptr<DcBackend>> MakeCudaBackend(int) {
  return absl::UnavailableError(
      "cannot use the GPU: this build of Fenestra has no CUDA backend (nvcc was not found "
      "when it was configured)");
}

#endif

}  // namespace fenestra
