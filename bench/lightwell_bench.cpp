// The lightwell daylight-coefficient case: speed, error and efficiency against Radiance.
// Usage: lightwell_bench [all|roulette|main|table|seeds]... [--quick] [--threads N]
//   roulette  path-termination strategies compared by variance x time (29, 4, unlimited)
//   main      3 sensors x 10^7 paths at 29 and 4 reflections (Radiance -ab 30 and -ab 5)
//   table     error against time for 10^3 .. 10^7 paths per sensor (29 reflections)
//   seeds     between-seed differences as in Radiance's campaign TSV, and Q
// See bench/README.md for what the numbers mean.
#include <sys/resource.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <fstream>
#include <string>
#include <thread>
#include <vector>

#include "bench/bench_util.h"
#include "core/common/radiance_matrix.h"
#include "core/dc/one_stage.h"
#include "core/geometry/scene.h"

namespace fenestra {
namespace {

const std::string kSourceDir = FENESTRA_SOURCE_DIR;

// Radiance 6.1a on the 2-core reference machine (tests/data/reference/README.md and
// lightwell_radiance_campaign.tsv): seconds per path (all 3 sensors) at -ab 30 (at -ab 5:
// 69.999 s per 10^7 paths), and the relative variance of one path's sky sum per sensor,
// c = N (sigma / mean)^2, pooled from the between-seed pairs at 10^5, 10^6 and the two 10^7
// halves of the reference.
constexpr double kRadianceSecondsPerPath30 = 369.413 / 1e7;
constexpr double kRadianceC30[3] = {47.4, 58.3, 777.1};

struct Bench {
  Scene scene;
  Matrix reference30, reference5;
  int threads = 0;
  bool quick = false;
};

// CPU seconds this process has used (all threads).
double CpuSeconds() {
  rusage usage;
  getrusage(RUSAGE_SELF, &usage);
  return usage.ru_utime.tv_sec + usage.ru_stime.tv_sec +
         1e-6 * (usage.ru_utime.tv_usec + usage.ru_stime.tv_usec);
}

double LoadAverage() {
  double load = 0;
  std::ifstream("/proc/loadavg") >> load;
  return load;
}

struct Run {
  OneStageResult result;
  double cpu_seconds = 0;       // CPU time of the run, all threads
  double seconds_per_path = 0;  // wall time / paths per sensor (all sensors together)
  double c[3] = {0, 0, 0};      // per sensor: N (SE / sum)^2
  double mean_relative_difference = 0;
  double mean_relative_se = 0;
};

double MeanRelativeDifference(const Matrix& ours, const Matrix& reference) {
  double total = 0;
  int count = 0;
  for (int s = 0; s < reference.rows(); ++s) {
    const double row_max = reference.row(s).maxCoeff();
    for (int b = 1; b < reference.cols(); ++b) {
      if (reference(s, b) > 0.01 * row_max) {
        total += std::fabs(ours(s, b) - reference(s, b)) / reference(s, b);
        ++count;
      }
    }
  }
  return total / count;
}

double SkySum(const Matrix& m, int row) { return m.row(row).tail(m.cols() - 1).sum(); }

// How a run ends its paths.
struct Strategy {
  bool roulette = true;
  double threshold = OneStageOptions{}.roulette_threshold;
  bool weight_windows = OneStageOptions{}.weight_windows;
};

Run Trace(const Bench& bench, int64_t paths, int max_bounces, const Strategy& strategy,
          uint64_t seed, const Matrix* reference) {
  OneStageOptions options;
  options.paths_per_sensor = paths;
  options.max_bounces = max_bounces;
  options.russian_roulette = strategy.roulette;
  options.roulette_threshold = strategy.threshold;
  options.weight_windows = strategy.weight_windows;
  options.seed = seed;
  options.threads = bench.threads;
  const double cpu_start = CpuSeconds();
  OneStageResult result =
      ValueOrExit(ComputeOneStage(bench.scene, DefaultDesign(bench.scene), options));
  const double cpu_seconds = CpuSeconds() - cpu_start;
  Run run;
  run.result = std::move(result);
  run.cpu_seconds = cpu_seconds;
  run.seconds_per_path = run.result.wall_seconds / paths;
  for (int s = 0; s < 3; ++s) {
    const double rel = run.result.sky_sum_standard_error(s) / run.result.sky_sum(s);
    run.c[s] = paths * rel * rel;
  }
  if (reference != nullptr) {
    run.mean_relative_difference = MeanRelativeDifference(run.result.coefficients, *reference);
  }
  run.mean_relative_se = MeanRelativeStandardError(run.result);
  return run;
}

void PrintMachine(const Bench& bench) {
  std::string model = "unknown";
  std::ifstream cpuinfo("/proc/cpuinfo");
  for (std::string line; std::getline(cpuinfo, line);) {
    if (line.rfind("model name", 0) == 0) {
      model = line.substr(line.find(':') + 2);
      break;
    }
  }
  char date[64];
  const std::time_t now = std::time(nullptr);
  std::strftime(date, sizeof(date), "%Y-%m-%d %H:%M:%S %Z", std::localtime(&now));
  std::printf("machine: %s, %u hardware threads; threads used: %d; %s; load average %.2f\n",
              model.c_str(), std::thread::hardware_concurrency(), bench.threads, date,
              LoadAverage());
}

// Seconds per path (3 sensors) charged to a run: its wall time, or when the machine was
// shared (other processes competing for the cores) its CPU time spread over our threads.
double ChargedSecondsPerPath(const Bench& bench, const Run& r) {
  return std::min(r.result.wall_seconds, r.cpu_seconds / bench.threads) / r.result.paths_per_sensor;
}

std::string StrategyName(const Strategy& s) {
  char name[64];
  if (s.weight_windows) {
    std::snprintf(name, sizeof(name), "windows");
  } else if (s.roulette) {
    std::snprintf(name, sizeof(name), "T=%g", s.threshold);
  } else {
    std::snprintf(name, sizeof(name), "off");
  }
  return name;
}

// Russian roulette strategies: threshold T means a path whose weight falls below T survives
// with probability weight / T and carries T on (T = 1: survive with the reflectance);
// "windows" = weight windows from a pilot-learned importance map (pilot included).
void Roulette(const Bench& bench) {
  const int64_t paths = bench.quick ? 200000 : 1000000;
  std::vector<Strategy> strategies;
  for (double t : {1.0, 0.5, 0.25, 0.1, 0.05, 0.02, 0.005}) strategies.push_back({true, t, false});
  strategies.push_back({false, 1.0, false});
  strategies.push_back({true, 0.25, true});
  for (int bounces : {29, 4, kUnlimitedBounces}) {
    std::printf(
        "\n## Path termination at %s, %lld paths per sensor, seed 7\n",
        bounces >= 0 ? (std::to_string(bounces) + " reflections").c_str() : "unlimited reflections",
        static_cast<long long>(paths));
    std::printf("%-9s %8s %8s %9s %9s %9s %9s %11s\n", "strategy", "wall s", "cpu s", "rays/path",
                "c(S1)", "c(S2)", "c(S3)", "efficiency");
    double base = 0;
    for (const Strategy& strategy : strategies) {
      if (bounces < 0 && !strategy.roulette) continue;
      const Run r = Trace(bench, paths, bounces, strategy, 7, nullptr);
      // Efficiency: 1 / (seconds per path x relative variance per path), mean over the
      // sensors, relative to the first row
      double e = 0;
      for (int s = 0; s < 3; ++s) e += 1 / (ChargedSecondsPerPath(bench, r) * r.c[s]) / 3;
      if (base == 0) base = e;
      std::printf("%-9s %8.2f %8.2f %9.2f %9.1f %9.1f %9.1f %11.2f\n",
                  StrategyName(strategy).c_str(), r.result.wall_seconds, r.cpu_seconds,
                  double(r.result.rays_traced) / (3.0 * paths), r.c[0], r.c[1], r.c[2], e / base);
      std::fflush(stdout);
    }
  }
}

void Main(const Bench& bench) {
  const int64_t paths = bench.quick ? 1000000 : 10000000;
  for (int bounces : {29, 4}) {
    const Matrix& reference = bounces == 29 ? bench.reference30 : bench.reference5;
    const Run r = Trace(bench, paths, bounces, Strategy{}, 1, &reference);
    const OneStageResult& res = r.result;
    const double seconds = ChargedSecondsPerPath(bench, r) * paths;
    const double rays_per_second = res.rays_traced / seconds;
    std::printf("\n## %d reflections (Radiance -ab %d), 3 sensors x %lld paths, default options\n",
                bounces, bounces + 1, static_cast<long long>(paths));
    std::printf(
        "wall %.2f s, CPU %.2f s (charged %.2f s); %llu rays (%.2f per path, pilot "
        "included), %.3g rays/s = %.3g rays/s per core (plain Embree yardstick: 1.24e7 "
        "on 2 threads = 6.2e6 per core)\n",
        res.wall_seconds, r.cpu_seconds, seconds, static_cast<unsigned long long>(res.rays_traced),
        double(res.rays_traced) / (3.0 * paths), rays_per_second, rays_per_second / res.threads);
    std::printf(
        "pilot %lld paths, %zu importance cells; branches %.2f per path; escaped %llu, "
        "roulette %llu, bounce limit %llu, truncated %llu; max path weight %.3g\n",
        static_cast<long long>(res.pilot_paths), res.importance_cells,
        double(res.branches) / (3.0 * paths), static_cast<unsigned long long>(res.escaped_paths),
        static_cast<unsigned long long>(res.roulette_paths),
        static_cast<unsigned long long>(res.bounce_limit_paths),
        static_cast<unsigned long long>(res.truncated_paths), res.max_path_weight);
    for (int s = 0; s < 3; ++s) {
      const double ref = SkySum(reference, s);
      std::printf("S%d: sky sum %.5e +- %.2e (%.2f%%), Radiance %.5e: %+.2f%%, bin 0 = %g\n", s + 1,
                  res.sky_sum(s), res.sky_sum_standard_error(s),
                  100 * res.sky_sum_standard_error(s) / res.sky_sum(s), ref,
                  100 * (res.sky_sum(s) - ref) / ref, res.coefficients(s, 0));
    }
    std::printf(
        "mean relative SE %.2f%%, mean relative difference to Radiance %.2f%% (bins "
        "above 1%% of the row maximum)\n",
        100 * r.mean_relative_se, 100 * r.mean_relative_difference);
    if (bounces != 29) continue;

    // Q = (T_rad sigma_rad^2) / (T_ours sigma_ours^2), both per path and relative
    const double t_ours = ChargedSecondsPerPath(bench, r);
    std::printf(
        "relative efficiency Q vs Radiance (time per path x relative variance of the "
        "sky sum per path, c):\n");
    double mean_rad = 0, mean_ours = 0, worst_time = 0;
    for (int s = 0; s < 3; ++s) {
      const double q = kRadianceSecondsPerPath30 * kRadianceC30[s] / (t_ours * r.c[s]);
      std::printf("  S%d: c ours %.1f, Radiance %.1f; Q = %.1f\n", s + 1, r.c[s], kRadianceC30[s],
                  q);
      mean_rad += kRadianceC30[s] / 3;
      mean_ours += r.c[s] / 3;
      // Paths we need for Radiance's 10^7-path error on this sensor, and their time
      worst_time = std::max(worst_time, 1e7 * r.c[s] / kRadianceC30[s] * t_ours);
    }
    std::printf("  time per path: ours %.3g s, Radiance %.3g s\n", t_ours,
                kRadianceSecondsPerPath30);
    std::printf("  Q on the mean relative variance = %.1f\n",
                kRadianceSecondsPerPath30 * mean_rad / (t_ours * mean_ours));
    std::printf(
        "  time for Radiance's 3 x 10^7-path standard error on every sensor: %.1f s "
        "(Radiance 369.4 s): %.1fx faster\n",
        worst_time, 369.413 / worst_time);
  }
}

void Table(const Bench& bench) {
  std::printf("\n## Error against time, 29 reflections, default options, seed 3\n");
  std::printf("%10s %9s %9s %13s %14s %16s\n", "paths", "wall s", "cpu s", "rays/s", "mean rel. SE",
              "mean rel. diff");
  const int64_t max_paths = bench.quick ? 1000000 : 10000000;
  for (int64_t n = 1000; n <= max_paths; n *= 10) {
    const Run r = Trace(bench, n, 29, Strategy{}, 3, &bench.reference30);
    std::printf("%10lld %9.3f %9.3f %13.3g %13.1f%% %15.1f%%\n", static_cast<long long>(n),
                r.result.wall_seconds, r.cpu_seconds,
                r.result.rays_traced / (ChargedSecondsPerPath(bench, r) * n),
                100 * r.mean_relative_se, 100 * r.mean_relative_difference);
    std::fflush(stdout);
  }
}

// Between-seed differences of the per-sensor sky sums, as the campaign TSV's
// vs_seed2:mean_dsum (mean over sensors of |a - b| / ((a + b) / 2)), and the Q they give.
void Seeds(const Bench& bench) {
  const int64_t paths = bench.quick ? 100000 : 1000000;
  const int pairs = bench.quick ? 4 : 10;
  std::printf("\n## Between-seed differences, 29 reflections, %lld paths, %d seed pairs\n",
              static_cast<long long>(paths), pairs);
  double dsum_squares = 0, seconds = 0;
  for (int p = 0; p < pairs; ++p) {
    const Run a = Trace(bench, paths, 29, Strategy{}, 100 + 2 * p, nullptr);
    const Run b = Trace(bench, paths, 29, Strategy{}, 101 + 2 * p, nullptr);
    double dsum = 0;
    for (int s = 0; s < 3; ++s) {
      const double x = a.result.sky_sum(s), y = b.result.sky_sum(s);
      dsum += std::fabs(x - y) / ((x + y) / 2) / 3;
    }
    dsum_squares += dsum * dsum / pairs;
    seconds += (ChargedSecondsPerPath(bench, a) + ChargedSecondsPerPath(bench, b)) / (2 * pairs);
    std::printf("pair %d: mean_dsum %.4f\n", p, dsum);
  }
  // Radiance: mean_dsum^2 N over its pairs at 10^5, 10^6 and 10^7 paths (the reference's
  // two halves: 0.0038, 0.0043, 0.0182 -> 0.0088)
  const double radiance =
      (0.0416 * 0.0416 * 1e5 + 0.0154 * 0.0154 * 1e6 + 0.0088 * 0.0088 * 1e7) / 3;
  const double ours = dsum_squares * paths;
  std::printf(
      "mean_dsum^2 x N: ours %.1f (rms mean_dsum %.4f at %lld paths; Radiance had "
      "0.0154 at 10^6), Radiance pooled %.1f\n",
      ours, std::sqrt(dsum_squares), static_cast<long long>(paths), radiance);
  std::printf("time per path: ours %.3g s, Radiance %.3g s\n", seconds, kRadianceSecondsPerPath30);
  std::printf("Q from between-seed differences = %.1f\n",
              kRadianceSecondsPerPath30 * radiance / (seconds * ours));
}

}  // namespace
}  // namespace fenestra

int main(int argc, char** argv) {
  using namespace fenestra;
  Bench bench;
  std::vector<std::string> sections;
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    if (arg == "--quick") {
      bench.quick = true;
    } else if (arg == "--threads" && i + 1 < argc) {
      bench.threads = std::atoi(argv[++i]);
    } else {
      sections.push_back(arg);
    }
  }
  if (sections.empty() || sections == std::vector<std::string>{"all"}) {
    sections = {"main", "table", "seeds", "roulette"};
  }
  absl::StatusOr<Scene> scene = LoadScene(kSourceDir + "/examples/lightwell/scene.json");
  absl::StatusOr<Matrix> ref30 =
      ReadRadianceMatrix(kSourceDir + "/tests/data/reference/lightwell_dc_radiance_ab30_2e7.txt");
  absl::StatusOr<Matrix> ref5 =
      ReadRadianceMatrix(kSourceDir + "/tests/data/reference/lightwell_dc_radiance_ab5_1e7.txt");
  if (!scene.ok() || !ref30.ok() || !ref5.ok()) {
    std::fprintf(stderr, "error: cannot read the lightwell scene or its reference\n");
    return 1;
  }
  bench.scene = *std::move(scene);
  bench.reference30 = *std::move(ref30);
  bench.reference5 = *std::move(ref5);
  bench.threads = bench.threads > 0 ? bench.threads : int(std::thread::hardware_concurrency());
  PrintMachine(bench);
  for (const std::string& s : sections) {
    if (s == "roulette") {
      Roulette(bench);
    } else if (s == "main") {
      Main(bench);
    } else if (s == "table") {
      Table(bench);
    } else if (s == "seeds") {
      Seeds(bench);
    } else {
      std::fprintf(stderr, "error: unknown section '%s'\n", s.c_str());
      return 1;
    }
    std::fflush(stdout);
  }
  return 0;
}
