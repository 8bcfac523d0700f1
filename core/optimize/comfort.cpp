#include "core/optimize/comfort.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <utility>
#include <vector>

#include "absl/strings/str_cat.h"
#include "core/common/status_macros.h"
#include "core/geometry/blind.h"
#include "core/metrics/glare.h"
#include "core/metrics/illuminance.h"
#include "core/optimize/hourly_illuminance.h"
#include "core/optimize/vns.h"

namespace fenestra {
namespace {

// How far the gain plane lies behind the window's outer face [m].
double GainPlaneDepth(const SceneWindow& w) {
  if (!w.blind) return w.window.depth_m + kGainPlaneClearanceM;
  const BlindEnvelope envelope = EnvelopeOfBlind(w.window, *w.blind, 0);
  const double centre_depth = Dot(w.window.center - envelope.center, w.window.normal);
  return centre_depth + envelope.half_extent[2] + kGainPlaneClearanceM;
}

// The distance from `origin` along unit `direction` to the nearest triangle of `mesh`, at
// most `limit` (Moller-Trumbore, every triangle: the margins need a few rays per window).
double FreeDistance(const TriangleMesh& mesh, Vec3d origin, Vec3d direction, double limit) {
  double nearest = limit;
  for (size_t t = 0; t < mesh.TriangleCount(); ++t) {
    const Vec3d a = mesh.vertices[3 * t], b = mesh.vertices[3 * t + 1],
                c = mesh.vertices[3 * t + 2];
    const Vec3d e1 = b - a, e2 = c - a;
    const Vec3d p = Cross(direction, e2);
    const double det = Dot(e1, p);
    if (std::abs(det) < 1e-14) continue;
    const Vec3d s = origin - a;
    const double u = Dot(s, p) / det;
    if (u < 0 || u > 1) continue;
    const Vec3d q = Cross(s, e1);
    const double v = Dot(direction, q) / det;
    if (v < 0 || u + v > 1) continue;
    const double d = Dot(e2, q) / det;
    if (d > 0 && d < nearest) nearest = d;
  }
  return nearest;
}

// A window's gain plane: its centre, in-plane axes, the half extents on each side of the
// centre (-across, +across, -up, +up) and the depth behind the outer face.
struct GainPlane {
  Vec3d center;
  double half[4] = {0, 0, 0, 0};
};

GainPlane GainPlaneOf(const Scene& scene, const SceneWindow& w) {
  const Window& win = w.window;
  const double depth = GainPlaneDepth(w);
  GainPlane plane;
  plane.center = win.center - depth * win.normal;
  // The margin, where the room leaves space for it: up to the nearest surface beside the
  // opening, kept clear of it
  const double margin = kGainMarginPerDepth * std::max(0.0, depth - win.depth_m);
  const Vec3d directions[4] = {-win.across, win.across, -win.up, win.up};
  const double half_opening[4] = {0.5 * win.width_m, 0.5 * win.width_m, 0.5 * win.height_m,
                                  0.5 * win.height_m};
  for (int k = 0; k < 4; ++k) {
    const double reach = half_opening[k] + margin;
    const double free = FreeDistance(scene.fixed, plane.center, directions[k], reach);
    plane.half[k] = std::max(half_opening[k] * 0.5, free - kGainPlaneClearanceM);
    plane.half[k] = std::min(plane.half[k], reach);
  }
  return plane;
}

// Whether `p` lies within window `w`'s zone: between its outer face and its gain plane,
// within the plane's extent (and a clearance).
bool InWindowZone(const SceneWindow& w, const GainPlane& plane, Vec3d p) {
  const Window& win = w.window;
  const double depth = Dot(win.center - p, win.normal);
  if (depth < -kGainPlaneClearanceM || depth > GainPlaneDepth(w) + kGainPlaneClearanceM) {
    return false;
  }
  const double a = Dot(p - plane.center, win.across), u = Dot(p - plane.center, win.up);
  return a >= -plane.half[0] - kGainPlaneClearanceM && a <= plane.half[1] + kGainPlaneClearanceM &&
         u >= -plane.half[2] - kGainPlaneClearanceM && u <= plane.half[3] + kGainPlaneClearanceM;
}

// The delete-one jackknife of a figure linear in the batches: its value and standard error
// from the batch values.
Estimated LinearEstimate(std::span<const double> batch_values) {
  const double count = static_cast<double>(batch_values.size());
  double sum = 0;
  for (const double v : batch_values) sum += v;
  std::vector<double> without;
  for (const double v : batch_values) without.push_back((sum - v) / (count - 1));
  return {sum / count, JackknifeStandardError(without)};
}

// What decides a glare step of `views` under `sky`: its occupied steps, threshold and
// per view the sun's geometric factor in each column.
GlareSteps GlareStepsOf(const std::vector<ViewPoint>& views, const ComfortSky& sky) {
  GlareSteps steps;
  steps.occupied = sky.occupied_column;
  steps.threshold = sky.glare_threshold;
  const Eigen::Index columns = static_cast<Eigen::Index>(sky.columns.size());
  steps.sun_factor = Matrix::Zero(static_cast<Eigen::Index>(views.size()), columns);
  for (const SunColumn& s : sky.suns) {
    for (size_t v = 0; v < views.size(); ++v) {
      steps.sun_factor(static_cast<Eigen::Index>(v), s.column) =
          SunGlareFactor(views[v].direction, views[v].up, s.direction);
    }
  }
  return steps;
}

}  // namespace

// One set of comfort sensors: its scene, its backend (its own tracer), tallies and sun.
struct DesignComfort::Part {
  Scene scene;
  std::unique_ptr<DcBackend> backend;
  std::unique_ptr<DesignTallies> tallies;
  std::unique_ptr<DirectSun> sun;
};

ComfortNeeds NeedsOf(std::span<const SceneMetric> metrics) {
  ComfortNeeds needs;
  for (const SceneMetric m : metrics) {
    needs.glare |= m == SceneMetric::kGlareAutonomy || m == SceneMetric::kGlareHours;
    needs.gains |= m == SceneMetric::kSolarGain || m == SceneMetric::kCoolingSolarGain;
  }
  return needs;
}

GainPoints GainPointsOf(const Scene& scene) {
  GainPoints points;
  // The R2 sequence (Roberts 2018): well spread for any count, no grid to alias with the slats
  constexpr double kG = 1.32471795724474602596;
  constexpr double kA1 = 1 / kG, kA2 = 1 / (kG * kG);
  for (const SceneWindow& w : scene.windows) {
    const GainPlane plane = GainPlaneOf(scene, w);
    const double width = plane.half[0] + plane.half[1], height = plane.half[2] + plane.half[3];
    for (int k = 0; k < kGainPointsPerWindow; ++k) {
      const double s = std::fmod(0.5 + kA1 * (k + 1), 1.0), t = std::fmod(0.5 + kA2 * (k + 1), 1.0);
      const Vec3d p = plane.center + (s * width - plane.half[0]) * w.window.across +
                      (t * height - plane.half[2]) * w.window.up;
      points.sensors.push_back(
          {absl::StrCat(w.name, " gain ", k), p, w.window.normal, absl::StrCat(w.name, ".gain")});
      points.area_m2.push_back(width * height / kGainPointsPerWindow);
    }
  }
  return points;
}

Scene GainScene(const Scene& scene, const GainPoints& points) {
  Scene out = scene;
  out.sensors = points.sensors;
  out.views.clear();
  std::vector<GainPlane> planes;
  for (const SceneWindow& w : scene.windows) planes.push_back(GainPlaneOf(scene, w));
  const uint32_t black = static_cast<uint32_t>(out.materials.size());
  out.materials.push_back({.name = "gain black", .reflectance = 0});
  for (size_t t = 0; t < out.fixed.TriangleCount(); ++t) {
    if (out.materials[out.fixed.material[t]].transmittance >= 0) continue;  // glazing stays
    const Vec3d centroid = (out.fixed.vertices[3 * t] + out.fixed.vertices[3 * t + 1] +
                            out.fixed.vertices[3 * t + 2]) /
                           3.0;
    bool zone = false;
    for (size_t w = 0; w < scene.windows.size() && !zone; ++w) {
      zone = InWindowZone(scene.windows[w], planes[w], centroid);
    }
    if (!zone) out.fixed.material[t] = black;
  }
  return out;
}

CoolingSeason DefaultCoolingSeason(double latitude_deg) {
  return latitude_deg >= 0 ? CoolingSeason{5, 9} : CoolingSeason{11, 3};
}

absl::StatusOr<ComfortSky> MakeComfortSky(const SkyMatrix& visible, const SkyMatrix& solar,
                                          std::vector<int> columns,
                                          const std::vector<bool>& occupied, double glare_threshold,
                                          CoolingSeason season) {
  if (solar.steps.size() != visible.steps.size() || occupied.size() != visible.steps.size()) {
    return absl::InvalidArgumentError("comfort: the solar and visible skies differ in steps");
  }
  ComfortSky sky;
  sky.columns = std::move(columns);
  FENESTRA_ASSIGN_OR_RETURN(lit_sky, SplitSkyColumnsInLux(visible, sky.columns));
  sky.lit_sky = std::move(lit_sky);
  sky.suns = SunColumnsOf(visible, sky.columns);
  for (const int c : sky.columns) sky.occupied_column.push_back(occupied[c]);
  sky.occupied_hours = static_cast<int>(std::count(occupied.begin(), occupied.end(), true));
  sky.glare_threshold = glare_threshold;

  const std::vector<int> lit = LitColumns(solar.radiance);
  FENESTRA_ASSIGN_OR_RETURN(split, SplitSkyColumnsInLux(solar, lit, 1.0));
  sky.gain_sky = Matrix::Zero(split.rows(), 2);
  for (size_t c = 0; c < lit.size(); ++c) {
    const bool in_season = season.Contains(solar.steps[lit[c]].month);
    sky.gain_in_season.push_back(in_season);
    sky.gain_sky.col(0) += split.col(static_cast<Eigen::Index>(c));  // one hour per step
    if (in_season) sky.gain_sky.col(1) += split.col(static_cast<Eigen::Index>(c));
  }
  sky.gain_suns = SunColumnsOf(solar, lit, 1.0);
  sky.gain_columns = static_cast<int>(lit.size());
  return sky;
}

DesignComfort::~DesignComfort() = default;

absl::StatusOr<std::unique_ptr<DesignComfort>> DesignComfort::Start(const Scene& ranged,
                                                                    const IndoorOptions& indoor,
                                                                    const DcBackend& lane,
                                                                    ComfortNeeds needs) {
  if (needs.glare && ranged.views.empty()) {
    return absl::InvalidArgumentError(absl::StrCat(
        ranged.source_path, ": glare metrics need view points in the scene (scene.proto, views)"));
  }
  auto comfort = std::unique_ptr<DesignComfort>(new DesignComfort());
  comfort->needs_ = needs;
  comfort->views_ = ranged.views;
  const auto start = [&](Scene scene,
                         const IndoorOptions& options) -> absl::StatusOr<std::unique_ptr<Part>> {
    auto part = std::make_unique<Part>();
    part->scene = std::move(scene);
    if (lane.Gpu() >= 0) {
      FENESTRA_ASSIGN_OR_RETURN(backend, MakeCudaBackend(lane.Gpu()));
      part->backend = std::move(backend);
    } else {
      part->backend = MakeEmbreeBackend();
    }
    FENESTRA_ASSIGN_OR_RETURN(tallies, part->backend->StartDesignTallies(part->scene, options));
    part->tallies = std::move(tallies);
    return part;
  };
  if (needs.glare) {
    Scene eyes = ranged;
    eyes.sensors.clear();
    for (const ViewPoint& v : ranged.views) eyes.sensors.push_back(EyeSensor(v));
    FENESTRA_ASSIGN_OR_RETURN(part, start(std::move(eyes), indoor));
    comfort->eyes_ = std::move(part);
  }
  if (needs.gains) {
    const GainPoints points = GainPointsOf(ranged);
    comfort->gain_area_m2_ = points.area_m2;
    IndoorOptions options = indoor;
    // Fewer paths per point, still a whole number per batch and part
    const int64_t unit = static_cast<int64_t>(indoor.batches) * kDesignParts;
    options.paths_per_sensor =
        std::max(unit, (indoor.paths_per_sensor / kGainPathsDivisor + unit - 1) / unit * unit);
    FENESTRA_ASSIGN_OR_RETURN(part, start(GainScene(ranged, points), options));
    comfort->gains_ = std::move(part);
  }
  return comfort;
}

absl::Status DesignComfort::SetSky(const std::vector<Matrix>& outdoor_batches,
                                   std::shared_ptr<const ComfortSky> sky) {
  sky_ = std::move(sky);
  if (eyes_) {
    FENESTRA_RETURN_IF_ERROR(eyes_->tallies->SetProduct(outdoor_batches, sky_->lit_sky));
    FENESTRA_ASSIGN_OR_RETURN(
        sun, DirectSun::Trace(eyes_->scene, sky_->suns, static_cast<int>(sky_->columns.size())));
    eyes_->sun = std::move(sun);
    FENESTRA_RETURN_IF_ERROR(eyes_->tallies->SetGlareSteps(GlareStepsOf(views_, *sky_)));
  }
  if (gains_) {
    FENESTRA_RETURN_IF_ERROR(gains_->tallies->SetProduct(outdoor_batches, sky_->gain_sky));
    FENESTRA_ASSIGN_OR_RETURN(sun,
                              DirectSun::Trace(gains_->scene, sky_->gain_suns, sky_->gain_columns));
    gains_->sun = std::move(sun);
  }
  return absl::OkStatus();
}

absl::StatusOr<ComfortEstimate> DesignComfort::Evaluate(const BlindDesign& design) {
  return std::move(EvaluateDesigns({design}).front());
}

std::vector<absl::StatusOr<ComfortEstimate>> DesignComfort::EvaluateDesigns(
    const std::vector<BlindDesign>& designs) {
  if (sky_ == nullptr) {
    return {designs.size(), absl::FailedPreconditionError("comfort: no sky set")};
  }
  const auto start = std::chrono::steady_clock::now();
  std::vector<absl::StatusOr<ComfortEstimate>> out(designs.size(), ComfortEstimate{});
  // Each part's figures of its product's own sky, the designs' paths replayed together
  const auto take = [&](auto per_design, auto figures) {
    for (size_t i = 0; i < designs.size(); ++i) {
      if (!out[i].ok()) continue;
      if (!per_design[i].ok()) {
        out[i] = per_design[i].status();
        continue;
      }
      (this->*figures)(designs[i], *per_design[i], *out[i]);
    }
  };
  if (eyes_ != nullptr) {
    std::vector<std::vector<SunEntry>> sun;
    for (const BlindDesign& design : designs) sun.push_back(eyes_->sun->Entries(design));
    take(eyes_->tallies->GlareDesigns(designs, sun), &DesignComfort::GlareOf);
  }
  if (gains_ != nullptr)
    take(gains_->tallies->DesignsIlluminance(designs), &DesignComfort::GainsOf);
  for (absl::StatusOr<ComfortEstimate>& o : out) {
    if (!o.ok()) continue;
    o->glare = eyes_ != nullptr;
    o->gains = gains_ != nullptr;
  }
  seconds_ += std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return out;
}

void DesignComfort::GlareOf(const BlindDesign&, const GlareCounts& counts,
                            ComfortEstimate& out) const {
  const int views = static_cast<int>(views_.size());
  const double occupied = std::max(1, sky_->occupied_hours);
  // Version 0: the mean of the batches; version 1 + b: the mean without batch b
  std::vector<double> autonomy, hours;
  for (size_t version = 0; version < counts.any_steps.size(); ++version) {
    double mean_autonomy = 0;
    for (int v = 0; v < views; ++v) {
      mean_autonomy +=
          100.0 * (1 - static_cast<double>(counts.view_steps[version][v]) / occupied) / views;
    }
    autonomy.push_back(mean_autonomy);
    hours.push_back(100.0 * static_cast<double>(counts.any_steps[version]) / occupied);
  }
  out.value.glare_autonomy_percent = autonomy[0];
  out.value.glare_hours_percent = hours[0];
  out.standard_error.glare_autonomy_percent =
      JackknifeStandardError(std::span<const double>(autonomy).subspan(1));
  out.standard_error.glare_hours_percent =
      JackknifeStandardError(std::span<const double>(hours).subspan(1));
}

void DesignComfort::GainsOf(const BlindDesign& design, const std::vector<Matrix>& batches,
                            ComfortEstimate& out) const {
  // The beam, exact: the same in every batch [Wh]
  double sun_year = 0, sun_season = 0;
  for (const SunEntry& e : gains_->sun->Entries(design)) {
    const double wh = e.lux * gain_area_m2_[e.sensor];
    sun_year += wh;
    if (sky_->gain_in_season[e.column]) sun_season += wh;
  }
  std::vector<double> year, season;
  for (const Matrix& b : batches) {
    double y = sun_year, s = sun_season;
    for (Eigen::Index p = 0; p < b.rows(); ++p) {
      y += gain_area_m2_[p] * b(p, 0);
      s += gain_area_m2_[p] * b(p, 1);
    }
    year.push_back(y / 1000);  // kWh
    season.push_back(s / 1000);
  }
  const Estimated y = LinearEstimate(year), s = LinearEstimate(season);
  out.value.solar_gain_kwh = y.value;
  out.standard_error.solar_gain_kwh = y.standard_error;
  out.value.cooling_solar_gain_kwh = s.value;
  out.standard_error.cooling_solar_gain_kwh = s.standard_error;
}

uint64_t DesignComfort::RaysTraced() const {
  return (eyes_ ? eyes_->tallies->RaysTraced() : 0) + (gains_ ? gains_->tallies->RaysTraced() : 0);
}

void AddComfort(const ComfortEstimate& comfort, AnnualMetricsEstimate& estimate) {
  SceneMetrics& v = estimate.value.scene;
  SceneMetrics& se = estimate.standard_error.scene;
  v.glare_autonomy_percent = comfort.value.glare_autonomy_percent;
  v.glare_hours_percent = comfort.value.glare_hours_percent;
  v.solar_gain_kwh = comfort.value.solar_gain_kwh;
  v.cooling_solar_gain_kwh = comfort.value.cooling_solar_gain_kwh;
  se.glare_autonomy_percent = comfort.standard_error.glare_autonomy_percent;
  se.glare_hours_percent = comfort.standard_error.glare_hours_percent;
  se.solar_gain_kwh = comfort.standard_error.solar_gain_kwh;
  se.cooling_solar_gain_kwh = comfort.standard_error.cooling_solar_gain_kwh;
  estimate.has_glare = comfort.glare;
  estimate.has_gains = comfort.gains;
}

}  // namespace fenestra
