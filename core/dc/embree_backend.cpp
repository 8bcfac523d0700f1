#include <algorithm>
#include <chrono>
#include <string>
#include <vector>

#include "absl/strings/str_cat.h"
#include "core/common/seconds.h"
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
    OneStageCpuRun settings;
    settings.paths_per_sensor = static_cast<uint64_t>(options.paths_per_sensor);
    settings.seed = options.seed;
    settings.threads = options.threads;
    settings.batches = OneStageBatches(options);
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
    FillOneStageResult(tally, options.paths_per_sensor, options.sequence, &result);
    result.rays_traced += pilot.rays;
    result.pilot_paths = static_cast<int64_t>(pilot.paths);
    result.importance_cells = settings.path.importance ? pilot.table.CellCount() : 0;
    result.backend = Name();
    result.wall_seconds = SecondsSince(start);
    return result;
  }

  absl::StatusOr<OutdoorBatches> Outdoor(const TraceGeometry& geometry,
                                         const std::vector<TraceWindow>& windows, int window,
                                         const HemisphereBasis& basis, uint64_t paths_per_cell,
                                         int batches, uint64_t seed, const PathSettings& path,
                                         int threads) override {
    FENESTRA_ASSIGN_OR_RETURN(scene, EmbreeScene::Build(geometry));
    return FormOutdoorBatches(TraceOutdoorCpu(scene->Intersector(), geometry.Surfaces(), windows,
                                              window, basis, paths_per_cell, batches, seed, path,
                                              threads));
  }

  // Record the paths once, replay them per design; without a blind there is nothing to vary
  absl::StatusOr<std::unique_ptr<IndoorStages>> MakeIndoorStages(
      const Scene& scene, const IndoorOptions& options) override {
    if (!ReplayFollows(scene)) {
      return DcBackend::MakeIndoorStages(scene, options);
    }
    FENESTRA_ASSIGN_OR_RETURN(replay, IndoorReplay::Record(scene, options));
    return std::unique_ptr<IndoorStages>(std::move(replay));
  }

  absl::StatusOr<IndoorTally> Indoor(const TraceGeometry& geometry, const TraceGeometry& outdoor,
                                     const std::vector<TraceSensor>& sensors,
                                     const std::vector<TraceWindow>& windows,
                                     const HemisphereBasis& basis, uint64_t paths_per_sensor,
                                     int batches, uint64_t seed, const PathSettings& path,
                                     int threads) override {
    FENESTRA_ASSIGN_OR_RETURN(scene, EmbreeScene::Build(geometry));
    FENESTRA_ASSIGN_OR_RETURN(outdoor_scene, EmbreeScene::Build(outdoor));
    const std::vector<uint8_t> met = OutdoorMetCells(geometry, outdoor, windows, basis);
    const OutdoorView<EmbreeIntersector> view{outdoor_scene->Intersector(),
                                              OutdoorOffset(geometry, outdoor), met.data()};
    return TraceIndoorCpu(scene->Intersector(), geometry.Surfaces(), view, sensors, windows, basis,
                          paths_per_sensor, batches, seed, path, threads);
  }
};

}  // namespace

std::unique_ptr<DcBackend> MakeEmbreeBackend() { return std::make_unique<EmbreeBackend>(); }

}  // namespace fenestra
