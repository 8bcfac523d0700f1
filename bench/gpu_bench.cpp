// GPU benchmarks (bench/README.md): rays per second on the lightwell and the city office,
// the lightwell 3 x 10^7-path case, the city-office outdoor stage, one candidate
// evaluation and the 500-evaluation four-variable optimization. Needs a CUDA device.
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>

#include "absl/strings/str_format.h"
#include "bench/bench_util.h"
#include "core/common/seconds.h"
#include "core/dc/backend_support.h"
#include "core/dc/dc_backend.h"
#include "core/dc/indoor_replay.h"
#include "core/dc/one_stage.h"
#include "core/dc/two_stage.h"
#include "core/metrics/illuminance.h"
#include "core/metrics/metric_errors.h"
#include "core/metrics/occupancy.h"
#include "core/optimize/job.h"
#include "core/sky/epw.h"
#include "core/sky/sky_matrix.h"
#include "core/trace/bvh.h"
#include "core/trace/bvh_intersector.h"
#include "core/trace/cuda/cuda_tracer.h"
#include "core/trace/trace_geometry.h"

namespace fenestra {
namespace {

const std::string kRoot = FENESTRA_SOURCE_DIR;

void OneStage(DcBackend& gpu, const std::string& name, const BlindDesign* design, int64_t paths,
              int bounces) {
  const Scene scene = ValueOrExit(LoadScene(kRoot + "/examples/" + name + "/scene.json"));
  OneStageOptions options;
  options.paths_per_sensor = paths;
  options.max_bounces = bounces;
  options.weight_windows = false;
  const BlindDesign d = design ? *design : DefaultDesign(scene);
  ValueOrExit(ComputeOneStage(scene, d, options, &gpu));  // warm-up
  const OneStageResult r = ValueOrExit(ComputeOneStage(scene, d, options, &gpu));
  std::printf(
      "one-stage %-12s %zu sensors x %lld paths, %d bounces: %.4f s, %.3e rays, %.2f G rays/s, "
      "mean relative SE %.4f, sky sums",
      name.c_str(), scene.sensors.size(), static_cast<long long>(paths), bounces, r.wall_seconds,
      static_cast<double>(r.rays_traced), r.rays_traced / r.wall_seconds / 1e9,
      MeanRelativeStandardError(r));
  for (Eigen::Index i = 0; i < r.sky_sum.size(); ++i) {
    std::printf(" %.4e±%.1e", r.sky_sum(i), r.sky_sum_standard_error(i));
  }
  std::printf("\n");
}

// Records every closest-hit query of the paths it serves.
struct RecordingIntersector {
  const BvhIntersector* scene;
  std::vector<Vec3f>* origins;
  std::vector<Vec3f>* directions;
  bool Intersect(Vec3f origin, Vec3f direction, SurfaceHit* hit) const {
    origins->push_back(origin);
    directions->push_back(direction);
    return scene->Intersect(origin, direction, hit);
  }
  bool Occluded(Vec3f origin, Vec3f direction, float distance) const {
    return scene->Occluded(origin, direction, distance);
  }
};

struct NoSink {
  void Add(int, double) {}
  void EndPath() {}
};

// The traversal alone, on the rays of one-stage paths (recorded on the CPU, 30 bounces):
// each lane its own ray, then every lane of a warp the same ray, which takes divergence and
// scattered reads away and leaves the instructions a ray costs.
void TraversalAlone(const std::string& name, const BlindDesign* design) {
  const Scene scene = ValueOrExit(LoadScene(kRoot + "/examples/" + name + "/scene.json"));
  const TraceGeometry geometry = ValueOrExit(PrepareTraceGeometry(
      AssembleMesh(scene, design ? *design : DefaultDesign(scene)), scene.materials));
  const BvhLayout bvh = ValueOrExit(BuildBvh(geometry));
  const BvhIntersector cpu{bvh.nodes.data(), bvh.triangles.data()};
  std::vector<Vec3f> origins, directions;
  const RecordingIntersector recorder{&cpu, &origins, &directions};
  OneStageOptions options;
  options.max_bounces = 30;
  const PathSettings settings = PathSettingsFor(options);
  const std::vector<TraceSensor> sensors = LocalSensors(geometry, scene.sensors);
  NoSink sink;
  for (uint64_t p = 0; origins.size() < 4'000'000; ++p) {
    for (size_t s = 0; s < sensors.size(); ++s) {
      OneStageMode<NoSink> mode{sensors[s].position, sensors[s].normal, &sink};
      TracePath<RecordingIntersector, OneStageMode<NoSink>, 0>(
          recorder, geometry.Surfaces(), settings, PathRandom(1, static_cast<uint32_t>(s), p),
          mode);
    }
  }
  absl::StatusOr<std::unique_ptr<CudaTracer>> tracer = CudaTracer::Create(0);
  absl::Status status = tracer.status();
  if (status.ok()) {
    status = (*tracer)->SetScene(bvh, geometry.triangle_material.data(),
                                 geometry.triangle_material.size(), geometry.materials.data(),
                                 geometry.materials.size());
  }
  if (!status.ok()) {
    std::printf("traversal alone: %s\n", status.ToString().c_str());
    return;
  }
  std::vector<float> distance(origins.size());
  double seconds[2] = {};
  for (const bool same : {false, true}) {
    for (int run = 0; run < 2; ++run) {  // the first warms up
      const absl::Status e = (*tracer)->IntersectRays(
          origins.data(), directions.data(), origins.size(), same, distance.data(), &seconds[same]);
      if (!e.ok()) std::printf("traversal alone: %s\n", e.ToString().c_str());
    }
  }
  std::printf(
      "traversal alone, %-12s %zu triangles, %zu recorded path rays: %.2f G rays/s; every lane "
      "of a warp on the same ray: %.2f G rays/s\n",
      name.c_str(), geometry.TriangleCount(), origins.size(), origins.size() / seconds[0] / 1e9,
      origins.size() / seconds[1] / 1e9);
}

// The city-office outdoor stage with the jobs' sampling (core/dc/two_stage.h), after a
// warm-up: prints its paths, time and rays per second.
OutdoorResult TimeOutdoorStage(DcBackend& gpu, const Scene& office, const OutdoorOptions& outdoor) {
  ValueOrExit(ComputeOutdoorStage(office, outdoor, &gpu));
  const OutdoorResult o = ValueOrExit(ComputeOutdoorStage(office, outdoor, &gpu));
  std::printf(
      "outdoor stage: %lld paths, %d bounces (-1: unlimited), %dx%d window parts: %.4f s, "
      "%.3e rays, %.2f G rays/s\n",
      static_cast<long long>(o.paths_per_cell * o.sky_view.size()), outdoor.max_bounces,
      outdoor.parts.columns, outdoor.parts.rows, o.wall_seconds, static_cast<double>(o.rays_traced),
      o.rays_traced / o.wall_seconds / 1e9);
  return o;
}

// Montevideo's sky over the lit occupied hours, as a job analyses it.
struct AnalysedSky {
  std::vector<bool> occupied;  // per sky step
  size_t hours = 0;            // the lit occupied hours
  Matrix matrix;               // kDaylightBins x hours: each hour's radiance x white efficacy
};

// Reads the weather and builds the analysed sky.
AnalysedSky MontevideoAnalysedSky() {
  const EpwData weather =
      ValueOrExit(ReadEpw(kRoot + "/examples/weather/URY_Montevideo.865800_IWEC.epw"));
  const SkyMatrix sky = ValueOrExit(BuildSkyMatrix(weather));
  std::vector<double> hours;
  for (const SkyStep& step : sky.steps) hours.push_back(step.hour);
  AnalysedSky a;
  a.occupied = ValueOrExit(OccupiedSteps(hours));
  std::vector<int> analysed;
  for (const int c : LitColumns(sky.radiance)) {
    if (a.occupied[c]) analysed.push_back(c);
  }
  a.hours = analysed.size();
  a.matrix = Matrix(kDaylightBins, static_cast<Eigen::Index>(analysed.size()));
  for (size_t c = 0; c < analysed.size(); ++c) {
    a.matrix.col(c) = kWhiteEfficacyLumensPerWatt * sky.radiance.col(analysed[c]);
  }
  return a;
}

constexpr int kCandidates = 20;

// Candidate c of the timed evaluations (0 is the warm-up).
BlindDesign Candidate(const Scene& office, int c) {
  return ValueOrExit(DesignWithOverrides(
      office, {{"alpha", 0.05 * c}, {"width", 0.10 + 0.002 * c}, {"spacing", 0.002 * c}}));
}

// The candidate evaluation's times [s] summed over the candidates, its parts' rays, and the
// last candidate's UDI [%].
struct CandidateTimes {
  double record = 0;  // the room's paths recorded once per job
  double total = 0, kernel = 0, prepare = 0, build = 0, full_kernel = 0;
  uint64_t rays = 0, full_rays = 0;
  double udi = 0, udi_se = 0;
};

// The room's paths recorded once, as a job does for its candidates; the seconds that took.
std::unique_ptr<DesignTallies> RecordDesignTallies(DcBackend& gpu, const Scene& office,
                                                   const IndoorOptions& indoor,
                                                   const OutdoorResult& o, const AnalysedSky& sky,
                                                   double* seconds) {
  auto recording = std::chrono::steady_clock::now();
  std::unique_ptr<DesignTallies> design_tallies =
      ValueOrExit(gpu.MakeDesignTallies(office, indoor, o.batches, sky.matrix));
  *seconds = SecondsSince(recording);
  return design_tallies;
}

// One candidate as a job evaluates it: the indoor stage, then the tallies of
// E_b = (I_b O_b) S over the lit occupied hours (formed and reduced on the GPU), then UDI with
// its jackknife error; timed over the candidates after a warm-up.
void TimeCandidates(DesignTallies& design_tallies, const Scene& office, const AnalysedSky& sky,
                    CandidateTimes* times) {
  const MetricOptions metric_options;
  const int analysed_hours = AnalysedHours(sky.occupied, metric_options.hours);
  for (int c = 0; c <= kCandidates; ++c) {
    const BlindDesign design = Candidate(office, c);
    const auto start = std::chrono::steady_clock::now();
    const std::vector<HourTally> tallies =
        ValueOrExit(design_tallies.Tally(design, metric_options));
    const AnnualMetricsEstimate m =
        ValueOrExit(AnnualMetricsFromTallies(tallies, analysed_hours, metric_options));
    if (c == 0) continue;  // warm-up
    times->total += SecondsSince(start);
    times->udi = m.value.scene.udi_mean_percent;
    times->udi_se = m.standard_error.scene.udi_mean_percent;
  }
}

// The candidates' parts, after the candidates as a job evaluates them: the replay kernel (the
// indoor stage alone, from the records), the design's slats put beside the room's BVH (and
// what a build of the room with the blind's mesh would take instead); and the kernel of the
// same stage traced in full
void TimeCandidateParts(DcBackend& gpu, IndoorStages& stages, const Scene& office,
                        const IndoorOptions& indoor, CandidateTimes* times) {
  const TraceGeometry room =
      ValueOrExit(PrepareTraceGeometry(SelectSide(office.fixed, Side::kIndoor), office.materials));
  const BvhLayout room_bvh = ValueOrExit(BuildBvh(room));
  for (int c = 1; c <= kCandidates; ++c) {
    const BlindDesign design = Candidate(office, c);
    const IndoorResult i = ValueOrExit(stages.Compute(design));
    const IndoorResult full = ValueOrExit(ComputeIndoorStage(office, design, indoor, &gpu));
    const auto host = std::chrono::steady_clock::now();
    BvhWithSlats(room_bvh, LocalSlatCorners(room, office, design),
                 static_cast<uint32_t>(room.TriangleCount()));
    times->prepare += SecondsSince(host);
    const auto built = std::chrono::steady_clock::now();
    const TraceGeometry geometry = ValueOrExit(PrepareTraceGeometry(
        SelectSide(AssembleMesh(office, design), Side::kIndoor), office.materials));
    ValueOrExit(BuildBvh(geometry, BvhQuality::kMedium));
    times->build += SecondsSince(built);
    times->kernel += i.trace_seconds;
    times->rays += i.rays_traced;
    times->full_kernel += full.trace_seconds;
    times->full_rays += full.rays_traced;
  }
}

// Prints the candidate evaluation's time per candidate, its parts', and the last UDI.
void PrintCandidateTimes(const CandidateTimes& t, const IndoorOptions& indoor, size_t hours) {
  std::printf(
      "candidate evaluation (9 sensors x 2e5 paths, %d bounces (-1: unlimited), D S over %zu "
      "hours, UDI): %.2f ms (the replay kernel %.2f ms, %.2f G queries/s: closest hits and "
      "connection tests against the slats alone; the design's slats beside the room's BVH "
      "%.3f ms (a build of the room with the blind's mesh: %.3f ms); the rest uploads, "
      "E = (I_b O_b) S, its tallies and the metrics); last UDI %.2f ± %.2f %%\n"
      "  the room's paths recorded once per job: %.1f ms; traced in full, a candidate's kernel "
      "would take %.2f ms (%.2f G closest-hit rays/s)\n",
      indoor.max_bounces, hours, 1e3 * t.total / kCandidates, 1e3 * t.kernel / kCandidates,
      t.rays / t.kernel / 1e9, 1e3 * t.prepare / kCandidates, 1e3 * t.build / kCandidates, t.udi,
      t.udi_se, 1e3 * t.record, 1e3 * t.full_kernel / kCandidates,
      t.full_rays / t.full_kernel / 1e9);
}

// Is one candidate enough to fill the GPU? The same design with 4 and 16 times the paths
// (as if that many candidates shared a launch)
void IndoorAtMorePaths(DcBackend& gpu, const Scene& office, const BlindDesign& open,
                       const IndoorOptions& indoor) {
  for (const int64_t scale : {4, 16}) {
    IndoorOptions more = indoor;
    more.paths_per_sensor = indoor.paths_per_sensor * scale;
    const IndoorResult i = ValueOrExit(ComputeIndoorStage(office, open, more, &gpu));
    std::printf("indoor stage at %lld x the paths: kernel %.2f ms, %.2f G closest-hit rays/s\n",
                static_cast<long long>(scale), 1e3 * i.trace_seconds,
                i.rays_traced / i.trace_seconds / 1e9);
  }
}

// Prints the optimization's result: evaluations, the time of each stage, the best design
// with its UDI and the final check; `start` is when the job began.
void PrintOptimization(const v1::JobResult& result, const std::string& stage_starts,
                       std::chrono::steady_clock::time_point start) {
  const v1::Timings& t = result.timings();
  const v1::FinalCheck& check = result.final_check();
  std::printf(
      "optimization: %d evaluations (%s; %d designs at once, %d evaluated ahead "
      "and dropped) in %.2f s (sky %.2f s, outdoor %.2f s, "
      "evaluations %.2f s, best design's hourly illuminance %.2f s, final check %.2f s with "
      "%lld + %lld paths per sensor, the rest %.2f s); best UDI %.2f ± %.2f %% (check %.2f ± "
      "%.2f %%) at",
      result.evaluations(), result.stop_reason().c_str(), result.candidates_at_once(),
      result.evaluations_discarded(), SecondsSince(start), t.sky_seconds(), t.outdoor_seconds(),
      t.evaluation_seconds(), t.best_hourly_seconds(), check.seconds(),
      static_cast<long long>(check.pilot_paths_per_sensor()),
      static_cast<long long>(check.paths_per_sensor()),
      t.total_seconds() - t.sky_seconds() - t.outdoor_seconds() - t.evaluation_seconds() -
          t.best_hourly_seconds() - check.seconds(),
      result.best_value().value(), result.best_value().standard_error(), check.one_stage().value(),
      check.one_stage().standard_error());
  for (const char* name : {"alpha", "width", "spacing", "thickness"}) {
    const auto value = result.best_design().find(name);
    if (value != result.best_design().end()) std::printf(" %s=%.4f", name, value->second);
  }
  std::printf("\nstages began at (s):%s; ended %.3f\n", stage_starts.c_str(), SecondsSince(start));
  std::printf("final check: difference %+.2f ± %.2f %%%s\n", check.difference().value(),
              check.difference().standard_error(), check.disagrees() ? " DISAGREES" : "");
}

// The job `path` (relative to the repository; by default the 500-evaluation four-variable
// optimization), end to end, with the time each of its stages began.
void FourVariableOptimization(
    const std::string& path = "examples/city_office/four_variables.json") {
  v1::Job job = ValueOrExit(ReadJobFile(kRoot + "/" + path));
  job.mutable_sampling()->set_backend("cuda");
  const std::string folder = kRoot + "/" + path.substr(0, path.rfind('/'));
  const PreparedJob prepared = ValueOrExit(PrepareJob(job, folder));
  const auto start = std::chrono::steady_clock::now();
  std::string stage_starts;  // when each stage began [s]
  JobCallbacks callbacks;
  callbacks.stage = [&](const std::string& stage) {
    stage_starts += absl::StrFormat(" %s %.3f", stage, SecondsSince(start));
  };
  const v1::JobResult result = ValueOrExit(RunJob(prepared, nullptr, callbacks));
  PrintOptimization(result, stage_starts, start);
}

}  // namespace
}  // namespace fenestra

int main(int argc, char** argv) {
  const std::string mode = argc > 1 ? argv[1] : "";
  const bool quick = mode == "quick";
  using namespace fenestra;
  std::unique_ptr<DcBackend> gpu = ValueOrExit(MakeCudaBackend(0));
  std::printf("device: %s\n", gpu->Name().c_str());
  if (mode == "job") {
    // The four-variable job (or the job file given after the count), `runs` times after one
    // run that loads the kernels
    const int runs = argc > 2 ? std::max(1, std::atoi(argv[2])) : 3;
    const std::string path = argc > 3 ? argv[3] : "examples/city_office/four_variables.json";
    std::printf("job %s; first run (loads the kernels):\n", path.c_str());
    for (int r = 0; r <= runs; ++r) FourVariableOptimization(path);
    return 0;
  }

  // Rays per second and the lightwell reference case (Radiance -ab 30 = 29 reflections)
  OneStage(*gpu, "lightwell", nullptr, 10'000'000, 29);
  OneStage(*gpu, "lightwell", nullptr, 10'000'000, 4);
  const Scene office = ValueOrExit(LoadScene(kRoot + "/examples/city_office/scene.json"));
  const BlindDesign open =
      ValueOrExit(DesignWithOverrides(office, {{"alpha", 0.6}, {"spacing", 0.05}}));
  OneStage(*gpu, "city_office", &open, 2'000'000, 30);
  TraversalAlone("lightwell", nullptr);
  TraversalAlone("city_office", &open);

  // The window in its default parts (4 x 3), as jobs trace it
  OutdoorOptions outdoor;
  outdoor.parts = AutomaticWindowParts(office.window());
  const OutdoorResult o = TimeOutdoorStage(*gpu, office, outdoor);

  // The candidates, then their parts (the recorded paths and the replayed stages are held
  // until the program ends)
  const AnalysedSky sky = MontevideoAnalysedSky();
  IndoorOptions indoor;
  indoor.parts = outdoor.parts;
  CandidateTimes times;
  const std::unique_ptr<DesignTallies> design_tallies =
      RecordDesignTallies(*gpu, office, indoor, o, sky, &times.record);
  TimeCandidates(*design_tallies, office, sky, &times);
  const std::unique_ptr<IndoorStages> stages = ValueOrExit(gpu->MakeIndoorStages(office, indoor));
  TimeCandidateParts(*gpu, *stages, office, indoor, &times);
  PrintCandidateTimes(times, indoor, sky.hours);

  IndoorAtMorePaths(*gpu, office, open, indoor);

  if (quick) return 0;
  FourVariableOptimization();
  return 0;
}
