// fenestra convergence: error against run time, from runs at doubling path counts.
#include <fmt/format.h>

#include <CLI/CLI.hpp>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <limits>
#include <memory>
#include <ostream>
#include <string>
#include <vector>

#include "absl/status/status.h"
#include "client/cli_util.h"
#include "client/commands.h"
#include "client/convergence_plot.h"
#include "client/dc_options.h"
#include "core/common/atomic_file.h"
#include "core/common/radiance_matrix.h"
#include "core/common/seconds.h"
#include "core/dc/one_stage.h"
#include "core/dc/rounds.h"
#include "core/dc/two_stage.h"

namespace fenestra {
namespace {

// The first run traces the path counts of `fenestra dc` divided by this.
constexpr int64_t kFirstRunDivisor = 16;
// Runs at most (2^29 times the first run's paths).
constexpr int kMaxRuns = 30;

struct ConvergenceArgs {
  DcFlags flags;
  std::string reference, prefix;
  double max_seconds = 120;
  int max_runs = 0;  // 0 = until --max-seconds
};

// One run's estimate of D with its cost.
struct Estimate {
  Matrix coefficients;
  Eigen::VectorXd sky_sum, sky_sum_standard_error;
  int64_t paths_per_sensor = 0, outdoor_paths = 0;
  uint64_t rays = 0;
  double seconds = 0;
};

// A row of the table.
struct Point {
  int64_t paths_per_sensor = 0, outdoor_paths = 0;
  uint64_t rays = 0;
  double seconds = 0;
  double max_relative_se = 0, mean_relative_se = 0;
  // Against the reference: the sensors' sky sums and the flux-weighted L1 distance of D
  double max_relative_difference = 0, mean_relative_difference = 0, flux_l1 = 0;
};

// Run `k`: the flags' paths times 2^k with the random streams of round k.
Estimate RunOnce(const ConvergenceArgs& a, DcInput& in, int k) {
  Estimate e;
  if (a.flags.method == "one-stage") {
    OneStageOptions options = OneStageOptionsFrom(a.flags);
    options.paths_per_sensor <<= k;
    options.seed = RoundSeed(options.seed, k);
    OneStageResult r = ValueOrFail(ComputeOneStage(in.scene, in.design, options, in.backend.get()));
    e.coefficients = std::move(r.coefficients);
    e.sky_sum = std::move(r.sky_sum);
    e.sky_sum_standard_error = std::move(r.sky_sum_standard_error);
    e.paths_per_sensor = r.paths_per_sensor;
    e.rays = r.rays_traced;
    e.seconds = r.wall_seconds;
    return e;
  }
  OutdoorOptions outdoor = OutdoorOptionsFrom(a.flags, in.parts);
  IndoorOptions indoor = IndoorOptionsFrom(a.flags, in.parts);
  outdoor.paths <<= k;
  indoor.paths_per_sensor <<= k;
  outdoor.seed = indoor.seed = RoundSeed(outdoor.seed, k);
  const OutdoorResult o = ValueOrFail(ComputeOutdoorStage(in.scene, outdoor, in.backend.get()));
  const IndoorResult i =
      ValueOrFail(ComputeIndoorStage(in.scene, in.design, indoor, in.backend.get()));
  TwoStageResult d = ValueOrFail(CombineStages(i, o));
  e.coefficients = std::move(d.coefficients);
  e.sky_sum = std::move(d.sky_sum);
  e.sky_sum_standard_error = std::move(d.sky_sum_standard_error);
  e.paths_per_sensor = i.paths_per_sensor;
  e.outdoor_paths = o.paths_per_cell * o.sky_view.size();
  e.rays = o.rays_traced + i.rays_traced;
  e.seconds = o.wall_seconds + i.wall_seconds;
  return e;
}

// The reference matrix, or InvalidArgument unless it is sensors x 146 with some sky light.
absl::StatusOr<Matrix> ReadReference(const std::string& path, size_t sensors) {
  absl::StatusOr<Matrix> reference = ReadRadianceMatrix(path);
  if (!reference.ok()) {
    return absl::InvalidArgumentError(
        fmt::format("--reference: {}", std::string(reference.status().message())));
  }
  if (reference->rows() != static_cast<Eigen::Index>(sensors) ||
      reference->cols() != kDaylightBins) {
    return absl::InvalidArgumentError(
        fmt::format("--reference: {} has {} x {} entries, the scene needs {} sensors x {} bins",
                    path, reference->rows(), reference->cols(), sensors, kDaylightBins));
  }
  if (!(reference->rightCols(kDaylightBins - 1).sum() > 0) || !reference->allFinite()) {
    return absl::InvalidArgumentError(
        fmt::format("--reference: {} has no sky light or entries that are not numbers", path));
  }
  return reference;
}

Point Measure(const Estimate& e, const Matrix* reference) {
  Point p{e.paths_per_sensor, e.outdoor_paths, e.rays, e.seconds};
  const Eigen::VectorXd relative = RelativeErrors(e.sky_sum, e.sky_sum_standard_error);
  p.max_relative_se = relative.maxCoeff();
  p.mean_relative_se = relative.mean();
  if (reference == nullptr) return p;
  int lit = 0;
  for (Eigen::Index s = 0; s < e.sky_sum.size(); ++s) {
    const double truth = reference->row(s).tail(kDaylightBins - 1).sum();
    if (!(truth > 0)) continue;  // no light to compare with
    const double difference = std::abs(e.sky_sum(s) - truth) / truth;
    p.max_relative_difference = std::max(p.max_relative_difference, difference);
    p.mean_relative_difference += difference;
    ++lit;
  }
  p.mean_relative_difference /= std::max(lit, 1);
  p.flux_l1 = (e.coefficients - *reference).cwiseAbs().sum() / reference->cwiseAbs().sum();
  return p;
}

std::string Row(const Point& p, bool with_reference, const char* separator, bool padded) {
  std::string row =
      padded
          ? fmt::format("{:>12}{}{:>12}{}{:>12}{}{:>9.3f}{}{:>9.4f}{}{:>9.4f}", p.paths_per_sensor,
                        separator, p.outdoor_paths, separator, p.rays, separator, p.seconds,
                        separator, p.max_relative_se, separator, p.mean_relative_se)
          : fmt::format("{}{}{}{}{}{}{:.6g}{}{:.6g}{}{:.6g}", p.paths_per_sensor, separator,
                        p.outdoor_paths, separator, p.rays, separator, p.seconds, separator,
                        p.max_relative_se, separator, p.mean_relative_se);
  if (with_reference) {
    row += padded
               ? fmt::format("{}{:>9.4f}{}{:>9.4f}{}{:>9.4f}", separator, p.max_relative_difference,
                             separator, p.mean_relative_difference, separator, p.flux_l1)
               : fmt::format("{}{:.6g}{}{:.6g}{}{:.6g}", separator, p.max_relative_difference,
                             separator, p.mean_relative_difference, separator, p.flux_l1);
  }
  return row;
}

constexpr const char* kColumns[] = {"paths_per_sensor", "outdoor_paths", "rays",
                                    "wall_seconds",     "max_rel_se",    "mean_rel_se",
                                    "max_rel_diff",     "mean_rel_diff", "flux_l1"};

std::string Header(bool with_reference, const char* separator, bool padded) {
  std::string header;
  const size_t columns = with_reference ? std::size(kColumns) : 6;
  for (size_t c = 0; c < columns; ++c) {
    if (c > 0) header += separator;
    header += padded ? fmt::format("{:>{}}", kColumns[c], c < 3 ? 12 : 9) : kColumns[c];
  }
  return header;
}

absl::Status WriteCsv(const std::string& path, const std::vector<Point>& points,
                      bool with_reference) {
  return WriteFileAtomically(path, [&](std::ostream& out) {
    out << Header(with_reference, ",", false) << '\n';
    for (const Point& p : points) out << Row(p, with_reference, ",", false) << '\n';
    return absl::OkStatus();
  });
}

absl::Status WriteSvg(const std::string& path, const std::string& title,
                      const std::vector<Point>& points, bool with_reference) {
  LogLogPlot plot;
  plot.title = title;
  plot.x_label = "wall time [s]";
  plot.y_label = "relative error";
  const auto series = [&](const char* name, double Point::*value) {
    PlotSeries s{name, {}, {}};
    for (const Point& p : points) s.x.push_back(p.seconds), s.y.push_back(p.*value);
    plot.series.push_back(std::move(s));
  };
  series("largest relative SE", &Point::max_relative_se);
  series("mean relative SE", &Point::mean_relative_se);
  if (with_reference) {
    series("largest difference to reference", &Point::max_relative_difference);
    series("mean difference to reference", &Point::mean_relative_difference);
    series("flux-weighted L1 of D", &Point::flux_l1);
  }
  return WriteLogLogSvg(path, plot);
}

void Run(const ConvergenceArgs& a) {
  if (const absl::Status s = CheckMethodFlags(a.flags); !s.ok()) Fail(s);
  if (!(a.max_seconds > 0)) Fail(absl::InvalidArgumentError("--max-seconds must be positive"));
  const std::filesystem::path folder = std::filesystem::path(a.prefix).parent_path();
  if (!folder.empty() && !std::filesystem::is_directory(folder)) {
    Fail(absl::InvalidArgumentError(
        fmt::format("--output: folder '{}' does not exist", folder.string())));
  }
  DcInput in = ValueOrFail(LoadDcInput(a.flags));
  Matrix reference;
  if (!a.reference.empty()) {
    reference = ValueOrFail(ReadReference(a.reference, in.scene.sensors.size()));
  }
  const bool with_reference = !a.reference.empty();
  const std::string title = fmt::format("{}, {}, {}: error against wall time", in.scene.name,
                                        a.flags.method, in.backend->Name());
  fmt::print("{}\n{}\n", title, Header(with_reference, " ", true));

  // Double the paths while the next run (about twice the last) fits in the time
  const auto start = std::chrono::steady_clock::now();
  const int runs = a.max_runs > 0 ? std::min(a.max_runs, kMaxRuns) : kMaxRuns;
  std::vector<Point> points;
  const auto plural = [](int n) { return n == 1 ? "" : "s"; };
  std::string stop = fmt::format("stopped after {} run{}", runs, plural(runs));
  for (int k = 0; k < runs; ++k) {
    const double elapsed = SecondsSince(start);
    if (k > 0 && elapsed + 2 * points.back().seconds > a.max_seconds) {
      stop = fmt::format("stopped after {} run{}, {:.1f} s: the next would pass --max-seconds {}",
                         k, plural(k), elapsed, a.max_seconds);
      break;
    }
    points.push_back(Measure(RunOnce(a, in, k), with_reference ? &reference : nullptr));
    fmt::print("{}\n", Row(points.back(), with_reference, " ", true));
    std::fflush(stdout);
  }
  fmt::print("{}\n", stop);
  const std::string csv = a.prefix + ".csv", svg = a.prefix + ".svg";
  if (const absl::Status s = WriteCsv(csv, points, with_reference); !s.ok()) Fail(s);
  if (const absl::Status s = WriteSvg(svg, title, points, with_reference); !s.ok()) {
    std::error_code ignored;
    std::filesystem::remove(csv, ignored);  // both files or neither
    Fail(s);
  }
  fmt::print("wrote {} and {}\n", csv, svg);
}

}  // namespace

void AddConvergenceCommand(CLI::App& app) {
  auto args = std::make_shared<ConvergenceArgs>();
  CLI::App* command = app.add_subcommand(
      "convergence",
      "Error against run time: runs at doubling path counts (each with its own random "
      "streams), writes PREFIX.csv (paths, rays, wall seconds, the largest and mean relative "
      "SE of the sensors' sky sums, and against --reference the largest and mean relative "
      "difference of the sky sums and the flux-weighted L1 distance of D, sum |D - R| / sum R) "
      "and PREFIX.svg (log-log, with the 1/sqrt(t) line through the first point). The path counts "
      "below are the first run's");
  AddDcFlags(command, &args->flags, kFirstRunDivisor);
  command->add_option("-o,--output", args->prefix, "Prefix of the .csv and .svg files")->required();
  command->add_option("--reference", args->reference,
                      "Reference D (sensors x 146, Radiance matrix or whitespace-separated "
                      "table), e.g. from a long one-stage run");
  command
      ->add_option("--max-seconds", args->max_seconds,
                   "Start no run that would end after this many seconds (a run takes about "
                   "twice the previous one)")
      ->capture_default_str();
  command->add_option("--max-runs", args->max_runs, "At most this many runs (0 = as time allows)")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  command->callback([args] { Run(*args); });
}

}  // namespace fenestra
