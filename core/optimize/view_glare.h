#pragma once

// The glare at a scene's view points over a year (core/README.md, "Glare"): each view's
// vertical eye illuminance per time step, as a sensor at the eye facing the view direction
// traced by the one-stage method with the direct sun where it is (E = D S - D_0 S_sun +
// E_sun), its DGP per step with the sun as glare source where its beam reaches the eye, and
// annual figures (core/metrics/glare.h), with standard errors by the delete-one jackknife over
// the batches (core/metrics/metric_errors.h).
#include <string>
#include <vector>

#include "absl/status/statusor.h"
#include "core/common/radiance_matrix.h"
#include "core/dc/dc_backend.h"
#include "core/geometry/scene.h"
#include "core/metrics/glare.h"
#include "core/sky/sky_matrix.h"
#include "fenestra/v1/job.pb.h"

namespace fenestra {

struct ViewGlareOptions {
  OneStageOptions tracing;  // its batches (at least 2) give the standard errors
  double threshold = kDefaultGlareThreshold;
};

struct ViewGlareResult {
  std::vector<ViewGlare> views;  // in the scene's order
  // Standard errors of each view's glare autonomy [points] and mean DGP
  std::vector<double> autonomy_standard_error, mean_dgp_standard_error;
  Matrix eye_lux;  // views x every step of the sky [lx], night steps 0
  Matrix eye_lux_standard_error;
  Matrix sun_lux;  // the sun's beam alone at each eye [lx], exact
  Matrix dgp;      // views x steps: DgpWithSun of eye_lux and sun_lux
  int64_t paths_per_view = 0;
  double seconds = 0;
};

// The glare of `scene`'s views at `design` under `sky` (a Tregenza sky matrix with the sun)
// over the steps `occupied` marks (one flag per step). InvalidArgument for a scene without a
// view, fewer than 2 batches or flags that do not match the sky's steps; errors of the tracing.
absl::StatusOr<ViewGlareResult> ComputeViewGlare(const Scene& scene, const BlindDesign& design,
                                                 const SkyMatrix& sky,
                                                 const std::vector<bool>& occupied,
                                                 const ViewGlareOptions& options,
                                                 DcBackend* backend = nullptr);

// `result`'s figures of each of `scene`'s views, as a job result holds them.
std::vector<v1::ViewGlare> ViewGlareProtos(const Scene& scene, const ViewGlareResult& result);

}  // namespace fenestra
