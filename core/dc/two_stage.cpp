#include "core/dc/two_stage.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <memory>

#include "absl/strings/numbers.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/str_split.h"
#include "core/common/status_macros.h"
#include "core/dc/backend_support.h"
#include "core/trace/trace_geometry.h"
#include "core/trace/two_stage_cpu.h"

namespace fenestra {
namespace {

constexpr int kMaxPartsPerSide = 16;

double Seconds(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

PathSettings Settings(int max_bounces, bool russian_roulette, double roulette_threshold) {
  PathSettings settings;
  settings.max_bounces = max_bounces >= 0 ? max_bounces : -1;
  settings.russian_roulette = russian_roulette;
  settings.roulette_threshold = static_cast<float>(roulette_threshold);
  settings.max_vertices = 1u << 20;
  return settings;
}

absl::Status CheckPaths(int max_bounces, bool russian_roulette, double roulette_threshold,
                        int threads) {
  if (max_bounces < 0 && !russian_roulette) {
    return absl::InvalidArgumentError("unlimited bounces need Russian roulette");
  }
  if (!(roulette_threshold > 0 && roulette_threshold <= 1)) {
    return absl::InvalidArgumentError("roulette threshold must be in (0, 1]");
  }
  if (threads < 0) return absl::InvalidArgumentError("threads must be >= 0");
  return absl::OkStatus();
}

absl::Status CheckParts(WindowParts parts) {
  if (parts.columns < 1 || parts.rows < 1 || parts.columns > kMaxPartsPerSide ||
      parts.rows > kMaxPartsPerSide) {
    return absl::InvalidArgumentError(absl::StrCat("window parts must be 1 to ", kMaxPartsPerSide,
                                                   " in each direction, got ", parts.columns, "x",
                                                   parts.rows));
  }
  return absl::OkStatus();
}

}  // namespace

WindowParts AutomaticWindowParts(const Window& window) {
  static constexpr double kPartSize = 0.5;  // [m]
  static constexpr int kMaxAutomatic = 8;
  auto count = [](double length) {
    return std::clamp(static_cast<int>(std::ceil(length / kPartSize - 1e-9)), 1, kMaxAutomatic);
  };
  return {count(window.width_m), count(window.height_m)};
}

TraceWindow LocalWindow(const TraceGeometry& geometry, const Window& window, WindowParts parts) {
  auto f = [](Vec3d v) { return Vec3f{float(v.x), float(v.y), float(v.z)}; };
  return {geometry.ToLocal(window.center),
          f(window.across),
          f(window.up),
          f(window.normal),
          static_cast<float>(window.width_m),
          static_cast<float>(window.height_m),
          parts.columns,
          parts.rows};
}

absl::StatusOr<WindowParts> ParseWindowParts(const std::string& text) {
  WindowParts parts;
  const std::vector<std::string> fields = absl::StrSplit(text, 'x');
  if (fields.size() != 2 || !absl::SimpleAtoi(fields[0], &parts.columns) ||
      !absl::SimpleAtoi(fields[1], &parts.rows)) {
    return absl::InvalidArgumentError(
        absl::StrCat("window parts must read COLUMNSxROWS, e.g. 4x2, got '", text, "'"));
  }
  FENESTRA_RETURN_IF_ERROR(CheckParts(parts));
  return parts;
}

absl::StatusOr<HemisphereBasis> BasisFor(int cells) {
  if (cells != 288 && cells != 1152) {
    return absl::InvalidArgumentError(
        absl::StrCat("window basis must have 288 or 1152 cells, got ", cells));
  }
  return BeckersBasis(cells);
}

TriangleMesh SelectSide(const TriangleMesh& mesh, Side side) {
  TriangleMesh out;
  out.part_names = mesh.part_names;
  for (size_t t = 0; t < mesh.TriangleCount(); ++t) {
    if (mesh.side[t] != side) continue;
    out.Add(mesh.vertices[3 * t], mesh.vertices[3 * t + 1], mesh.vertices[3 * t + 2],
            mesh.material[t], side, mesh.part[t]);
  }
  return out;
}

absl::StatusOr<OutdoorResult> ComputeOutdoorStage(const Scene& scene, const OutdoorOptions& options,
                                                  DcBackend* backend) {
  const auto start = std::chrono::steady_clock::now();
  FENESTRA_ASSIGN_OR_RETURN(basis, BasisFor(options.basis_cells));
  FENESTRA_RETURN_IF_ERROR(CheckParts(options.parts));
  FENESTRA_RETURN_IF_ERROR(CheckPaths(options.max_bounces, options.russian_roulette,
                                      options.roulette_threshold, options.threads));
  const int64_t window_cells =
      int64_t{basis.cell_count} * options.parts.columns * options.parts.rows;
  if (options.paths < window_cells * 2) {
    return absl::InvalidArgumentError(
        absl::StrCat("outdoor paths must be at least 2 per window cell (", 2 * window_cells,
                     "), got ", options.paths));
  }
  const TriangleMesh outdoor = SelectSide(scene.fixed, Side::kOutdoor);
  FENESTRA_ASSIGN_OR_RETURN(geometry, PrepareTraceGeometry(outdoor, scene.materials));
  std::unique_ptr<DcBackend> fallback;
  if (backend == nullptr) backend = (fallback = MakeEmbreeBackend()).get();

  // Trace, then O = sums / paths per cell
  const uint64_t per_cell = static_cast<uint64_t>(options.paths / window_cells);
  FENESTRA_ASSIGN_OR_RETURN(
      tally, backend->Outdoor(geometry, LocalWindow(geometry, scene.window, options.parts), basis,
                              per_cell, options.seed,
                              Settings(options.max_bounces, options.russian_roulette,
                                       options.roulette_threshold),
                              options.threads));
  OutdoorResult result;
  result.basis_cells = basis.cell_count;
  result.parts = options.parts;
  result.paths_per_cell = static_cast<int64_t>(per_cell);
  result.coefficients.resize(tally.cells, kDaylightBins);
  result.standard_error.resize(tally.cells, kDaylightBins);
  const double n = static_cast<double>(per_cell);
  for (int k = 0; k < tally.cells; ++k) {
    for (int j = 0; j < kDaylightBins; ++j) {
      const double sum = tally.sum[k * kDaylightBins + j];
      const double mean = sum / n;
      const double variance =
          std::max(0.0, (tally.sum_squares[k * kDaylightBins + j] - sum * mean) / (n - 1));
      result.coefficients(k, j) = mean;
      result.standard_error(k, j) = std::sqrt(variance / n);
    }
  }
  result.rays_traced = tally.counters.rays;
  result.triangles = outdoor.TriangleCount();
  result.backend = backend->Name();
  result.wall_seconds = Seconds(start);
  return result;
}

absl::StatusOr<HemisphereBasis> CheckIndoorOptions(const IndoorOptions& options) {
  FENESTRA_ASSIGN_OR_RETURN(basis, BasisFor(options.basis_cells));
  FENESTRA_RETURN_IF_ERROR(CheckParts(options.parts));
  FENESTRA_RETURN_IF_ERROR(CheckPaths(options.max_bounces, options.russian_roulette,
                                      options.roulette_threshold, options.threads));
  if (options.batches < 2) return absl::InvalidArgumentError("batches must be at least 2");
  if (options.paths_per_sensor < options.batches) {
    return absl::InvalidArgumentError(
        absl::StrCat("indoor paths per sensor must be at least the batch count (", options.batches,
                     "), got ", options.paths_per_sensor));
  }
  return basis;
}

PathSettings IndoorPathSettings(const IndoorOptions& options) {
  return Settings(options.max_bounces, options.russian_roulette, options.roulette_threshold);
}

IndoorResult IndoorResultFromTally(const IndoorTally& tally, const IndoorOptions& options) {
  IndoorResult result;
  result.parts = options.parts;
  const int sensors = tally.sensors, cells = tally.cells, batches = tally.batches;
  result.coefficients = Matrix::Zero(sensors, cells);
  for (int b = 0; b < batches; ++b) {
    Matrix batch(sensors, cells);
    for (int s = 0; s < sensors; ++s) {
      for (int k = 0; k < cells; ++k) {
        batch(s, k) = tally.sum[(static_cast<size_t>(b) * sensors + s) * cells + k] /
                      static_cast<double>(tally.batch_paths[b]);
      }
    }
    result.coefficients += batch / batches;
    result.batches.push_back(std::move(batch));
  }
  Matrix variance = Matrix::Zero(sensors, cells);
  for (const Matrix& batch : result.batches) {
    variance += (batch - result.coefficients).cwiseAbs2();
  }
  result.standard_error = (variance / (batches * (batches - 1.0))).cwiseSqrt();
  result.paths_per_sensor = options.paths_per_sensor;
  result.trace_seconds = tally.trace_seconds;
  result.rays_traced = tally.counters.rays;
  return result;
}

absl::StatusOr<IndoorResult> ComputeIndoorStage(const Scene& scene, const BlindDesign& design,
                                                const IndoorOptions& options, DcBackend* backend) {
  const auto start = std::chrono::steady_clock::now();
  FENESTRA_ASSIGN_OR_RETURN(basis, CheckIndoorOptions(options));
  const TriangleMesh indoor = SelectSide(AssembleMesh(scene, design), Side::kIndoor);
  FENESTRA_ASSIGN_OR_RETURN(geometry, PrepareTraceGeometry(indoor, scene.materials));
  std::unique_ptr<DcBackend> fallback;
  if (backend == nullptr) backend = (fallback = MakeEmbreeBackend()).get();

  // Trace, then I_b = batch sums / batch paths
  FENESTRA_ASSIGN_OR_RETURN(
      tally, backend->Indoor(geometry, LocalSensors(geometry, scene.sensors),
                             LocalWindow(geometry, scene.window, options.parts), basis,
                             static_cast<uint64_t>(options.paths_per_sensor), options.batches,
                             options.seed, IndoorPathSettings(options), options.threads));
  IndoorResult result = IndoorResultFromTally(tally, options);
  result.triangles = indoor.TriangleCount();
  result.backend = backend->Name();
  result.wall_seconds = Seconds(start);
  return result;
}

absl::StatusOr<TwoStageResult> CombineStages(const IndoorResult& indoor,
                                             const OutdoorResult& outdoor) {
  if (!(indoor.parts == outdoor.parts)) {
    return absl::InvalidArgumentError(absl::StrCat(
        "indoor matrix has ", indoor.parts.columns, "x", indoor.parts.rows,
        " window parts, outdoor matrix ", outdoor.parts.columns, "x", outdoor.parts.rows));
  }
  if (indoor.coefficients.cols() != outdoor.coefficients.rows()) {
    return absl::InvalidArgumentError(absl::StrCat("indoor matrix has ", indoor.coefficients.cols(),
                                                   " window cells, outdoor matrix ",
                                                   outdoor.coefficients.rows()));
  }
  // Every batch's D in one product (I is the mean of its batches, so D is the mean of theirs)
  TwoStageResult result;
  const Eigen::Index rows = indoor.coefficients.rows();
  const double batches = static_cast<double>(indoor.batches.size());
  FENESTRA_ASSIGN_OR_RETURN(stacked,
                            StackIndoorBatches(indoor.batches, outdoor.coefficients.rows()));
  result.batches = SplitBatches(stacked * outdoor.coefficients, indoor.batches.size());
  result.coefficients = Matrix::Zero(rows, outdoor.coefficients.cols());
  for (const Matrix& d : result.batches) result.coefficients += d / batches;
  Matrix indoor_variance = Matrix::Zero(rows, result.coefficients.cols());
  for (const Matrix& d : result.batches) indoor_variance += (d - result.coefficients).cwiseAbs2();
  if (batches > 1) indoor_variance /= batches * (batches - 1);
  const Matrix outdoor_variance =
      indoor.coefficients.cwiseAbs2() * outdoor.standard_error.cwiseAbs2();
  result.standard_error = (indoor_variance + outdoor_variance).cwiseSqrt();

  // Sky sums: indoor error from the batches; outdoor error from each cell's row sum. A path
  // scores one bin, so a row sum's second moment is the sum of its entries' second moments:
  // var(row) = sum_j se_j^2 + (sum_j m_j^2 - (sum_j m_j)^2) / (n - 1)
  const Eigen::Index sensors = result.coefficients.rows(), cells = outdoor.coefficients.rows();
  const double n = static_cast<double>(std::max<int64_t>(2, outdoor.paths_per_cell));
  Eigen::VectorXd row_variance(cells);
  for (Eigen::Index k = 0; k < cells; ++k) {
    const auto m = outdoor.coefficients.row(k).tail(kDaylightBins - 1);
    const auto se = outdoor.standard_error.row(k).tail(kDaylightBins - 1);
    row_variance(k) =
        std::max(0.0, se.squaredNorm() + (m.squaredNorm() - m.sum() * m.sum()) / (n - 1));
  }
  result.sky_sum.resize(sensors);
  result.sky_sum_standard_error.resize(sensors);
  for (Eigen::Index i = 0; i < sensors; ++i) {
    result.sky_sum(i) = result.coefficients.row(i).tail(kDaylightBins - 1).sum();
    double variance = 0;
    for (const Matrix& d : result.batches) {
      variance += std::pow(d.row(i).tail(kDaylightBins - 1).sum() - result.sky_sum(i), 2);
    }
    if (batches > 1) variance /= batches * (batches - 1);
    variance += indoor.coefficients.row(i).cwiseAbs2().dot(row_variance);
    result.sky_sum_standard_error(i) = std::sqrt(variance);
  }
  return result;
}

namespace {

// Every design traced in full by the backend.
class TracedIndoorStages : public IndoorStages {
 public:
  TracedIndoorStages(Scene scene, const IndoorOptions& options, DcBackend* backend)
      : scene_(std::move(scene)), options_(options), backend_(backend) {}
  absl::StatusOr<IndoorResult> Compute(const BlindDesign& design) const override {
    return ComputeIndoorStage(scene_, design, options_, backend_);
  }

 private:
  Scene scene_;
  IndoorOptions options_;
  DcBackend* backend_;
};

// The indoor stage, then the annual product's tallies.
class StagedDesignTallies : public DesignTallies {
 public:
  StagedDesignTallies(std::unique_ptr<IndoorStages> stages, std::unique_ptr<AnnualProduct> product)
      : stages_(std::move(stages)), product_(std::move(product)) {}
  absl::StatusOr<std::vector<HourTally>> Tally(const BlindDesign& design,
                                               const MetricOptions& options) override {
    FENESTRA_ASSIGN_OR_RETURN(indoor, stages_->Compute(design));
    return product_->Tally(indoor.batches, options);
  }

 private:
  std::unique_ptr<IndoorStages> stages_;
  std::unique_ptr<AnnualProduct> product_;
};

}  // namespace

absl::StatusOr<std::unique_ptr<DesignTallies>> DcBackend::MakeDesignTallies(
    const Scene& scene, const IndoorOptions& options, const Matrix& outdoor, const Matrix& sky) {
  FENESTRA_ASSIGN_OR_RETURN(stages, MakeIndoorStages(scene, options));
  FENESTRA_ASSIGN_OR_RETURN(product, MakeAnnualProduct(outdoor, sky));
  return std::make_unique<StagedDesignTallies>(std::move(stages), std::move(product));
}

absl::StatusOr<std::unique_ptr<IndoorStages>> DcBackend::MakeIndoorStages(
    const Scene& scene, const IndoorOptions& options) {
  FENESTRA_RETURN_IF_ERROR(CheckIndoorOptions(options).status());
  return std::make_unique<TracedIndoorStages>(scene, options, this);
}

}  // namespace fenestra
