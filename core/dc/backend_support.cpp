#include "core/dc/backend_support.h"

#include <algorithm>
#include <cmath>

#include "absl/strings/str_cat.h"
#include "core/common/status_macros.h"
#include "core/common/thread_pool.h"
#include "core/trace/one_stage_cpu.h"

namespace fenestra {

absl::Status CheckOneStageInput(const std::vector<Sensor>& sensors,
                                const OneStageOptions& options) {
  if (sensors.empty()) return absl::InvalidArgumentError("the scene has no sensors");
  for (size_t i = 0; i < sensors.size(); ++i) {
    const Sensor& s = sensors[i];
    const Vec3d p = s.position, d = s.direction;
    if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z)) {
      return absl::InvalidArgumentError(
          absl::StrCat("sensor ", i, " ('", s.name, "') has a non-finite position"));
    }
    const double length = Length(d);
    if (!std::isfinite(length) || !(length > 1e-12)) {
      return absl::InvalidArgumentError(
          absl::StrCat("sensor ", i, " ('", s.name, "') has no valid direction"));
    }
  }
  if (options.paths_per_sensor < 2) {
    return absl::InvalidArgumentError(
        absl::StrCat("paths per sensor must be at least 2 (for a standard error), got ",
                     options.paths_per_sensor));
  }
  if (options.threads < 0) {
    return absl::InvalidArgumentError(
        absl::StrCat("threads must be >= 0 (0 = all cores), got ", options.threads));
  }
  if (options.weight_windows &&
      !(std::isfinite(options.importance_cell_m) && options.importance_cell_m > 0)) {
    return absl::InvalidArgumentError(
        absl::StrCat("importance cell size must be positive, got ", options.importance_cell_m));
  }
  if (options.pilot_paths_per_sensor < 0) {
    return absl::InvalidArgumentError(absl::StrCat("pilot paths must be >= 0 (0 = automatic), got ",
                                                   options.pilot_paths_per_sensor));
  }
  if (options.batches < 0 || options.batches > options.paths_per_sensor) {
    return absl::InvalidArgumentError(
        absl::StrCat("batches must be in [0, paths per sensor], got ", options.batches));
  }
  if (options.max_bounces < 0 && !options.russian_roulette) {
    return absl::InvalidArgumentError(
        "unlimited bounces (max_bounces < 0) need Russian roulette to end the paths");
  }
  if (options.russian_roulette &&
      !(options.roulette_threshold > 0 && options.roulette_threshold <= 1)) {
    return absl::InvalidArgumentError(
        absl::StrCat("roulette threshold must be in (0, 1], got ", options.roulette_threshold));
  }
  return absl::OkStatus();
}

PathSettings PathSettingsFor(const OneStageOptions& options) {
  PathSettings settings;
  settings.max_bounces = options.max_bounces >= 0 ? options.max_bounces : kUnlimitedBounces;
  settings.russian_roulette = options.russian_roulette;
  settings.roulette_threshold = static_cast<float>(options.roulette_threshold);
  settings.max_vertices = 1u << 20;
  settings.sequence = options.sequence;
  return settings;
}

Vec3d OneStageFrameOrigin(const std::vector<Sensor>& sensors) {
  if (sensors.empty()) return {0, 0, 0};
  Vec3d lo = sensors[0].position, hi = sensors[0].position;
  for (const Sensor& s : sensors) {
    lo = {std::min(lo.x, s.position.x), std::min(lo.y, s.position.y), std::min(lo.z, s.position.z)};
    hi = {std::max(hi.x, s.position.x), std::max(hi.y, s.position.y), std::max(hi.z, s.position.z)};
  }
  return (lo + hi) * 0.5;
}

std::vector<TraceSensor> LocalSensors(const TraceGeometry& geometry,
                                      const std::vector<Sensor>& sensors) {
  std::vector<TraceSensor> local;
  for (const Sensor& s : sensors) {
    const Vec3d d = Normalize(s.direction);
    local.push_back({geometry.ToLocal(s.position),
                     {static_cast<float>(d.x), static_cast<float>(d.y), static_cast<float>(d.z)}});
  }
  return local;
}

namespace {

// Coefficients, standard errors and sky sums from per-sensor, per-bin sums of path scores
// and of their squares, and per-sensor sums of the squared sky score of each path.
void FillFromSums(const std::vector<double>& sum, const std::vector<double>& sum_squares,
                  const std::vector<double>& sky_sum_squares, int sensor_count, int64_t paths,
                  OneStageResult* result) {
  const double n = static_cast<double>(paths);
  result->paths_per_sensor = paths;
  result->coefficients.resize(sensor_count, kDaylightBins);
  result->standard_error.resize(sensor_count, kDaylightBins);
  result->sky_sum.resize(sensor_count);
  result->sky_sum_standard_error.resize(sensor_count);
  // Standard error of a mean of n values from its first two moments
  const auto standard_error = [n](double total, double total_squares) {
    const double mean = total / n;
    return std::sqrt(std::max(0.0, (total_squares / n - mean * mean) / (n - 1)));
  };
  result->direct_coefficients.resize(sensor_count, kDaylightBins);
  for (int s = 0; s < sensor_count; ++s) {
    double sky = 0;
    for (int b = 0; b < kDaylightBins; ++b) {
      // Both blocks of the bin (OneStageBin): a path scores in one of them only, so their
      // squares add up to the square of its score
      const size_t k = static_cast<size_t>(s) * kOneStageBins + b;
      const double total = sum[k] + sum[k + kDaylightBins];
      result->coefficients(s, b) = total / n;
      result->standard_error(s, b) =
          standard_error(total, sum_squares[k] + sum_squares[k + kDaylightBins]);
      result->direct_coefficients(s, b) = sum[k + kDaylightBins] / n;
      if (b > 0) sky += total;
    }
    result->sky_sum(s) = sky / n;
    result->sky_sum_standard_error(s) = standard_error(sky, sky_sum_squares[s]);
  }
}

// batch_coefficients from per-batch sums, when batches > 1.
void FillBatches(const std::vector<double>& batch_sum, int sensor_count, int batches, int64_t paths,
                 OneStageResult* result) {
  result->batch_coefficients.clear();
  result->batch_direct_coefficients.clear();
  if (batches < 2) return;
  for (int b = 0; b < batches; ++b) {
    const double n =
        static_cast<double>(BatchStart(paths, batches, b + 1) - BatchStart(paths, batches, b));
    Matrix d(sensor_count, kDaylightBins), direct(sensor_count, kDaylightBins);
    for (int s = 0; s < sensor_count; ++s) {
      const double* row = &batch_sum[(static_cast<size_t>(s) * batches + b) * kOneStageBins];
      for (int bin = 0; bin < kDaylightBins; ++bin) {
        d(s, bin) = (row[bin] + row[bin + kDaylightBins]) / n;
        direct(s, bin) = row[bin + kDaylightBins] / n;
      }
    }
    result->batch_coefficients.push_back(std::move(d));
    result->batch_direct_coefficients.push_back(std::move(direct));
  }
}

// The standard errors of the coefficients and sky sums from the scatter of the batches'
// (the standard error of the mean of B independent batch estimates).
void ErrorsFromBatches(OneStageResult* result) {
  const std::vector<Matrix>& batches = result->batch_coefficients;
  const double count = static_cast<double>(batches.size());
  Matrix squares = Matrix::Zero(result->coefficients.rows(), result->coefficients.cols());
  Eigen::VectorXd sky_squares = Eigen::VectorXd::Zero(result->coefficients.rows());
  for (const Matrix& d : batches) {
    squares += (d - result->coefficients).array().square().matrix();
    const Eigen::VectorXd sky = d.rightCols(kDaylightBins - 1).rowwise().sum() - result->sky_sum;
    sky_squares += sky.array().square().matrix();
  }
  result->standard_error = (squares / (count * (count - 1))).cwiseSqrt();
  result->sky_sum_standard_error = (sky_squares / (count * (count - 1))).cwiseSqrt();
}

}  // namespace

int OneStageBatches(const OneStageOptions& options) {
  if (options.sequence == Sequence::kSobol && options.batches < 2) return kSobolBatches;
  return std::max(1, options.batches);
}

void FillOneStageResult(const OneStageTally& tally, int64_t paths, Sequence sequence,
                        OneStageResult* result) {
  FillFromSums(tally.sum, tally.sum_squares, tally.sky_sum_squares, tally.sensor_count, paths,
               result);
  FillBatches(tally.batch_sum, tally.sensor_count, tally.batches, paths, result);
  if (sequence == Sequence::kSobol && tally.batches >= 2) ErrorsFromBatches(result);
  result->rays_traced = tally.rays;
  result->branches = tally.branches;
  result->escaped_paths = tally.ends[static_cast<int>(PathEnd::kEscaped)];
  result->roulette_paths = tally.ends[static_cast<int>(PathEnd::kRoulette)];
  result->bounce_limit_paths = tally.ends[static_cast<int>(PathEnd::kBounceLimit)];
  result->truncated_paths = tally.ends[static_cast<int>(PathEnd::kTruncated)];
  result->max_path_weight = tally.max_weight;
  result->threads = tally.threads;
}

int64_t PilotPathsPerSensor(const OneStageOptions& options, size_t sensor_count) {
  if (options.pilot_paths_per_sensor > 0) return options.pilot_paths_per_sensor;
  const int64_t cap = std::max<int64_t>(20000, 600000 / std::max<size_t>(1, sensor_count));
  return std::max<int64_t>(1, std::min(options.paths_per_sensor, cap));
}

namespace {

// Whether every indoor batch has the first one's rows and `cells` columns.
absl::Status CheckIndoorBatches(const std::vector<Matrix>& batches, Eigen::Index cells) {
  const Eigen::Index rows = batches.empty() ? 0 : batches[0].rows();
  for (size_t b = 0; b < batches.size(); ++b) {
    if (batches[b].rows() != rows || batches[b].cols() != cells) {
      return absl::InvalidArgumentError(
          absl::StrCat("indoor batch ", b, " is ", batches[b].rows(), " x ", batches[b].cols(),
                       ", the outdoor matrix has ", cells, " window cells"));
    }
  }
  return absl::OkStatus();
}

}  // namespace

absl::StatusOr<Matrix> StackIndoorBatches(const std::vector<Matrix>& batches, Eigen::Index cells) {
  FENESTRA_RETURN_IF_ERROR(CheckIndoorBatches(batches, cells));
  const Eigen::Index rows = batches.empty() ? 0 : batches[0].rows();
  Matrix stacked(rows * static_cast<Eigen::Index>(batches.size()), cells);
  for (size_t b = 0; b < batches.size(); ++b) stacked.middleRows(b * rows, rows) = batches[b];
  return stacked;
}

absl::Status CheckOutdoorBatches(const std::vector<Matrix>& outdoor_batches, const Matrix& sky) {
  if (outdoor_batches.size() < 2) {
    return absl::InvalidArgumentError(
        absl::StrCat("the outdoor matrix needs at least 2 batches, got ", outdoor_batches.size()));
  }
  for (const Matrix& o : outdoor_batches) {
    if (o.rows() != outdoor_batches[0].rows() || o.cols() != kDaylightBins) {
      return absl::InvalidArgumentError(
          absl::StrCat("an outdoor batch is ", o.rows(), " x ", o.cols(), ", expected ",
                       outdoor_batches[0].rows(), " x ", kDaylightBins));
    }
  }
  return CheckSkyRows(sky);
}

absl::Status CheckProductSet(const AnnualProduct* product) {
  if (product == nullptr) {
    return absl::FailedPreconditionError("the design tallies have no annual product yet");
  }
  return absl::OkStatus();
}

absl::Status CheckSkyRows(const Matrix& sky) {
  if (sky.rows() != kDaylightBins && sky.rows() != kSplitSkyRows) {
    return absl::InvalidArgumentError(absl::StrCat("the outdoor matrix has ", kDaylightBins,
                                                   " sky bins, the sky ", sky.rows(), " rows"));
  }
  return absl::OkStatus();
}

Matrix UnreflectedOf(const Matrix& stacked_indoor) {
  return stacked_indoor.rightCols(kDaylightBins);
}

absl::Status CheckPairs(const std::vector<Matrix>& indoor_batches,
                        const std::vector<Matrix>& outdoor_batches) {
  if (indoor_batches.size() != outdoor_batches.size()) {
    return absl::InvalidArgumentError(absl::StrCat("the indoor stage has ", indoor_batches.size(),
                                                   " batches, the outdoor matrix ",
                                                   outdoor_batches.size(), "; they pair up"));
  }
  return CheckIndoorBatches(indoor_batches, outdoor_batches[0].rows());
}

Matrix ThroughWindow(const std::vector<Matrix>& indoor_batches,
                     const std::vector<Matrix>& outdoor_batches, bool unreflected) {
  const Eigen::Index sensors = indoor_batches.empty() ? 0 : indoor_batches[0].rows();
  const Eigen::Index bins = outdoor_batches.empty() ? 0 : outdoor_batches[0].cols();
  // One blocked product per batch, the batches on all cores, each into its own rows: six
  // times faster than a rank-one update per column of I (bench/README.md, "The annual
  // products on the CPU")
  Matrix through(sensors * static_cast<Eigen::Index>(indoor_batches.size()),
                 unreflected ? 2 * bins : bins);
  ParallelFor(indoor_batches.size(), ResolveThreadCount(0), [&](uint64_t b) {
    const Eigen::Index first = static_cast<Eigen::Index>(b) * sensors;
    through.block(first, 0, sensors, bins).noalias() = indoor_batches[b] * outdoor_batches[b];
    if (unreflected) {
      through.block(first, bins, sensors, bins) = indoor_batches[b].rightCols(bins);
    }
  });
  return through;
}

Matrix ProductOnAllCores(const Matrix& a, const Matrix& b) {
  // Parts of at least kColumns columns of b, one task each
  constexpr Eigen::Index kColumns = 256;
  const Eigen::Index parts = std::max<Eigen::Index>(1, b.cols() / kColumns);
  Matrix product(a.rows(), b.cols());
  ParallelFor(static_cast<uint64_t>(parts), ResolveThreadCount(0), [&](uint64_t k) {
    const Eigen::Index first = b.cols() * static_cast<Eigen::Index>(k) / parts;
    const Eigen::Index last = b.cols() * static_cast<Eigen::Index>(k + 1) / parts;
    product.middleCols(first, last - first).noalias() = a * b.middleCols(first, last - first);
  });
  return product;
}

std::vector<Matrix> SplitBatches(const Matrix& stacked, size_t count) {
  std::vector<Matrix> batches;
  const Eigen::Index rows = count == 0 ? 0 : stacked.rows() / static_cast<Eigen::Index>(count);
  for (size_t b = 0; b < count; ++b) batches.push_back(stacked.middleRows(b * rows, rows));
  return batches;
}

}  // namespace fenestra
