#include "client/grpc_client.h"

#include <algorithm>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "absl/strings/match.h"
#include "absl/strings/str_cat.h"
#include "core/geometry/obj_io.h"
#include "core/geometry/scene.h"

namespace fenestra {

namespace fs = std::filesystem;

void AddServerOptions(CLI::App* command, ServerOptions& options) {
  command->add_option("--server", options.address, "fenestrad address host:port")
      ->capture_default_str();
  command->add_option("--timeout", options.timeout_seconds, "deadline of each request [s]")
      ->capture_default_str();
}

FenestradClient::FenestradClient(const ServerOptions& options) : options_(options) {
  grpc::ChannelArguments args;
  args.SetInt(GRPC_ARG_KEEPALIVE_TIME_MS, 30'000);
  args.SetInt(GRPC_ARG_KEEPALIVE_TIMEOUT_MS, 10'000);
  args.SetInt(GRPC_ARG_KEEPALIVE_PERMIT_WITHOUT_CALLS, 1);
  args.SetMaxReceiveMessageSize(256 << 20);
  args.SetMaxSendMessageSize(256 << 20);
  channel_ = grpc::CreateCustomChannel(options.address, grpc::InsecureChannelCredentials(), args);
  sites_ = v1::SiteService::NewStub(channel_);
  jobs_ = v1::JobService::NewStub(channel_);
}

std::unique_ptr<grpc::ClientContext> FenestradClient::UnaryContext() const {
  auto context = std::make_unique<grpc::ClientContext>();
  context->set_deadline(
      std::chrono::system_clock::now() +
      std::chrono::milliseconds(static_cast<int64_t>(options_.timeout_seconds * 1000)));
  return context;
}

absl::Status FenestradClient::Check(const grpc::Status& status) const {
  if (status.ok()) return absl::OkStatus();
  const std::string& message = status.error_message();
  const auto code = static_cast<absl::StatusCode>(status.error_code());
  if (status.error_code() == grpc::StatusCode::UNAVAILABLE &&
      !absl::StartsWith(message, "fenestrad")) {
    return absl::UnavailableError(absl::StrCat("cannot reach fenestrad at ", options_.address, " (",
                                               message, "); is it running?"));
  }
  if (status.error_code() == grpc::StatusCode::DEADLINE_EXCEEDED) {
    return absl::DeadlineExceededError(absl::StrCat("fenestrad at ", options_.address,
                                                    " did not answer within ",
                                                    options_.timeout_seconds, " s (--timeout)"));
  }
  return absl::Status(code, absl::StrCat(absl::StatusCodeToString(code), ": ", message));
}

absl::StatusOr<std::string> ReadFileBytes(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return absl::NotFoundError(absl::StrCat(path, ": cannot open"));
  std::stringstream bytes;
  bytes << in.rdbuf();
  return bytes.str();
}

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
      // Degenerate triangles would fail the polygon check (area > 1e-6 x longest edge²)
      const double edge = std::max({Length(b - a), Length(c - b), Length(a - c)});
      if (!(0.5 * Length(Cross(b - a, c - a)) > 1e-6 * edge * edge)) continue;
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
      return absl::NotFoundError(
          absl::StrCat(path, ": weather file ", weather.string(), ": cannot open"));
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

JobProgress FromProto(const v1::JobProgress& p) {
  JobProgress progress;
  progress.evaluations = p.evaluations();
  progress.max_evaluations = p.max_evaluations();
  progress.current = p.current();
  progress.best = p.best();
  progress.elapsed_seconds = p.elapsed_seconds();
  progress.remaining_seconds = p.remaining_seconds();
  if (p.has_final_check()) progress.final_check = p.final_check();
  return progress;
}

}  // namespace fenestra
