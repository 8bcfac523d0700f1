#pragma once

#include <string>

#include "absl/status/statusor.h"
#include "fenestra/v1/service.pb.h"

namespace fenestra {

// Makes a scene self-contained for the service: each OBJ surface becomes one polygon
// surface per triangle (group materials kept, degenerate triangles dropped); OBJ paths are
// taken relative to `scene_dir`.
absl::StatusOr<v1::Scene> InlineObjMeshes(const v1::Scene& scene, const std::string& scene_dir);

// A job file made ready for JobService.Submit: the scene read (scene_file, relative to the
// job file) and inlined, the weather file's content attached (the job's weather_file,
// relative to the job file, else the scene's site.weather_file, relative to the scene).
// Without a weather file the request carries none (a site may provide it).
absl::StatusOr<v1::SubmitJobRequest> SubmitRequestFromJobFile(const std::string& path);

}  // namespace fenestra
