#pragma once

#include <grpcpp/grpcpp.h>

#include <CLI/CLI.hpp>
#include <memory>
#include <string>

#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "core/optimize/job.h"
#include "fenestra/v1/service.grpc.pb.h"

namespace fenestra {

// Where fenestrad listens and how long a unary call may take.
struct ServerOptions {
  std::string address = "localhost:50051";
  double timeout_seconds = 30;  // deadline of every unary call [s]
};

// Adds --server and --timeout to a subcommand.
void AddServerOptions(CLI::App* command, ServerOptions& options);

// A channel to fenestrad (keepalive pings every 30 s) and the two service stubs.
class FenestradClient {
 public:
  explicit FenestradClient(const ServerOptions& options);

  v1::SiteService::Stub& sites() { return *sites_; }
  v1::JobService::Stub& jobs() { return *jobs_; }
  // A context whose deadline is the unary timeout from now.
  std::unique_ptr<grpc::ClientContext> UnaryContext() const;
  // OK, or a status a user can act on: "cannot reach fenestrad at ..." when the server is
  // down, "... did not answer within N s" when a deadline passed, else the server's message
  // with its code (e.g. INVALID_ARGUMENT).
  absl::Status Check(const grpc::Status& status) const;

 private:
  ServerOptions options_;
  std::shared_ptr<grpc::Channel> channel_;
  std::unique_ptr<v1::SiteService::Stub> sites_;
  std::unique_ptr<v1::JobService::Stub> jobs_;
};

// Makes a scene self-contained for the service: each OBJ surface becomes one polygon
// surface per triangle (group materials kept, degenerate triangles dropped); OBJ paths are
// taken relative to `scene_dir`.
absl::StatusOr<v1::Scene> InlineObjMeshes(const v1::Scene& scene, const std::string& scene_dir);

// A file's bytes.
absl::StatusOr<std::string> ReadFileBytes(const std::string& path);

// A job file made ready for JobService.Submit: the scene read (scene_file, relative to the
// job file) and inlined, the weather file's content attached (the job's weather_file,
// relative to the job file, else the scene's site.weather_file, relative to the scene).
// Without a weather file the request carries none (a site may provide it).
absl::StatusOr<v1::SubmitJobRequest> SubmitRequestFromJobFile(const std::string& path);

// Converts a progress event to what FormatProgress shows.
JobProgress FromProto(const v1::JobProgress& progress);

}  // namespace fenestra
