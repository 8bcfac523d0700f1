#pragma once

#include "absl/status/status.h"
#include "fenestra/v1/daemon.pb.h"
#include "fenestra/v1/job.pb.h"
#include "fenestra/v1/scene.pb.h"

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

// Checks resolved sampling settings: outdoor paths, and indoor paths per sensor when
// `indoor`. InvalidArgument naming the limit.
absl::Status CheckSamplingLimits(const v1::Sampling& sampling, const v1::Limits& limits,
                                 bool indoor);

// Checks a job's evaluation budget (0 = the default, 150). InvalidArgument naming the limit.
absl::Status CheckBudgetLimits(const v1::Budget& budget, const v1::Limits& limits);

}  // namespace fenestra
