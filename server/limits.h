#pragma once

#include <functional>
#include <string>

#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "core/geometry/scene.h"
#include "core/optimize/job.h"
#include "fenestra/v1/daemon.pb.h"
#include "fenestra/v1/job.pb.h"
#include "fenestra/v1/scene.pb.h"
#include "fenestra/v1/service.pb.h"

namespace fenestra {

// Checks that a scene sent to the daemon is self-contained: no OBJ mesh paths (files on
// the client), no scene_file. InvalidArgument naming the surface otherwise.
absl::Status CheckInlineScene(const v1::Scene& scene);

// Checks a scene message against the limits before it is built: triangles (polygons,
// boxes, and the blind with the most slats its ranges allow) and sensors (grids expanded).
// `min_slat_width_m` > 0 overrides the blind's smallest slat width [m]. InvalidArgument
// naming the limit.
absl::Status CheckSceneLimits(const v1::Scene& scene, const v1::Limits& limits,
                              double min_slat_width_m = 0);

// Checks resolved sampling settings: outdoor paths, and when `indoor` indoor paths per
// sensor and designs at once. InvalidArgument naming the limit.
absl::Status CheckSamplingLimits(const v1::Sampling& sampling, const v1::Limits& limits,
                                 bool indoor);

// Checks a job's evaluation budget (0 = the default, 150). InvalidArgument naming the limit.
absl::Status CheckBudgetLimits(const v1::Budget& budget, const v1::Limits& limits);

// Parses uploaded EPW bytes in memory (ParseEpw): InvalidArgument naming the line and the
// field, the file called "weather_epw" (with `weather_name` when valid).
absl::Status CheckUploadedWeather(const std::string& bytes, const std::string& weather_name);

// A site registration checked before anything is stored or queued.
struct CheckedSite {
  Scene scene;            // ValidateScene'd, its weather file cleared
  v1::Sampling sampling;  // resolved, the daemon's default backend filled in
};
// The door for SiteService.Register: every string of the request, the scene (inline, within
// the limits, ValidateScene: a site's scene is a complete scene, its room included), the
// outdoor sampling within the limits, the uploaded weather parsed. InvalidArgument naming
// the field or the limit.
absl::StatusOr<CheckedSite> CheckSiteRequest(const v1::RegisterSiteRequest& request,
                                             const v1::DaemonConfig& config);

// A job submission checked before anything is stored or queued.
struct CheckedJob {
  v1::Job job;           // as submitted, the default backend filled in, no weather paths
  PreparedJob prepared;  // ValidateJob'd (no weather)
};
// The door for JobService.Submit: every string of the request, the scene (inline, within
// the limits), the budget and sampling within the limits, ValidateJob, the uploaded weather
// parsed (but where `parsed_before`, given its bytes, says it parsed already). Where the
// weather comes from (upload or site) is Submit's to decide. InvalidArgument naming the
// field or the limit.
absl::StatusOr<CheckedJob> CheckJobRequest(
    const v1::SubmitJobRequest& request, const v1::DaemonConfig& config,
    const std::function<bool(const std::string&)>& parsed_before = nullptr);

}  // namespace fenestra
