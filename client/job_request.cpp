#include "client/job_request.h"

#include <filesystem>

#include "absl/strings/str_cat.h"
#include "client/cli_util.h"
#include "core/geometry/obj_io.h"
#include "core/geometry/scene.h"
#include "core/optimize/job.h"

namespace fenestra {

namespace fs = std::filesystem;

absl::StatusOr<v1::Scene> InlineObjMeshes(const v1::Scene& scene, const std::string& scene_dir) {
  v1::Scene out = scene;
  out.clear_surfaces();
  for (int i = 0; i < scene.surfaces_size(); ++i) {
    const v1::Surface& s = scene.surfaces(i);
    if (!s.has_obj()) {
      *out.add_surfaces() = s;
      continue;
    }
    const std::string path = (fs::path(scene_dir) / s.obj().path()).string();
    absl::StatusOr<ObjTriangles> obj = ReadObj(path);
    if (!obj.ok()) {
      return absl::InvalidArgumentError(
          absl::StrCat("surfaces[", i, "].obj.path: ", obj.status().message()));
    }
    for (size_t t = 0; t < obj->group.size(); ++t) {
      const Vec3d a = obj->vertices[3 * t], b = obj->vertices[3 * t + 1],
                  c = obj->vertices[3 * t + 2];
      if (IsDegenerateTriangle(a, b, c)) continue;  // it would fail the polygon check
      v1::Surface& triangle = *out.add_surfaces();
      triangle.set_name(s.name());
      triangle.set_side(s.side());
      auto group = s.obj().group_materials().find(obj->group[t]);
      triangle.set_material(group == s.obj().group_materials().end() ? s.material()
                                                                     : group->second);
      for (const Vec3d& v : {a, b, c}) {
        v1::Vec3& vertex = *triangle.mutable_polygon()->add_vertices();
        vertex.set_x(v.x);
        vertex.set_y(v.y);
        vertex.set_z(v.z);
      }
    }
  }
  return out;
}

absl::StatusOr<v1::SubmitJobRequest> SubmitRequestFromJobFile(const std::string& path) {
  absl::StatusOr<v1::Job> job = ReadJobFile(path);
  if (!job.ok()) return job.status();
  const fs::path job_dir = fs::path(path).parent_path();
  fs::path scene_dir = job_dir;
  v1::Scene scene = job->scene();
  if (!job->scene_file().empty()) {
    const fs::path scene_path = job_dir / job->scene_file();
    absl::StatusOr<v1::Scene> read = ReadSceneProto(scene_path.string());
    if (!read.ok()) return read.status();
    scene = *std::move(read);
    scene_dir = scene_path.parent_path();
    job->clear_scene_file();
  }
  absl::StatusOr<v1::Scene> inlined = InlineObjMeshes(scene, scene_dir.string());
  if (!inlined.ok()) return inlined.status();

  // The weather file travels as bytes
  v1::SubmitJobRequest request;
  fs::path weather;
  if (!job->weather_file().empty()) {
    weather = job_dir / job->weather_file();
  } else if (!inlined->site().weather_file().empty()) {
    weather = scene_dir / inlined->site().weather_file();
  }
  if (!weather.empty()) {
    absl::StatusOr<std::string> bytes = ReadFileBytes(weather.string());
    if (!bytes.ok()) {
      return absl::NotFoundError(absl::StrCat(path, ": weather file ", bytes.status().message()));
    }
    request.set_weather_epw(*std::move(bytes));
    request.set_weather_name(weather.filename().string());
  }
  job->clear_weather_file();
  inlined->mutable_site()->clear_weather_file();
  *job->mutable_scene() = *std::move(inlined);
  *request.mutable_job() = *std::move(job);
  return request;
}

}  // namespace fenestra
