#include "core/optimize/view_glare.h"

#include <chrono>
#include <cmath>

#include "absl/strings/str_cat.h"
#include "core/common/seconds.h"
#include "core/common/status_macros.h"
#include "core/dc/direct_sun.h"
#include "core/dc/one_stage.h"
#include "core/metrics/illuminance.h"
#include "core/metrics/metric_errors.h"
#include "core/optimize/hourly_illuminance.h"

namespace fenestra {
namespace {

// The DGP with the sun of view `v` at every step of `sky`, from its eye illuminance `eye` at
// the steps `lit` (views x lit steps, lx; negative noise read as 0) and the sun's beam alone
// `sun` (the same layout); the other steps are dark (DGP of 0 lx).
std::vector<double> HourlyDgp(const Matrix& eye, const Matrix& sun, int v, const ViewPoint& view,
                              const SkyMatrix& sky, const std::vector<int>& lit) {
  std::vector<double> dgp(sky.steps.size(), Dgp(0, {}));
  for (size_t c = 0; c < lit.size(); ++c) {
    const Eigen::Index i = static_cast<Eigen::Index>(c);
    dgp[lit[c]] = DgpWithSun(std::max(0.0, eye(v, i)), sun(v, i), view.direction, view.up,
                             SunDirection(sky.steps[lit[c]]));
  }
  return dgp;
}

}  // namespace

absl::StatusOr<ViewGlareResult> ComputeViewGlare(const Scene& scene, const BlindDesign& design,
                                                 const SkyMatrix& sky,
                                                 const std::vector<bool>& occupied,
                                                 const ViewGlareOptions& options,
                                                 DcBackend* backend) {
  const auto start = std::chrono::steady_clock::now();
  if (scene.views.empty()) {
    return absl::InvalidArgumentError(
        absl::StrCat(scene.source_path, ": the scene has no view points (scene.proto, views)"));
  }
  if (options.tracing.batches < 2) {
    return absl::InvalidArgumentError(absl::StrCat(
        "glare needs at least 2 batches for its standard errors, got ", options.tracing.batches));
  }
  const int steps = static_cast<int>(sky.steps.size());
  if (static_cast<int>(occupied.size()) != steps) {
    return absl::InvalidArgumentError(
        absl::StrCat("glare: ", occupied.size(), " occupancy flags for ", steps, " sky steps"));
  }
  // The eyes as sensors of the same room
  Scene eyes = scene;
  eyes.sensors.clear();
  for (const ViewPoint& v : scene.views) eyes.sensors.push_back(EyeSensor(v));
  const int views = static_cast<int>(eyes.sensors.size());

  FENESTRA_ASSIGN_OR_RETURN(traced, ComputeOneStage(eyes, design, options.tracing, backend));
  const std::vector<int> lit = LitColumns(sky.radiance);
  FENESTRA_ASSIGN_OR_RETURN(split, SplitSkyColumnsInLux(sky, lit));
  FENESTRA_ASSIGN_OR_RETURN(
      sun, DirectSun::Trace(eyes, SunColumnsOf(sky, lit), static_cast<int>(lit.size())));
  const Matrix sun_lux = sun->Illuminance(design);

  // Each batch's eye illuminance, E_b = [D_b D_0,b] [S; -S_sun] + E_sun
  std::vector<Matrix> batches;
  for (size_t b = 0; b < traced.batch_coefficients.size(); ++b) {
    const Matrix& d = traced.batch_coefficients[b];
    Matrix both(d.rows(), 2 * d.cols());
    both << d, traced.batch_direct_coefficients[b];
    batches.push_back(both * split + sun_lux);
  }
  const double count = static_cast<double>(batches.size());
  Matrix mean = Matrix::Zero(views, static_cast<Eigen::Index>(lit.size()));
  for (const Matrix& e : batches) mean += e / count;
  Matrix squares = Matrix::Zero(mean.rows(), mean.cols());
  for (const Matrix& e : batches) squares += (e - mean).cwiseAbs2();
  const Matrix error = (squares / (count - 1) / count).cwiseSqrt();

  ViewGlareResult result;
  result.eye_lux = Matrix::Zero(views, steps);
  result.eye_lux_standard_error = Matrix::Zero(views, steps);
  result.sun_lux = Matrix::Zero(views, steps);
  for (size_t c = 0; c < lit.size(); ++c) {
    const Eigen::Index i = static_cast<Eigen::Index>(c);
    result.eye_lux.col(lit[c]) = mean.col(i).cwiseMax(0.0);
    result.eye_lux_standard_error.col(lit[c]) = error.col(i);
    result.sun_lux.col(lit[c]) = sun_lux.col(i);
  }
  result.dgp = Matrix::Zero(views, steps);
  for (int v = 0; v < views; ++v) {
    const ViewPoint& view = scene.views[v];
    std::vector<bool> sunlit(steps, false);
    for (int s = 0; s < steps; ++s) sunlit[s] = result.sun_lux(v, s) > 0;
    const std::vector<double> dgp = HourlyDgp(mean, sun_lux, v, view, sky, lit);
    for (int s = 0; s < steps; ++s) result.dgp(v, s) = dgp[s];
    FENESTRA_ASSIGN_OR_RETURN(glare, GlareOfView(dgp, occupied, options.threshold, sunlit));
    result.views.push_back(glare);
    // The errors by the delete-one jackknife over the batches (metric_errors.h): the figures
    // of E_(-b) = (B E - E_b) / (B - 1)
    std::vector<double> autonomy, mean_dgp;
    for (const Matrix& e : batches) {
      const Matrix without = (count * mean - e) / (count - 1);
      FENESTRA_ASSIGN_OR_RETURN(g, GlareOfView(HourlyDgp(without, sun_lux, v, view, sky, lit),
                                               occupied, options.threshold));
      autonomy.push_back(g.autonomy_percent);
      mean_dgp.push_back(g.mean_dgp);
    }
    result.autonomy_standard_error.push_back(JackknifeStandardError(autonomy));
    result.mean_dgp_standard_error.push_back(JackknifeStandardError(mean_dgp));
  }
  result.paths_per_view = traced.paths_per_sensor;
  result.seconds = SecondsSince(start);
  return result;
}

std::vector<v1::ViewGlare> ViewGlareProtos(const Scene& scene, const ViewGlareResult& result) {
  std::vector<v1::ViewGlare> out;
  for (size_t v = 0; v < result.views.size(); ++v) {
    const ViewGlare& g = result.views[v];
    v1::ViewGlare& p = out.emplace_back();
    p.set_view(scene.views[v].name);
    p.mutable_autonomy()->set_value(g.autonomy_percent);
    p.mutable_autonomy()->set_standard_error(result.autonomy_standard_error[v]);
    p.mutable_mean_dgp()->set_value(g.mean_dgp);
    p.mutable_mean_dgp()->set_standard_error(result.mean_dgp_standard_error[v]);
    p.set_dgp_95(g.dgp_95);
    p.set_en17037(std::string(En17037GlareName(g.en17037)));
    for (const int hours : g.class_hours) p.add_class_hours(hours);
    p.set_sunlit_hours(g.sunlit_hours);
    p.set_analysed_hours(g.occupied_hours);
  }
  return out;
}

}  // namespace fenestra
