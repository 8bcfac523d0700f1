#include "core/dc/two_stage.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <memory>

#include "absl/strings/numbers.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/str_split.h"
#include "core/common/seconds.h"
#include "core/common/status_macros.h"
#include "core/dc/backend_support.h"
#include "core/dc/direct_sun.h"
#include "core/trace/trace_geometry.h"
#include "core/trace/two_stage_cpu.h"
#include "core/trace/two_stage_modes.h"
#include "core/trace/window_cells.h"

namespace fenestra {
namespace {

PathSettings Settings(int max_bounces, bool russian_roulette, double roulette_threshold,
                      Sequence sequence) {
  PathSettings settings;
  settings.sequence = sequence;
  settings.max_bounces = max_bounces >= 0 ? max_bounces : kUnlimitedBounces;
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

// A side of 0 is automatic (PartsOfWindow)
absl::Status CheckParts(WindowParts parts) {
  if (parts.columns < 0 || parts.rows < 0 || parts.columns > kMaxWindowPartsPerSide ||
      parts.rows > kMaxWindowPartsPerSide) {
    return absl::InvalidArgumentError(
        absl::StrCat("window parts must be 1 to ", kMaxWindowPartsPerSide,
                     " in each direction, got ", parts.columns, "x", parts.rows));
  }
  return absl::OkStatus();
}

absl::Status CheckBatches(int batches) {
  if (batches < 2 || batches > kMaxBatches) {
    return absl::InvalidArgumentError(
        absl::StrCat("batches must be 2 to ", kMaxBatches, ", got ", batches));
  }
  return absl::OkStatus();
}

}  // namespace

OutdoorBatches FormOutdoorBatches(const OutdoorTally& tally) {
  OutdoorBatches o;
  const int cells = tally.cells;
  o.first_escapes = Eigen::VectorXd::Zero(cells);
  for (int b = 0; b < tally.batches; ++b) {
    Matrix batch(OutdoorRowCount(cells), kDaylightBins);
    const double paths = static_cast<double>(tally.batch_paths[b]);
    for (int k = 0; k < cells; ++k) {
      const double* row = &tally.sum[(static_cast<size_t>(b) * cells + k) * kOutdoorRowSize];
      for (int j = 0; j < kDaylightBins; ++j) batch(k, j) = OutdoorCoefficient(row, paths, j);
      o.first_escapes(k) += row[kFirstEscapeEntry];
    }
    // The identity for each block of direct columns (IndoorColumnCount)
    batch.middleRows(cells, kDaylightBins).setIdentity();
    batch.bottomRows(kDaylightBins).setIdentity();
    o.batches.push_back(std::move(batch));
  }
  MeanAndError(o.batches, &o.mean, &o.standard_error);
  o.paths_per_cell = tally.paths_per_cell;
  o.counters = tally.counters;
  return o;
}

WindowParts AutomaticWindowParts(const Window& window) {
  static constexpr double kPartSize = 0.5;  // [m]
  static constexpr int kMaxAutomatic = 8;
  auto count = [](double length) {
    return std::clamp(static_cast<int>(std::ceil(length / kPartSize - 1e-9)), 1, kMaxAutomatic);
  };
  return {count(window.width_m), count(window.height_m)};
}

WindowParts PartsOfWindow(const Window& window, WindowParts parts) {
  const WindowParts automatic = AutomaticWindowParts(window);
  return {parts.columns > 0 ? parts.columns : automatic.columns,
          parts.rows > 0 ? parts.rows : automatic.rows};
}

int WindowCellsOf(const Scene& scene, WindowParts parts, int basis_cells) {
  int cells = 0;
  for (const SceneWindow& w : scene.windows) {
    const WindowParts p = PartsOfWindow(w.window, parts);
    cells += p.columns * p.rows * basis_cells;
  }
  return cells;
}

std::vector<TraceWindow> LocalWindows(const TraceGeometry& geometry, const Scene& scene,
                                      WindowParts parts, const HemisphereBasis& basis) {
  std::vector<TraceWindow> windows;
  for (const SceneWindow& w : scene.windows) {
    windows.push_back(LocalWindow(geometry, w.window, PartsOfWindow(w.window, parts)));
  }
  LinkWindows(basis, &windows);
  return windows;
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
  if (parts.columns < 1 || parts.rows < 1) {
    return absl::InvalidArgumentError(
        absl::StrCat("window parts must be at least 1 in each direction, got '", text, "'"));
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

namespace {

// O of several windows from each window's own: their cell rows one after the other, then the
// identity rows of the direct columns.
OutdoorBatches StackWindows(std::vector<OutdoorBatches> windows, int cells) {
  if (windows.size() == 1) return std::move(windows.front());
  OutdoorBatches o;
  o.paths_per_cell = windows.front().paths_per_cell;
  o.first_escapes.resize(cells);
  for (size_t b = 0; b < windows.front().batches.size(); ++b) {
    Matrix batch(OutdoorRowCount(cells), kDaylightBins);
    int row = 0;
    for (const OutdoorBatches& w : windows) {
      const Eigen::Index rows = w.first_escapes.size();
      batch.middleRows(row, rows) = w.batches[b].topRows(rows);
      row += static_cast<int>(rows);
    }
    batch.middleRows(cells, kDaylightBins).setIdentity();
    batch.bottomRows(kDaylightBins).setIdentity();
    o.batches.push_back(std::move(batch));
  }
  int row = 0;
  for (const OutdoorBatches& w : windows) {
    o.first_escapes.segment(row, w.first_escapes.size()) = w.first_escapes;
    row += static_cast<int>(w.first_escapes.size());
    o.counters.Add(w.counters);
  }
  MeanAndError(o.batches, &o.mean, &o.standard_error);
  return o;
}

}  // namespace

absl::StatusOr<OutdoorResult> ComputeOutdoorStage(const Scene& scene, const OutdoorOptions& options,
                                                  DcBackend* backend) {
  const auto start = std::chrono::steady_clock::now();
  FENESTRA_ASSIGN_OR_RETURN(basis, BasisFor(options.basis_cells));
  FENESTRA_RETURN_IF_ERROR(CheckParts(options.parts));
  FENESTRA_RETURN_IF_ERROR(CheckPaths(options.max_bounces, options.russian_roulette,
                                      options.roulette_threshold, options.threads));
  FENESTRA_RETURN_IF_ERROR(CheckBatches(options.batches));
  const int64_t window_cells = WindowCellsOf(scene, options.parts, basis.cell_count);
  if (options.paths < window_cells * options.batches) {
    return absl::InvalidArgumentError(
        absl::StrCat("outdoor paths must be at least one per window cell and batch (",
                     window_cells * options.batches, "), got ", options.paths));
  }
  FENESTRA_ASSIGN_OR_RETURN(geometry, OutdoorGeometry(scene));
  std::unique_ptr<DcBackend> fallback;
  if (backend == nullptr) backend = (fallback = MakeEmbreeBackend()).get();

  // Trace and form O_b (FormOutdoorBatches; a GPU backend forms them where its sums lie),
  // window by window
  const uint64_t per_cell = static_cast<uint64_t>(options.paths / window_cells);
  const std::vector<TraceWindow> windows = LocalWindows(geometry, scene, options.parts, basis);
  std::vector<OutdoorBatches> each;
  for (int w = 0; w < static_cast<int>(windows.size()); ++w) {
    FENESTRA_ASSIGN_OR_RETURN(
        formed,
        backend->Outdoor(geometry, windows, w, basis, per_cell, options.batches, options.seed,
                         Settings(options.max_bounces, options.russian_roulette,
                                  options.roulette_threshold, options.sequence),
                         options.threads));
    each.push_back(std::move(formed));
  }
  OutdoorBatches formed = StackWindows(std::move(each), static_cast<int>(window_cells));
  OutdoorResult result;
  result.coefficients = std::move(formed.mean);
  result.standard_error = std::move(formed.standard_error);
  result.batches = std::move(formed.batches);
  result.batches_on_device = std::move(formed.batches_on_device);
  result.sky_view = formed.first_escapes / static_cast<double>(formed.paths_per_cell);
  result.paths_per_cell = static_cast<int64_t>(formed.paths_per_cell);
  result.basis_cells = basis.cell_count;
  result.parts = options.parts;
  result.rays_traced = formed.counters.rays;
  result.triangles = geometry.TriangleCount();
  result.backend = backend->Name();
  result.wall_seconds = SecondsSince(start);
  return result;
}

absl::StatusOr<TraceGeometry> OutdoorGeometry(const Scene& scene) {
  return PrepareTraceGeometry(SelectSide(scene.fixed, Side::kOutdoor), scene.materials);
}

absl::StatusOr<TraceGeometry> OutdoorViewGeometry(const Scene& scene) {
  const TriangleMesh outdoor = SelectSide(scene.fixed, Side::kOutdoor);
  TriangleMesh in_front;
  in_front.part_names = outdoor.part_names;
  const auto is_in_front = [](const Vec3d* v, const Window& w) {
    return std::max({Dot(v[0] - w.center, w.normal), Dot(v[1] - w.center, w.normal),
                     Dot(v[2] - w.center, w.normal)}) > 0;
  };
  for (size_t t = 0; t < outdoor.TriangleCount(); ++t) {
    const Vec3d* v = &outdoor.vertices[3 * t];
    if (std::any_of(scene.windows.begin(), scene.windows.end(),
                    [&](const SceneWindow& w) { return is_in_front(v, w.window); })) {
      in_front.Add(v[0], v[1], v[2], outdoor.material[t], Side::kOutdoor, outdoor.part[t]);
    }
  }
  return PrepareTraceGeometry(in_front, scene.materials);
}

Vec3f OutdoorOffset(const TraceGeometry& indoor, const TraceGeometry& outdoor) {
  const Vec3d d = indoor.origin - outdoor.origin;
  return {static_cast<float>(d.x), static_cast<float>(d.y), static_cast<float>(d.z)};
}

std::vector<uint8_t> OutdoorMetCells(const TraceGeometry& indoor, const TraceGeometry& outdoor,
                                     const std::vector<TraceWindow>& windows,
                                     const HemisphereBasis& basis) {
  std::vector<uint8_t> met;
  for (TraceWindow window : windows) {
    window.center = window.center + OutdoorOffset(indoor, outdoor);
    const std::vector<uint8_t> cells = WindowCellsMeetingSurfaces(outdoor, window, basis);
    met.insert(met.end(), cells.begin(), cells.end());
  }
  return met;
}

absl::StatusOr<HemisphereBasis> CheckIndoorOptions(const IndoorOptions& options) {
  FENESTRA_ASSIGN_OR_RETURN(basis, BasisFor(options.basis_cells));
  FENESTRA_RETURN_IF_ERROR(CheckParts(options.parts));
  FENESTRA_RETURN_IF_ERROR(CheckPaths(options.max_bounces, options.russian_roulette,
                                      options.roulette_threshold, options.threads));
  FENESTRA_RETURN_IF_ERROR(CheckBatches(options.batches));
  if (options.paths_per_sensor < options.batches) {
    return absl::InvalidArgumentError(
        absl::StrCat("indoor paths per sensor must be at least the batch count (", options.batches,
                     "), got ", options.paths_per_sensor));
  }
  return basis;
}

absl::Status CheckOutdoorFitsIndoor(const std::vector<Matrix>& outdoor_batches, const Scene& scene,
                                    const IndoorOptions& options) {
  FENESTRA_ASSIGN_OR_RETURN(basis, CheckIndoorOptions(options));
  const Eigen::Index columns =
      OutdoorRowCount(WindowCellsOf(scene, options.parts, basis.cell_count));
  const Eigen::Index rows = outdoor_batches.empty() ? 0 : outdoor_batches[0].rows();
  if (rows != columns || static_cast<int>(outdoor_batches.size()) != options.batches) {
    return absl::InvalidArgumentError(
        absl::StrCat("the outdoor matrix has ", rows, " rows in ", outdoor_batches.size(),
                     " batches, the indoor stage ", columns, " columns in ", options.batches));
  }
  return absl::OkStatus();
}

PathSettings IndoorPathSettings(const IndoorOptions& options) {
  return Settings(options.max_bounces, options.russian_roulette, options.roulette_threshold,
                  options.sequence);
}

IndoorResult IndoorResultFromTally(const IndoorTally& tally, const IndoorOptions& options) {
  IndoorResult result;
  result.parts = options.parts;
  const int sensors = tally.sensors, columns = tally.columns;
  for (int b = 0; b < tally.batches; ++b) {
    Matrix batch(sensors, columns);
    for (int s = 0; s < sensors; ++s) {
      for (int k = 0; k < columns; ++k) {
        batch(s, k) = tally.sum[(static_cast<size_t>(b) * sensors + s) * columns + k] /
                      static_cast<double>(tally.batch_paths[b]);
      }
    }
    result.batches.push_back(std::move(batch));
  }
  MeanAndError(result.batches, &result.coefficients, &result.standard_error);
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
  FENESTRA_ASSIGN_OR_RETURN(outdoor, OutdoorViewGeometry(scene));
  std::unique_ptr<DcBackend> fallback;
  if (backend == nullptr) backend = (fallback = MakeEmbreeBackend()).get();

  // Trace, then I_b = batch sums / batch paths
  FENESTRA_ASSIGN_OR_RETURN(
      tally, backend->Indoor(geometry, outdoor, LocalSensors(geometry, scene.sensors),
                             LocalWindows(geometry, scene, options.parts, basis), basis,
                             static_cast<uint64_t>(options.paths_per_sensor), options.batches,
                             options.seed, IndoorPathSettings(options), options.threads));
  IndoorResult result = IndoorResultFromTally(tally, options);
  result.triangles = indoor.TriangleCount();
  result.backend = backend->Name();
  result.wall_seconds = SecondsSince(start);
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
                                                   " columns, outdoor matrix ",
                                                   outdoor.coefficients.rows(), " rows"));
  }
  if (indoor.batches.size() != outdoor.batches.size() || indoor.batches.size() < 2) {
    return absl::InvalidArgumentError(absl::StrCat("indoor matrix has ", indoor.batches.size(),
                                                   " batches, outdoor matrix ",
                                                   outdoor.batches.size(), "; they pair up"));
  }
  // D_b = I_b O_b; D and its errors from the batches
  TwoStageResult result;
  result.batches =
      SplitBatches(ThroughWindow(indoor.batches, outdoor.batches), indoor.batches.size());
  MeanAndError(result.batches, &result.coefficients, &result.standard_error);
  std::vector<Matrix> sky_sums;
  for (const Matrix& d : result.batches)
    sky_sums.push_back(d.rightCols(kDaylightBins - 1).rowwise().sum());
  Matrix sky_sum, sky_sum_error;
  MeanAndError(sky_sums, &sky_sum, &sky_sum_error);
  result.sky_sum = sky_sum.col(0);
  result.sky_sum_standard_error = sky_sum_error.col(0);
  return result;
}

absl::StatusOr<IndoorTally> IndoorStages::TraceParts(const BlindDesign&, int, int) const {
  return absl::UnimplementedError("these indoor stages trace every design in full");
}

absl::Status CheckDesignParts(int first, int last) {
  if (0 <= first && first < last && last <= kDesignParts) return absl::OkStatus();
  return absl::InvalidArgumentError(
      absl::StrCat("parts [", first, ", ", last, ") of a design's paths, of ", kDesignParts));
}

absl::Status AddIndoorTally(const IndoorTally& more, IndoorTally& into) {
  if (more.sensors != into.sensors || more.columns != into.columns ||
      more.batches != into.batches || more.sum.size() != into.sum.size() ||
      more.batch_paths.size() != into.batch_paths.size()) {
    return absl::InvalidArgumentError("indoor sums of different sensors, columns or batches");
  }
  for (size_t i = 0; i < into.sum.size(); ++i) into.sum[i] += more.sum[i];
  for (size_t b = 0; b < into.batch_paths.size(); ++b) into.batch_paths[b] += more.batch_paths[b];
  into.counters.Add(more.counters);
  into.wall_seconds += more.wall_seconds;
  into.trace_seconds += more.trace_seconds;
  return absl::OkStatus();
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

// The indoor stage, then the annual product's tallies; in parts where the stages trace so.
class StagedDesignTallies : public DesignTallies {
 public:
  StagedDesignTallies(std::unique_ptr<IndoorStages> stages, DcBackend* backend, const Scene& scene,
                      const IndoorOptions& options)
      : stages_(std::move(stages)), backend_(backend), scene_(scene), options_(options) {}

  absl::Status SetProduct(const std::vector<Matrix>& outdoor_batches, const Matrix& sky,
                          const DeviceMatrices&) override {
    FENESTRA_RETURN_IF_ERROR(CheckOutdoorFitsIndoor(outdoor_batches, scene_, options_));
    FENESTRA_ASSIGN_OR_RETURN(product, backend_->MakeAnnualProduct(outdoor_batches, sky));
    product_ = std::move(product);
    return absl::OkStatus();
  }
  absl::StatusOr<std::vector<HourTally>> Tally(const BlindDesign& design,
                                               const MetricOptions& options, int parts) override {
    FENESTRA_RETURN_IF_ERROR(CheckDesignParts(0, parts));
    FENESTRA_RETURN_IF_ERROR(CheckProductSet(product_.get()));
    if (!stages_->TracesInParts()) {
      if (parts != kDesignParts) return stages_->TraceParts(design, 0, parts).status();
      FENESTRA_ASSIGN_OR_RETURN(indoor, stages_->Compute(design));
      rays_ += indoor.rays_traced;
      const std::vector<SunEntry> sun = SunOf(design);
      return WithSunlitHours(product_->Tally(indoor.batches, options, sun), sun, options);
    }
    // The parts not traced yet: all of them for another design
    const bool goes_on = held_parts_ > 0 && design == held_design_ && parts > held_parts_;
    held_parts_ = goes_on ? held_parts_ : 0;
    FENESTRA_ASSIGN_OR_RETURN(more, stages_->TraceParts(design, held_parts_, parts));
    rays_ += more.counters.rays;
    if (goes_on) {
      FENESTRA_RETURN_IF_ERROR(AddIndoorTally(more, held_));
    } else {
      held_ = std::move(more);
    }
    held_design_ = design;
    held_parts_ = parts;
    const std::vector<SunEntry> sun = SunOf(design);
    return WithSunlitHours(
        product_->Tally(IndoorResultFromTally(held_, options_).batches, options, sun), sun,
        options);
  }
  absl::StatusOr<std::vector<Matrix>> IndoorBatches(const BlindDesign& design) override {
    FENESTRA_ASSIGN_OR_RETURN(indoor, stages_->Compute(design));
    rays_ += indoor.rays_traced;
    return std::move(indoor.batches);
  }
  AnnualProduct* Product() override { return product_.get(); }
  bool TracesInParts() const override { return stages_->TracesInParts(); }
  uint64_t RaysTraced() const override { return rays_; }

 private:
  std::unique_ptr<IndoorStages> stages_;
  DcBackend* backend_;
  std::unique_ptr<AnnualProduct> product_;
  Scene scene_;
  IndoorOptions options_;
  // The sums of the design of the last call, over its first held_parts_ parts
  IndoorTally held_;
  BlindDesign held_design_;
  int held_parts_ = 0;
  uint64_t rays_ = 0;
};

}  // namespace

std::vector<SunEntry> DesignTallies::SunOf(const BlindDesign& design) const {
  return sun_ != nullptr ? sun_->Entries(design) : std::vector<SunEntry>{};
}

absl::StatusOr<std::vector<HourTally>> DesignTallies::WithSunlitHours(
    absl::StatusOr<std::vector<HourTally>> versions, const std::vector<SunEntry>& sun,
    const MetricOptions& options) const {
  if (sun_ == nullptr || !versions.ok()) return versions;
  // Exact: the same in every version
  std::vector<int64_t> sunlit(sun_->Sensors(), 0);
  for (const SunEntry& e : sun) sunlit[e.sensor] += e.lux > options.ase_threshold_lux;
  for (HourTally& v : *versions) v.sunlit = sunlit;
  return versions;
}

std::vector<absl::StatusOr<std::vector<HourTally>>> DesignTallies::TallyDesigns(
    const std::vector<BlindDesign>& designs, const MetricOptions& options) {
  std::vector<absl::StatusOr<std::vector<HourTally>>> out;
  for (const BlindDesign& design : designs) out.push_back(Tally(design, options));
  return out;
}

absl::StatusOr<std::vector<Matrix>> DesignTallies::DesignIlluminance(const BlindDesign& design,
                                                                     const Matrix& sky) {
  FENESTRA_RETURN_IF_ERROR(CheckProductSet(Product()));
  FENESTRA_ASSIGN_OR_RETURN(indoor, IndoorBatches(design));
  return Product()->ApplyToSky(indoor, sky);
}

std::vector<absl::StatusOr<std::vector<Matrix>>> DesignTallies::DesignsIlluminance(
    const std::vector<BlindDesign>& designs) {
  std::vector<absl::StatusOr<std::vector<Matrix>>> out;
  for (const BlindDesign& design : designs) {
    if (const absl::Status set = CheckProductSet(Product()); !set.ok()) {
      out.push_back(set);
    } else {
      out.push_back(DesignIlluminance(design, Product()->Sky()));
    }
  }
  return out;
}

absl::Status DesignTallies::SetGlareSteps(GlareSteps steps) {
  FENESTRA_RETURN_IF_ERROR(CheckProductSet(Product()));
  FENESTRA_RETURN_IF_ERROR(CheckGlareSteps(steps, static_cast<int>(steps.sun_factor.rows()),
                                           static_cast<int>(Product()->Sky().cols())));
  glare_steps_ = std::make_unique<const GlareSteps>(std::move(steps));
  return absl::OkStatus();
}

std::vector<absl::StatusOr<GlareCounts>> DesignTallies::GlareDesigns(
    const std::vector<BlindDesign>& designs, const std::vector<std::vector<SunEntry>>& sun) {
  if (glare_steps_ == nullptr) {
    return {designs.size(), absl::FailedPreconditionError("glare: no glare steps set")};
  }
  std::vector<absl::StatusOr<std::vector<Matrix>>> e = DesignsIlluminance(designs);
  std::vector<absl::StatusOr<GlareCounts>> out;
  for (size_t k = 0; k < designs.size(); ++k) {
    if (!e[k].ok()) {
      out.push_back(e[k].status());
      continue;
    }
    out.push_back(CountGlare(
        *e[k], k < sun.size() ? std::span<const SunEntry>(sun[k]) : std::span<const SunEntry>(),
        *glare_steps_));
  }
  return out;
}

absl::StatusOr<std::unique_ptr<DesignTallies>> DcBackend::StartDesignTallies(
    const Scene& scene, const IndoorOptions& options) {
  FENESTRA_ASSIGN_OR_RETURN(stages, MakeIndoorStages(scene, options));
  return std::make_unique<StagedDesignTallies>(std::move(stages), this, scene, options);
}

absl::StatusOr<std::unique_ptr<DesignTallies>> DcBackend::MakeDesignTallies(
    const Scene& scene, const IndoorOptions& options, const std::vector<Matrix>& outdoor_batches,
    const Matrix& sky) {
  FENESTRA_ASSIGN_OR_RETURN(tallies, StartDesignTallies(scene, options));
  FENESTRA_RETURN_IF_ERROR(tallies->SetProduct(outdoor_batches, sky));
  return tallies;
}

absl::StatusOr<std::unique_ptr<IndoorStages>> DcBackend::MakeIndoorStages(
    const Scene& scene, const IndoorOptions& options) {
  FENESTRA_RETURN_IF_ERROR(CheckIndoorOptions(options).status());
  return std::make_unique<TracedIndoorStages>(scene, options, this);
}

}  // namespace fenestra
