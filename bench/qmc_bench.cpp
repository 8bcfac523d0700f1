// The efficiency of quasi-random sampling (bench/README.md): Q = variance x cost of the
// pseudo-random draws over the Sobol draws (core/trace/philox.h, Sequence), measured side by
// side at the same path counts over `runs` seeds each, on the lightwell and the city office:
// one-stage coefficients and sensor sums, the outdoor stage's O, the indoor stage's I, and
// the sky sums of their product D. Per figure the median Q over the entries above 1% of
// their row's largest, and over the sensors' sums the median, least and largest.
// Usage: qmc_bench [cpu|cuda|auto] [runs]
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "bench/bench_util.h"
#include "core/dc/dc_backend.h"
#include "core/dc/one_stage.h"
#include "core/dc/two_stage.h"

namespace fenestra {
namespace {

// Per entry of a figure, its values over the runs.
struct Runs {
  std::vector<Matrix> values, errors;
  double seconds = 0;
  void Add(const Matrix& m, const Matrix& se, double s) {
    values.push_back(m);
    errors.push_back(se);
    seconds += s;
  }
  // The standard deviation of z = (value - mean over the runs) / sqrt(mean squared standard
  // error), scaled by sqrt(runs / (runs - 1)): 1 where the errors are calibrated.
  double ZScoreSd() const {
    const Matrix mean = Mean();
    const double runs = static_cast<double>(values.size());
    Matrix mean_variance = Matrix::Zero(mean.rows(), mean.cols());
    for (const Matrix& e : errors) mean_variance += e.array().square().matrix() / runs;
    double squares = 0;
    int count = 0;
    for (const Matrix& v : values) {
      for (Eigen::Index r = 0; r < mean.rows(); ++r) {
        const double largest = mean.row(r).cwiseAbs().maxCoeff();
        for (Eigen::Index c = 0; c < mean.cols(); ++c) {
          if (!(std::abs(mean(r, c)) > 0.01 * largest) || !(mean_variance(r, c) > 0)) continue;
          const double z = (v(r, c) - mean(r, c)) / std::sqrt(mean_variance(r, c));
          squares += z * z * runs / (runs - 1);
          ++count;
        }
      }
    }
    return count > 0 ? std::sqrt(squares / count) : 0;
  }
  Matrix Variance() const {
    Matrix mean = Matrix::Zero(values[0].rows(), values[0].cols());
    for (const Matrix& v : values) mean += v / values.size();
    Matrix var = Matrix::Zero(mean.rows(), mean.cols());
    for (const Matrix& v : values)
      var += (v - mean).array().square().matrix() / (values.size() - 1);
    return var;
  }
  Matrix Mean() const {
    Matrix mean = Matrix::Zero(values[0].rows(), values[0].cols());
    for (const Matrix& v : values) mean += v / values.size();
    return mean;
  }
};

double Median(std::vector<double> v) {
  if (v.empty()) return 0;
  std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
  return v[v.size() / 2];
}

// Q of every entry above 1% of its row's largest mean: (var_p t_p) / (var_s t_s).
std::vector<double> EntryQ(const Runs& pseudo, const Runs& sobol) {
  const Matrix vp = pseudo.Variance(), vs = sobol.Variance(), mean = pseudo.Mean();
  const double time = pseudo.seconds / sobol.seconds;
  std::vector<double> q;
  for (Eigen::Index r = 0; r < mean.rows(); ++r) {
    const double largest = mean.row(r).cwiseAbs().maxCoeff();
    for (Eigen::Index c = 0; c < mean.cols(); ++c) {
      if (std::abs(mean(r, c)) > 0.01 * largest && vs(r, c) > 0) {
        q.push_back(vp(r, c) / vs(r, c) * time);
      }
    }
  }
  return q;
}

void Report(const char* what, const Runs& pseudo, const Runs& sobol, bool per_row) {
  const std::vector<double> q = EntryQ(pseudo, sobol);
  std::printf("  %-34s Q median %6.2f over %5zu entries", what, Median(q), q.size());
  if (per_row && !q.empty()) {
    std::printf(" (least %.2f, largest %.2f)", *std::min_element(q.begin(), q.end()),
                *std::max_element(q.begin(), q.end()));
  }
  std::printf("; time %.3f s against %.3f s per run; z-score SD %.2f Sobol, %.2f pseudo-random\n",
              sobol.seconds / sobol.values.size(), pseudo.seconds / pseudo.values.size(),
              sobol.ZScoreSd(), pseudo.ZScoreSd());
}

double SecondsSince(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

void OneStage(DcBackend* backend, const Scene& scene, int runs, int64_t paths, int max_bounces) {
  Runs coefficients[2], sums[2];
  for (int k = 0; k < 2; ++k) {
    for (int r = 0; r < runs; ++r) {
      OneStageOptions options;
      options.paths_per_sensor = paths;
      options.seed = 1000 + r;
      options.batches = kSobolBatches;
      options.max_bounces = max_bounces;
      options.sequence = k == 0 ? Sequence::kPseudoRandom : Sequence::kSobol;
      const auto start = std::chrono::steady_clock::now();
      const OneStageResult d =
          ValueOrExit(ComputeOneStage(scene, DefaultDesign(scene), options, backend));
      const double s = SecondsSince(start);
      coefficients[k].Add(d.coefficients, d.standard_error, s);
      sums[k].Add(d.sky_sum.transpose(), d.sky_sum_standard_error.transpose(), s);
    }
  }
  std::printf(
      " one-stage, %lld paths per sensor, %s:\n", static_cast<long long>(paths),
      max_bounces == 0 ? "no reflection (the sky in direct view)" : "unlimited reflections");
  Report("coefficients D", coefficients[0], coefficients[1], false);
  Report("sensor sums of D", sums[0], sums[1], true);
}

void TwoStage(DcBackend* backend, const Scene& scene, int runs, int64_t outdoor_paths,
              int64_t indoor_paths) {
  Runs o[2], i[2], sums[2];
  const WindowParts parts = AutomaticWindowParts(scene.window());
  for (int k = 0; k < 2; ++k) {
    const Sequence sequence = k == 0 ? Sequence::kPseudoRandom : Sequence::kSobol;
    for (int r = 0; r < runs; ++r) {
      OutdoorOptions outdoor;
      outdoor.parts = parts;
      outdoor.paths = outdoor_paths;
      outdoor.seed = 2000 + r;
      outdoor.sequence = sequence;
      const OutdoorResult out = ValueOrExit(ComputeOutdoorStage(scene, outdoor, backend));
      const Eigen::Index cells = out.sky_view.size();
      o[k].Add(out.coefficients.topRows(cells), out.standard_error.topRows(cells),
               out.wall_seconds);
      IndoorOptions indoor;
      indoor.parts = parts;
      indoor.paths_per_sensor = indoor_paths;
      indoor.seed = 3000 + r;
      indoor.sequence = sequence;
      const IndoorResult in =
          ValueOrExit(ComputeIndoorStage(scene, DefaultDesign(scene), indoor, backend));
      i[k].Add(in.coefficients, in.standard_error, in.wall_seconds);
      const TwoStageResult d = ValueOrExit(CombineStages(in, out));
      sums[k].Add(d.sky_sum.transpose(), d.sky_sum_standard_error.transpose(),
                  out.wall_seconds + in.wall_seconds);
    }
  }
  std::printf(" two-stage, %lld outdoor paths, %lld indoor paths per sensor:\n",
              static_cast<long long>(outdoor_paths), static_cast<long long>(indoor_paths));
  Report("outdoor stage O", o[0], o[1], false);
  Report("indoor stage I", i[0], i[1], false);
  Report("sensor sums of D = I O", sums[0], sums[1], true);
}

}  // namespace
}  // namespace fenestra

int main(int argc, char** argv) {
  using namespace fenestra;
  const std::string backend_name = argc > 1 ? argv[1] : "cpu";
  const int runs = argc > 2 ? std::atoi(argv[2]) : 16;
  std::unique_ptr<DcBackend> backend = ValueOrExit(MakeBackend(backend_name));
  const bool gpu = backend->Gpu() >= 0;
  std::printf("backend %s, %d runs per sequence and figure\n", backend->Name().c_str(), runs);
  for (const char* name : {"lightwell", "city_office"}) {
    const Scene scene = ValueOrExit(
        LoadScene(std::string(FENESTRA_SOURCE_DIR) + "/examples/" + name + "/scene.json"));
    std::printf("%s:\n", name);
    for (const int bounces : {0, kUnlimitedBounces}) {
      OneStage(backend.get(), scene, runs, gpu ? 200'000 : 20'000, bounces);
    }
    TwoStage(backend.get(), scene, runs, gpu ? 20'000'000 : 2'000'000, gpu ? 200'000 : 20'000);
  }
  return 0;
}
