// Two-stage benchmark on the city office (bench/README.md) with the jobs' sampling
// (core/dc/two_stage.h): the outdoor stage at 2 x 10^7 paths, the indoor stage for 9 sensors
// at 2 x 10^5 paths, both with unlimited reflections, their wall times and standard errors.
// Backend: the first argument (cpu, cuda, auto).
#include <cmath>
#include <cstdio>
#include <string>

#include "bench/bench_util.h"
#include "core/dc/dc_backend.h"
#include "core/dc/indoor_replay.h"
#include "core/dc/two_stage.h"

namespace fenestra {
namespace {

std::string Reflections(int max_bounces) {
  return max_bounces < 0 ? "unlimited reflections"
                         : "at most " + std::to_string(max_bounces) + " reflections";
}

}  // namespace
}  // namespace fenestra

int main(int argc, char** argv) {
  using namespace fenestra;
  const std::string backend_name = argc > 1 ? argv[1] : "cpu";
  std::unique_ptr<DcBackend> backend = ValueOrExit(MakeBackend(backend_name));
  const Scene scene =
      ValueOrExit(LoadScene(std::string(FENESTRA_SOURCE_DIR) + "/examples/city_office/scene.json"));
  std::printf("backend: %s\n", backend->Name().c_str());

  const WindowParts parts = AutomaticWindowParts(scene.window());
  OutdoorOptions outdoor;
  outdoor.parts = parts;
  const OutdoorResult o = ValueOrExit(ComputeOutdoorStage(scene, outdoor, backend.get()));
  std::printf(
      "outdoor stage: %lld paths (%lld per cell, %dx%d window parts x %d direction cells), %s, "
      "%zu triangles: %.3f s, %.3e rays (%.3e rays/s); mean relative SE of O %.4f\n",
      static_cast<long long>(o.paths_per_cell * o.sky_view.size()),
      static_cast<long long>(o.paths_per_cell), parts.columns, parts.rows, o.basis_cells,
      Reflections(outdoor.max_bounces).c_str(), o.triangles, o.wall_seconds,
      static_cast<double>(o.rays_traced), o.rays_traced / o.wall_seconds,
      MeanRelativeError(o.coefficients.topRows(o.sky_view.size()),
                        o.standard_error.topRows(o.sky_view.size())));

  for (const double alpha : {0.0, 0.6, 1.5707963}) {
    const BlindDesign design = ValueOrExit(DesignWithOverrides(scene, {{"alpha", alpha}}));
    IndoorOptions indoor;
    indoor.parts = parts;
    const IndoorResult i = ValueOrExit(ComputeIndoorStage(scene, design, indoor, backend.get()));
    const TwoStageResult d = ValueOrExit(CombineStages(i, o));
    std::printf(
        "indoor stage, alpha %.3f: 9 sensors x 2e5 paths, %s, %zu triangles: %.3f s, %.3e "
        "closest-hit rays; mean relative SE of I %.4f, of D %.4f; sky sum of D, sensor 1: %.4e "
        "± %.1e\n",
        alpha, Reflections(indoor.max_bounces).c_str(), i.triangles, i.wall_seconds,
        static_cast<double>(i.rays_traced), MeanRelativeError(i.coefficients, i.standard_error),
        MeanRelativeError(d.coefficients, d.standard_error), d.sky_sum(0),
        d.sky_sum_standard_error(0));
  }

  // The same indoor stages replayed (core/dc/indoor_replay.h): recorded once, then per design
  IndoorOptions indoor;
  indoor.parts = parts;
  const std::unique_ptr<IndoorReplay> replay = ValueOrExit(IndoorReplay::Record(scene, indoor));
  std::printf("indoor replay: recorded in %.3f s, %.1f%% of the paths traced on per design\n",
              replay->RecordSeconds(), 100 * replay->ResumedFraction());
  for (const double alpha : {0.0, 0.6, 1.5707963}) {
    const BlindDesign design = ValueOrExit(DesignWithOverrides(scene, {{"alpha", alpha}}));
    const IndoorResult i = ValueOrExit(replay->Compute(design));
    const TwoStageResult d = ValueOrExit(CombineStages(i, o));
    std::printf(
        "indoor replay, alpha %.3f: %.3f s; mean relative SE of I %.4f, of D %.4f; sky sum of D, "
        "sensor 1: %.4e ± %.1e\n",
        alpha, i.wall_seconds, MeanRelativeError(i.coefficients, i.standard_error),
        MeanRelativeError(d.coefficients, d.standard_error), d.sky_sum(0),
        d.sky_sum_standard_error(0));
  }
  return 0;
}
