// Two-stage against one-stage across the blind's design space (bench/README.md, "Two-stage
// across the design space"), bounces unlimited in both methods: a grid of 3^4 designs of
// the city office (alpha, w, s, t at both ends and the middle of their ranges) and the
// designs named in the notes; per design and sensor the two methods' sky sums with their
// combined standard error, per design the scene's UDI of both with jackknife errors, and
// the times; then the sensor sums of one design over independent seeds of both stages,
// for the calibration of the errors (z-scores). Meant for the GPU:
//   two_stage_grid_bench [cuda|cpu] [--quick] [--seeds N] [--slats lambertian|metal|plastic]
//                        [--calibrate-only] [--indoor-only]
// --slats gives the blind's slats Radiance's metal (0.8 grey, specularity 0.9, roughness 0.05)
// or plastic (0.8, 0.05, 0.1) instead of the scene's Lambertian 0.8. --calibrate-only skips
// the grid; --indoor-only calibrates the indoor stage alone: every seed's indoor stage against
// the one outdoor stage of the grid (2e8 paths), so that the seeds' scatter is the indoor
// stage's.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <numbers>
#include <random>
#include <span>
#include <string>
#include <vector>

#include "bench/bench_util.h"
#include "core/common/seconds.h"
#include "core/dc/dc_backend.h"
#include "core/dc/one_stage.h"
#include "core/dc/two_stage.h"
#include "core/geometry/material.h"
#include "core/metrics/illuminance.h"
#include "core/metrics/metric_errors.h"
#include "core/metrics/occupancy.h"
#include "core/sky/epw.h"
#include "core/sky/sky_matrix.h"

namespace fenestra {
namespace {

const std::string kRoot = FENESTRA_SOURCE_DIR;

struct Design {
  std::string name;
  double alpha, width, spacing, thickness;
};

std::vector<Design> Designs() {
  std::vector<Design> designs = {{"optimum", 0.0, 0.13, 0.07, 0.014},
                                 {"source_tilt", 0.58, 0.15, 0.0, 0.01},
                                 {"source_tilt_open", 0.58, 0.15, 0.05, 0.02},
                                 {"thin_wide_gaps", 0.0, 0.05, 0.10, 0.01},
                                 {"shelves", std::numbers::pi / 2, 0.15, 0.0, 0.02},
                                 // The inverse experiments' answer: slits about 1 mm wide
                                 {"nearly_closed", 0.1136, 0.15, 0.0, 0.01}};
  const double pi = std::numbers::pi;
  for (double alpha : {0.0, pi / 4, pi / 2}) {
    for (double width : {0.05, 0.10, 0.15}) {
      for (double spacing : {0.0, 0.05, 0.10}) {
        for (double thickness : {0.01, 0.015, 0.02}) {
          designs.push_back({"grid", alpha, width, spacing, thickness});
        }
      }
    }
  }
  return designs;
}

struct AnnualSky {
  Matrix radiance;
  std::vector<int> columns;
  std::vector<bool> occupied;
};

AnnualSky CityOfficeSky() {
  AnnualSky s;
  const EpwData weather =
      ValueOrExit(ReadEpw(kRoot + "/examples/weather/URY_Montevideo.865800_IWEC.epw"));
  const SkyMatrix matrix = ValueOrExit(BuildSkyMatrix(weather));
  std::vector<double> hours;
  for (const SkyStep& step : matrix.steps) hours.push_back(step.hour);
  s.occupied = ValueOrExit(OccupiedSteps(hours));
  for (const int c : LitColumns(matrix.radiance)) {
    if (s.occupied[c]) s.columns.push_back(c);
  }
  s.radiance = matrix.radiance;
  return s;
}

// The scene's mean UDI [%] and its jackknife error from batches of D.
std::pair<double, double> Udi(const AnnualSky& sky, const std::vector<Matrix>& batches) {
  const AnnualMetricsEstimate m = ValueOrExit(AnnualMetricsWithErrors(
      batches, std::span<const Matrix>(&sky.radiance, 1), sky.columns, sky.occupied));
  return {m.value.scene.udi_mean_percent, m.standard_error.scene.udi_mean_percent};
}

// The command line's options.
struct Args {
  std::string backend_name = "cuda";
  bool quick = false;
  int seeds = 40;
  std::string slats = "lambertian";
  bool calibrate_only = false;
  bool indoor_only = false;
};

// The command line: the backend's name, --quick, --seeds N.
Args Parse(int argc, char** argv) {
  Args a;
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    if (arg == "--quick") {
      a.quick = true;
    } else if (arg == "--seeds" && i + 1 < argc) {
      a.seeds = std::atoi(argv[++i]);
    } else if (arg == "--slats" && i + 1 < argc) {
      a.slats = argv[++i];
    } else if (arg == "--calibrate-only") {
      a.calibrate_only = true;
    } else if (arg == "--indoor-only") {
      a.indoor_only = true;
    } else {
      a.backend_name = arg;
    }
  }
  return a;
}

// `scene` with its slats (both faces) of the finish `slats` names (Args::slats).
Scene WithSlats(Scene scene, const std::string& slats) {
  if (slats == "lambertian") return scene;
  Material m;
  if (slats == "metal") {
    m = MaterialOfKind(MaterialKind::kMetal,
                       {.colour = 0.8, .specularity = 0.9, .roughness = 0.05});
  } else if (slats == "plastic") {
    m = MaterialOfKind(MaterialKind::kPlastic,
                       {.colour = 0.8, .specularity = 0.05, .roughness = 0.1});
  } else {
    std::fprintf(stderr, "--slats: lambertian, metal or plastic, not %s\n", slats.c_str());
    std::exit(2);
  }
  m.name = "slats_" + slats;
  scene.materials.push_back(m);
  scene.blind()->material = static_cast<uint32_t>(scene.materials.size() - 1);
  scene.blind()->outer_material.reset();
  return scene;
}

// The scene's blind at design d.
BlindDesign BlindAt(const Scene& scene, const Design& d) {
  return ValueOrExit(DesignWithOverrides(scene, {{"alpha", d.alpha},
                                                 {"width", d.width},
                                                 {"spacing", d.spacing},
                                                 {"thickness", d.thickness}}));
}

// The comparison over the designs so far: every sensor's z-score, the worst differences
// and where, how many lie beyond the limits, and the summed times [s].
struct GridSummary {
  std::vector<double> z_all, udi_differences;
  double worst_z = 0, worst_relative = 0, worst_udi = 0, worst_udi_z = 0;
  std::string worst_z_at, worst_udi_at;
  int beyond_3 = 0, beyond_3_plus_1 = 0, beyond_udi = 0;
  double one_seconds = 0, two_seconds = 0;
};

// Prints design d's per-sensor columns: (two-stage / one-stage - 1) in % and in combined
// standard errors.
void CompareSensorSums(const Design& d, const OneStageResult& r, const TwoStageResult& t,
                       GridSummary* g) {
  for (Eigen::Index s = 0; s < r.sky_sum.size(); ++s) {
    const double se = std::hypot(r.sky_sum_standard_error(s), t.sky_sum_standard_error(s));
    const double z = (t.sky_sum(s) - r.sky_sum(s)) / se;
    const double relative = t.sky_sum(s) / r.sky_sum(s) - 1;
    g->z_all.push_back(z);
    if (std::abs(z) > 3) ++g->beyond_3;
    if (std::abs(t.sky_sum(s) - r.sky_sum(s)) > 3 * se + 0.01 * r.sky_sum(s)) {
      ++g->beyond_3_plus_1;
    }
    if (std::abs(z) > std::abs(g->worst_z)) {
      g->worst_z = z;
      g->worst_z_at = d.name + " S" + std::to_string(s + 1);
    }
    g->worst_relative = std::max(g->worst_relative, std::abs(relative));
    std::printf(" %+5.2f(%+4.1f)", 100 * relative, z);
  }
}

// Prints the end of design d's row: the scene's UDI of both methods with jackknife errors,
// their difference, and both methods' times [s].
void CompareUdi(const Design& d, const AnnualSky& sky, const OneStageResult& r,
                const TwoStageResult& t, double two_seconds, GridSummary* g) {
  const auto [udi_one, udi_one_se] = Udi(sky, r.batch_coefficients);
  const auto [udi_two, udi_two_se] = Udi(sky, t.batches);
  const double difference = udi_two - udi_one;
  const double udi_z = difference / std::hypot(udi_one_se, udi_two_se);
  g->udi_differences.push_back(difference);
  if (std::abs(difference) > std::abs(g->worst_udi)) {
    g->worst_udi = difference, g->worst_udi_at = d.name;
  }
  g->worst_udi_z = std::max(g->worst_udi_z, std::abs(udi_z));
  if (std::abs(difference) > 0.5) ++g->beyond_udi;
  std::printf(" | %6.2f±%.2f %6.2f±%.2f (%+.2f, %+.1f SE) | %.3f %.3f\n", udi_one, udi_one_se,
              udi_two, udi_two_se, difference, udi_z, r.wall_seconds, two_seconds);
}

// Computes design d with both methods (the two-stage one's indoor stage timed, with the
// outdoor stage o) and prints its row.
void CompareDesign(const Design& d, const Scene& scene, const AnnualSky& sky, DcBackend& backend,
                   const WindowParts& parts, int64_t one_stage_paths, int64_t indoor_paths,
                   const OutdoorResult& o, GridSummary* g) {
  const BlindDesign design = BlindAt(scene, d);
  OneStageOptions one;
  one.paths_per_sensor = one_stage_paths;
  one.max_bounces = kUnlimitedBounces;
  one.seed = 1;
  one.batches = kDefaultBatches;
  one.weight_windows = false;  // as the GPU runs it
  const OneStageResult r = ValueOrExit(ComputeOneStage(scene, design, one, &backend));
  IndoorOptions indoor;
  indoor.paths_per_sensor = indoor_paths;
  indoor.max_bounces = -1;
  indoor.parts = parts;
  indoor.seed = 3;
  const auto start = std::chrono::steady_clock::now();
  const IndoorResult i = ValueOrExit(ComputeIndoorStage(scene, design, indoor, &backend));
  const TwoStageResult t = ValueOrExit(CombineStages(i, o));
  const double two = SecondsSince(start);
  g->one_seconds += r.wall_seconds, g->two_seconds += two;
  std::printf("%-17s %5.3f %5.3f %5.3f %6.4f |", d.name.c_str(), d.alpha, d.width, d.spacing,
              d.thickness);
  CompareSensorSums(d, r, t, g);
  CompareUdi(d, sky, r, t, two, g);
}

// Prints the comparison's summary over all designs: sky sums, then UDI and the times.
void PrintGridSummary(const GridSummary& g, size_t design_count) {
  double squares = 0;
  for (const double z : g.z_all) squares += z * z;
  std::printf(
      "\n%zu designs x 9 sensors: |two / one - 1| at most %.2f%%; largest |difference| %.2f "
      "combined SE (%s); rms %.2f SE; beyond 3 SE: %d, beyond 3 SE + 1%%: %d\n",
      design_count, 100 * g.worst_relative, std::abs(g.worst_z), g.worst_z_at.c_str(),
      std::sqrt(squares / g.z_all.size()), g.beyond_3, g.beyond_3_plus_1);
  std::printf(
      "UDI: largest |two-stage - one-stage| %.2f points (%s), largest %.1f combined SE; beyond "
      "0.5 points: %d of %zu; time per design: one-stage %.3f s, two-stage indoor %.3f s\n",
      std::abs(g.worst_udi), g.worst_udi_at.c_str(), g.worst_udi_z, g.beyond_udi, design_count,
      g.one_seconds / design_count, g.two_seconds / design_count);
}

// The two-stage sky sums of one blind design and their standard errors, per seed of both
// stages (each seed a fresh outdoor and indoor stage at a job's sampling), or of the indoor
// stage alone against `fixed_outdoor` where it is given.
void SeedSums(const Scene& scene, const BlindDesign& design, DcBackend& backend,
              const OutdoorOptions& outdoor, const WindowParts& parts, bool quick, int seeds,
              const OutdoorResult* fixed_outdoor, std::vector<Eigen::VectorXd>* sums,
              std::vector<Eigen::VectorXd>* errors) {
  for (int k = 0; k < seeds; ++k) {
    OutdoorOptions out = outdoor;
    out.paths = quick ? 1'000'000 : 20'000'000;
    out.seed = 1000 + k;
    IndoorOptions in;
    in.paths_per_sensor = quick ? 20'000 : 200'000;
    in.max_bounces = -1;
    in.parts = parts;
    in.seed = 2000 + k;
    const IndoorResult ik = ValueOrExit(ComputeIndoorStage(scene, design, in, &backend));
    const TwoStageResult tk = ValueOrExit(
        fixed_outdoor != nullptr
            ? CombineStages(ik, *fixed_outdoor)
            : CombineStages(ik, ValueOrExit(ComputeOutdoorStage(scene, out, &backend))));
    sums->push_back(tk.sky_sum);
    errors->push_back(tk.sky_sum_standard_error);
  }
}

// The seeds' z-scores of the sensors' sums (sums[k](s)) against the mean over `picked` seeds
// (indices into sums, repeats allowed): per sensor the sum of z^2 with the pooled SE
// (rms over the picked seeds) into pooled[s], with each seed's own SE into own[s].
void SquaredZ(const std::vector<Eigen::VectorXd>& sums, const std::vector<Eigen::VectorXd>& errors,
              const std::vector<int>& picked, std::vector<double>* pooled,
              std::vector<double>* own) {
  const double n = static_cast<double>(picked.size());
  const double scale = n / (n - 1.0);
  for (Eigen::Index s = 0; s < sums[0].size(); ++s) {
    double mean = 0, variance = 0;
    for (const int k : picked) {
      mean += sums[k](s) / n;
      variance += errors[k](s) * errors[k](s) / n;
    }
    double p = 0, o = 0;
    for (const int k : picked) {
      const double d = sums[k](s) - mean;
      p += d * d / variance * scale;
      o += d * d / (errors[k](s) * errors[k](s)) * scale;
    }
    (*pooled)[s] = p, (*own)[s] = o;
  }
}

// Prints design d's calibration line: per sensor the SD of the seeds' z-scores against the
// pooled SE, then over all sensors with the pooled and with each seed's own SE, and the
// pooled SD's 95% interval from 2000 bootstrap resamples of the seeds (which keeps the
// sensors' correlation through the shared stages).
void PrintSeedZScores(const Design& d, const std::vector<Eigen::VectorXd>& sums,
                      const std::vector<Eigen::VectorXd>& errors, int seeds) {
  const size_t sensors = static_cast<size_t>(sums[0].size());
  std::vector<double> pooled(sensors), own(sensors);
  std::vector<int> all(seeds);
  for (int k = 0; k < seeds; ++k) all[k] = k;
  SquaredZ(sums, errors, all, &pooled, &own);
  double pooled_all = 0, own_all = 0;
  std::printf("%-17s per sensor z SD:", d.name.c_str());
  for (size_t s = 0; s < sensors; ++s) {
    std::printf(" %.2f", std::sqrt(pooled[s] / seeds));
    pooled_all += pooled[s], own_all += own[s];
  }
  const double count = static_cast<double>(seeds * sensors);
  std::mt19937_64 random(7);
  std::uniform_int_distribution<int> pick(0, seeds - 1);
  std::vector<double> resampled;
  std::vector<int> picked(seeds);
  std::vector<double> p(sensors), o(sensors);
  for (int r = 0; r < 2000; ++r) {
    for (int& k : picked) k = pick(random);
    SquaredZ(sums, errors, picked, &p, &o);
    double total = 0;
    for (const double v : p) total += v;
    resampled.push_back(std::sqrt(total / count));
  }
  std::sort(resampled.begin(), resampled.end());
  std::printf("; all: %.3f [%.3f, %.3f] (own SE: %.3f), %.0f z-scores\n",
              std::sqrt(pooled_all / count), resampled[50], resampled[1949],
              std::sqrt(own_all / count), count);
}

// Calibration: sky sums over independent seeds of both stages, at a job's sampling, for
// three of the named designs.
void Calibrate(const Scene& scene, const std::vector<Design>& designs, DcBackend& backend,
               const OutdoorOptions& outdoor, const WindowParts& parts, bool quick, int seeds,
               const OutdoorResult* fixed_outdoor) {
  std::printf(
      "\nsky sums over %d seeds of %s (outdoor 2e7 paths, indoor 2e5 paths per sensor, "
      "unlimited bounces, 8 batches): z = (x_k - mean) / rms(SE_k) x sqrt(K / (K - 1)); and "
      "with each seed's own SE; [95%% bootstrap interval over the seeds]\n",
      seeds,
      fixed_outdoor != nullptr ? "the indoor stage, against one outdoor stage of 2e8 paths"
                               : "both stages");
  for (const Design& d : {designs[0], designs[1], designs[4]}) {
    const BlindDesign design = BlindAt(scene, d);
    std::vector<Eigen::VectorXd> sums, errors;
    SeedSums(scene, design, backend, outdoor, parts, quick, seeds, fixed_outdoor, &sums, &errors);
    PrintSeedZScores(d, sums, errors, seeds);
  }
}

}  // namespace
}  // namespace fenestra

int main(int argc, char** argv) {
  using namespace fenestra;
  const Args args = Parse(argc, argv);
  const bool quick = args.quick;
  std::unique_ptr<DcBackend> backend = ValueOrExit(MakeBackend(args.backend_name));
  const Scene scene =
      WithSlats(ValueOrExit(LoadScene(kRoot + "/examples/city_office/scene.json")), args.slats);
  const AnnualSky sky = CityOfficeSky();
  const WindowParts parts = AutomaticWindowParts(scene.window());
  const int64_t one_stage_paths = quick ? 200'000 : 10'000'000;
  const int64_t outdoor_paths = quick ? 2'000'000 : 200'000'000;
  const int64_t indoor_paths = quick ? 200'000 : 2'000'000;
  std::printf(
      "backend: %s\ncity office, slats %s, bounces unlimited (roulette) in both methods; one-stage "
      "%lld "
      "paths per sensor (plain roulette, threshold 0.25, 8 batches); two-stage: outdoor %lld "
      "paths once for all designs, indoor %lld paths per sensor, %dx%d window parts x 288 "
      "direction cells, 8 batches paired\n",
      backend->Name().c_str(), args.slats.c_str(), static_cast<long long>(one_stage_paths),
      static_cast<long long>(outdoor_paths), static_cast<long long>(indoor_paths), parts.columns,
      parts.rows);

  OutdoorOptions outdoor;
  outdoor.paths = outdoor_paths;
  outdoor.max_bounces = -1;
  outdoor.parts = parts;
  outdoor.seed = 2;
  const OutdoorResult o = ValueOrExit(ComputeOutdoorStage(scene, outdoor, backend.get()));
  std::printf("outdoor stage: %.3f s\n\n", o.wall_seconds);

  // Per design and sensor
  std::printf(
      "%-17s %5s %5s %5s %6s | per sensor: (two-stage / one-stage - 1) in %% and in combined SE "
      "| UDI one-stage, two-stage [%%] | s one, two\n",
      "design", "alpha", "w", "s", "t");
  const std::vector<Design> designs = Designs();
  if (!args.calibrate_only) {
    GridSummary summary;
    for (const Design& d : designs) {
      CompareDesign(d, scene, sky, *backend, parts, one_stage_paths, indoor_paths, o, &summary);
    }
    PrintGridSummary(summary, designs.size());
  }
  Calibrate(scene, designs, *backend, outdoor, parts, quick, args.seeds,
            args.indoor_only ? &o : nullptr);
  return 0;
}
