#include <algorithm>
#include <atomic>
#include <chrono>
#include <mutex>
#include <string>
#include <vector>

#include "absl/strings/escaping.h"
#include "absl/strings/numbers.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/str_split.h"
#include "core/common/status_macros.h"
#include "core/dc/backend_support.h"
#include "core/dc/dc_backend.h"
#include "core/dc/indoor_replay.h"
#include "core/dc/two_stage.h"
#include "core/trace/embree_scene.h"
#include "core/trace/one_stage_cpu.h"
#include "core/trace/trace_geometry.h"
#include "core/trace/two_stage_cpu.h"

namespace fenestra {
namespace {

class EmbreeBackend : public DcBackend {
 public:
  std::string Name() const override { return "embree-cpu"; }

  absl::StatusOr<OneStageResult> OneStage(const TriangleMesh& mesh,
                                          const std::vector<Material>& materials,
                                          const std::vector<Sensor>& sensors,
                                          const OneStageOptions& options) override {
    const auto start = std::chrono::steady_clock::now();
    FENESTRA_RETURN_IF_ERROR(CheckOneStageInput(sensors, options));
    const Vec3d origin = OneStageFrameOrigin(sensors);
    FENESTRA_ASSIGN_OR_RETURN(geometry, PrepareTraceGeometry(mesh, materials, &origin));
    FENESTRA_ASSIGN_OR_RETURN(scene, EmbreeScene::Build(geometry));

    // Learn the importance map, then trace
    OneStageSettings settings;
    settings.paths_per_sensor = static_cast<uint64_t>(options.paths_per_sensor);
    settings.seed = options.seed;
    settings.threads = options.threads;
    settings.batches = std::max(1, options.batches);
    settings.path = PathSettingsFor(options);
    const std::vector<TraceSensor> local = LocalSensors(geometry, sensors);
    const EmbreeIntersector intersector = scene->Intersector();
    ImportancePilot pilot;
    ImportanceMap map;
    if (options.weight_windows) {
      pilot = TraceImportancePilotCpu(intersector, geometry.Surfaces(), local,
                                      PilotPathsPerSensor(options, sensors.size()), options.seed,
                                      settings.path, options.threads,
                                      static_cast<float>(options.importance_cell_m));
      if (pilot.scoring_paths >= kMinPilotScoringPaths) {
        map = pilot.table.Map();
        settings.path.importance = &map;
        for (double score : pilot.mean_score) settings.window_scale.push_back(float(score));
      }
    }
    const OneStageTally tally = TraceOneStageCpu(intersector, geometry.Surfaces(), local, settings);

    // Report
    OneStageResult result;
    FillOneStageResult(tally, options.paths_per_sensor, &result);
    result.rays_traced += pilot.rays;
    result.pilot_paths = static_cast<int64_t>(pilot.paths);
    result.importance_cells = settings.path.importance ? pilot.table.CellCount() : 0;
    result.backend = Name();
    result.wall_seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    return result;
  }

  absl::StatusOr<OutdoorTally> Outdoor(const TraceGeometry& geometry, const TraceWindow& window,
                                       const HemisphereBasis& basis, uint64_t paths_per_cell,
                                       int batches, uint64_t seed, const PathSettings& path,
                                       int threads) override {
    FENESTRA_ASSIGN_OR_RETURN(scene, EmbreeScene::Build(geometry));
    return TraceOutdoorCpu(scene->Intersector(), geometry.Surfaces(), window, basis, paths_per_cell,
                           batches, seed, path, threads);
  }

  // Record the paths once, replay them per design; without a blind there is nothing to vary
  absl::StatusOr<std::unique_ptr<IndoorStages>> MakeIndoorStages(
      const Scene& scene, const IndoorOptions& options) override {
    if (!scene.blind) return DcBackend::MakeIndoorStages(scene, options);
    FENESTRA_ASSIGN_OR_RETURN(replay, IndoorReplay::Record(scene, options));
    return std::unique_ptr<IndoorStages>(std::move(replay));
  }

  absl::StatusOr<IndoorTally> Indoor(const TraceGeometry& geometry, const TraceGeometry& outdoor,
                                     const std::vector<TraceSensor>& sensors,
                                     const TraceWindow& window, const HemisphereBasis& basis,
                                     uint64_t paths_per_sensor, int batches, uint64_t seed,
                                     const PathSettings& path, int threads) override {
    FENESTRA_ASSIGN_OR_RETURN(scene, EmbreeScene::Build(geometry));
    FENESTRA_ASSIGN_OR_RETURN(outdoor_scene, EmbreeScene::Build(outdoor));
    const std::vector<uint8_t> met = OutdoorMetCells(geometry, outdoor, window, basis);
    const OutdoorView<EmbreeIntersector> view{outdoor_scene->Intersector(),
                                              OutdoorOffset(geometry, outdoor), met.data()};
    return TraceIndoorCpu(scene->Intersector(), geometry.Surfaces(), view, sensors, window, basis,
                          paths_per_sensor, batches, seed, path, threads);
  }
};

}  // namespace

std::unique_ptr<DcBackend> MakeEmbreeBackend() { return std::make_unique<EmbreeBackend>(); }

namespace {

std::mutex devices_mutex;
std::vector<int> chosen_devices;  // UseCudaDevices'; empty: every visible GPU

}  // namespace

void UseCudaDevices(std::vector<int> devices) {
  const std::lock_guard<std::mutex> lock(devices_mutex);
  chosen_devices = std::move(devices);
}

int NextCudaDevice() {
  static std::atomic<uint64_t> next{0};
  const uint64_t k = next.fetch_add(1);
  {
    const std::lock_guard<std::mutex> lock(devices_mutex);
    if (!chosen_devices.empty()) return chosen_devices[k % chosen_devices.size()];
  }
  const int count = CudaDevices();
  return count > 0 ? static_cast<int>(k % static_cast<uint64_t>(count)) : 0;
}

absl::StatusOr<std::vector<int>> ParseGpuList(const std::string& gpus, int visible) {
  std::vector<int> devices;
  if (gpus == "all") {
    for (int d = 0; d < visible; ++d) devices.push_back(d);
    return devices;
  }
  const std::string seen =
      visible > 0 ? absl::StrCat(visible, " visible: 0 to ", visible - 1) : "none visible";
  for (const absl::string_view part : absl::StrSplit(gpus, ',')) {
    int device = 0;
    if (!absl::SimpleAtoi(part, &device)) {
      return absl::InvalidArgumentError(absl::StrCat(
          "gpus must be \"all\" or comma-separated device indices such as \"0,1\", got \"",
          absl::CHexEscape(gpus), "\""));
    }
    if (device < 0 || device >= visible) {
      return absl::InvalidArgumentError(
          absl::StrCat("gpus: there is no GPU ", device, " (", seen, ")"));
    }
    if (std::find(devices.begin(), devices.end(), device) != devices.end()) {
      return absl::InvalidArgumentError(absl::StrCat("gpus: GPU ", device, " is listed twice"));
    }
    devices.push_back(device);
  }
  return devices;
}

absl::StatusOr<std::unique_ptr<DcBackend>> MakeBackend(const std::string& name) {
  if (name == "cpu") return MakeEmbreeBackend();
  if (name == "cuda") return MakeCudaBackend(NextCudaDevice());
  if (name == "auto") {
    if (CudaDevices() > 0) return MakeCudaBackend(NextCudaDevice());
    return MakeEmbreeBackend();
  }
  return absl::InvalidArgumentError("backend must be cpu, cuda or auto, got '" + name + "'");
}

}  // namespace fenestra
