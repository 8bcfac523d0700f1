#include "server/limits.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <string>

#include "absl/strings/str_cat.h"
#include "core/common/status_macros.h"
#include "core/common/text.h"
#include "core/sky/epw.h"
#include "core/trace/room_check.h"

namespace fenestra {
namespace {

absl::Status OverLimit(const std::string& what, double value, const std::string& limit,
                       int64_t maximum) {
  const int64_t shown =
      value < 9e18 ? static_cast<int64_t>(value) : int64_t{9'000'000'000'000'000'000};
  return absl::InvalidArgumentError(
      absl::StrCat(what, " is ", shown, ", above this server's limit ", limit, " = ", maximum));
}

// Upper bound on the slats the blind generator can place on `window` (12 triangles each):
// pitch >= w.
double MaxSlats(const v1::Window& window, const v1::VenetianBlind& blind, double min_slat_width_m) {
  double w = min_slat_width_m;
  if (!(w > 0))
    w = blind.slat_width_m().min() > 0 ? blind.slat_width_m().min() : blind.slat_width_m().value();
  if (!(w > 0) || !std::isfinite(w)) return 0;  // invalid; the scene check reports it
  const bool vertical = blind.orientation() == v1::VenetianBlind::VERTICAL;
  const double extent = vertical ? window.width_m() : window.height_m();
  if (!(extent > 0) || !std::isfinite(extent)) return 0;
  return std::ceil(extent / w) + 1;
}

// The same over every blind of the scene, in either window form.
double MaxBlindSlats(const v1::Scene& scene, double min_slat_width_m) {
  double slats = scene.has_blind() ? MaxSlats(scene.window(), scene.blind(), min_slat_width_m) : 0;
  for (const v1::Window& w : scene.windows()) {
    if (w.has_blind()) slats += MaxSlats(w, w.blind(), min_slat_width_m);
  }
  return slats;
}

}  // namespace

absl::Status CheckInlineScene(const v1::Scene& scene) {
  for (int i = 0; i < scene.surfaces_size(); ++i) {
    const v1::Surface& s = scene.surfaces(i);
    if (s.has_obj()) {
      return absl::InvalidArgumentError(absl::StrCat(
          "surfaces[", i, "] ('", s.name(), "'): OBJ mesh '", s.obj().path(),
          "' is a file on the client; send it inline as polygons (fenestra job submit and "
          "fenestra site add do this)"));
    }
  }
  return absl::OkStatus();
}

absl::Status CheckSceneLimits(const v1::Scene& scene, const v1::Limits& limits,
                              double min_slat_width_m) {
  double triangles = 0;
  for (const v1::Surface& s : scene.surfaces()) {
    if (s.has_polygon()) triangles += std::max(0, s.polygon().vertices_size() - 2);
    if (s.has_box()) triangles += 12;
  }
  triangles += 12 * MaxBlindSlats(scene, min_slat_width_m);
  if (triangles > limits.max_triangles()) {
    return OverLimit("the scene's triangle count (the blind at its most slats included)", triangles,
                     "max_triangles", limits.max_triangles());
  }
  // Each view point is traced as a sensor is (the glare at a job's best design)
  double sensors = scene.sensors_size() + scene.views_size();
  for (const v1::SensorGrid& g : scene.sensor_grids()) {
    if (!(g.spacing_m() > 0)) continue;  // invalid; the scene check reports it
    const double nx = std::floor((g.x_max_m() - g.x_min_m()) / g.spacing_m()) + 1;
    const double ny = std::floor((g.y_max_m() - g.y_min_m()) / g.spacing_m()) + 1;
    if (nx > 0 && ny > 0) sensors += nx * ny;
  }
  if (!(sensors <= limits.max_sensors())) {
    return OverLimit("the scene's sensor count (grids expanded, views included)", sensors,
                     "max_sensors", limits.max_sensors());
  }
  return absl::OkStatus();
}

absl::Status CheckSamplingLimits(const v1::Sampling& sampling, const v1::Limits& limits,
                                 bool indoor) {
  if (sampling.outdoor_paths() > limits.max_outdoor_paths()) {
    return OverLimit("sampling.outdoor_paths", static_cast<double>(sampling.outdoor_paths()),
                     "max_outdoor_paths", limits.max_outdoor_paths());
  }
  if (indoor && sampling.indoor_paths_per_sensor() > limits.max_indoor_paths_per_sensor()) {
    return OverLimit("sampling.indoor_paths_per_sensor",
                     static_cast<double>(sampling.indoor_paths_per_sensor()),
                     "max_indoor_paths_per_sensor", limits.max_indoor_paths_per_sensor());
  }
  if (indoor && sampling.candidates_at_once() > limits.max_candidates_at_once()) {
    return OverLimit("sampling.candidates_at_once", sampling.candidates_at_once(),
                     "max_candidates_at_once", limits.max_candidates_at_once());
  }
  return absl::OkStatus();
}

absl::Status CheckBudgetLimits(const v1::Budget& budget, const v1::Limits& limits) {
  const int evaluations =
      budget.max_evaluations() > 0 ? budget.max_evaluations() : kDefaultMaxEvaluations;
  if (evaluations > limits.max_evaluations()) {
    return OverLimit("budget.max_evaluations", evaluations, "max_evaluations",
                     limits.max_evaluations());
  }
  return absl::OkStatus();
}

absl::Status CheckUploadedWeather(const std::string& bytes, const std::string& weather_name) {
  const bool named = !weather_name.empty() && CheckText(weather_name, "").ok();
  const std::string source =
      named ? absl::StrCat("weather_epw ('", weather_name, "')") : std::string("weather_epw");
  return ParseEpw(bytes, source).status();
}

absl::StatusOr<CheckedSite> CheckSiteRequest(const v1::RegisterSiteRequest& request,
                                             const v1::DaemonConfig& config) {
  FENESTRA_RETURN_IF_ERROR(CheckMessageText(request, ""));
  if (!request.has_scene()) return absl::InvalidArgumentError("scene: is required");
  FENESTRA_RETURN_IF_ERROR(CheckInlineScene(request.scene()));
  FENESTRA_RETURN_IF_ERROR(CheckSceneLimits(request.scene(), config.limits()));
  CheckedSite site;
  v1::Sampling sampling = request.sampling();
  if (sampling.backend().empty()) sampling.set_backend(config.backend());
  FENESTRA_ASSIGN_OR_RETURN(resolved, ResolveSampling(sampling));
  FENESTRA_RETURN_IF_ERROR(CheckSamplingLimits(resolved, config.limits(), /*indoor=*/false));
  site.sampling = resolved;
  FENESTRA_ASSIGN_OR_RETURN(built, ValidateScene(request.scene(), "scene"));
  built.site.weather_file.clear();  // a path on the client, never read here
  site.scene = std::move(built);
  if (!request.weather_epw().empty()) {
    FENESTRA_RETURN_IF_ERROR(CheckUploadedWeather(request.weather_epw(), request.weather_name()));
  }
  return site;
}

absl::StatusOr<CheckedJob> CheckJobRequest(
    const v1::SubmitJobRequest& request, const v1::DaemonConfig& config,
    const std::function<bool(const std::string&)>& parsed_before) {
  FENESTRA_RETURN_IF_ERROR(CheckMessageText(request, ""));
  const v1::Limits& limits = config.limits();
  CheckedJob checked;
  v1::Job& job = checked.job;
  job = request.job();
  if (!job.scene_file().empty()) {
    return absl::InvalidArgumentError(absl::StrCat(
        "job.scene_file '", job.scene_file(),
        "' is a path on the client; send the scene inline in job.scene (fenestra job submit "
        "does this)"));
  }
  if (!job.has_scene()) {
    return absl::InvalidArgumentError("job.scene: is required (the scene, inline)");
  }
  FENESTRA_RETURN_IF_ERROR(CheckInlineScene(job.scene()));
  double min_slat_width_m = 0;
  for (const v1::DesignVariable& v : job.variables()) {
    if (v.name() == "width") min_slat_width_m = v.fixed() ? v.start() : v.lower();
  }
  FENESTRA_RETURN_IF_ERROR(CheckSceneLimits(job.scene(), limits, min_slat_width_m));
  FENESTRA_RETURN_IF_ERROR(CheckBudgetLimits(job.budget(), limits));
  if (job.sampling().backend().empty()) {
    job.mutable_sampling()->set_backend(
        request.default_backend().empty() ? config.backend() : request.default_backend());
  }
  FENESTRA_ASSIGN_OR_RETURN(sampling, ResolveSampling(job.sampling()));
  FENESTRA_RETURN_IF_ERROR(CheckSamplingLimits(sampling, limits, /*indoor=*/true));
  v1::Job without_paths = job;
  without_paths.clear_weather_file();
  without_paths.mutable_scene()->mutable_site()->clear_weather_file();
  FENESTRA_ASSIGN_OR_RETURN(prepared, ValidateJob(without_paths, ""));
  checked.prepared = std::move(prepared);
  if (!request.weather_epw().empty() && !(parsed_before && parsed_before(request.weather_epw()))) {
    FENESTRA_RETURN_IF_ERROR(CheckUploadedWeather(request.weather_epw(), request.weather_name()));
  }
  return checked;
}

}  // namespace fenestra
