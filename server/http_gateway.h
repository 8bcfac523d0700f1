#pragma once

// The web dashboard's port (DaemonConfig.http_listen; server/web/README.md): the page's
// static files and a JSON API over the same managers as the gRPC services, so that callers,
// owners, limits and validation are the gRPC port's. HTTPS with the daemon's certificate
// options, else plain HTTP (which ResolveConfig allows only where the gRPC port could be
// plaintext). Every answer carries a Content-Security-Policy that allows the page's own files
// only, no CORS headers; requests are bounded in size, in rate per client address and in
// time; log lines escape what clients send.
#include <memory>
#include <string>
#include <thread>

#include "absl/status/statusor.h"
#include "fenestra/v1/daemon.pb.h"
#include "fenestra/v1/service.pb.h"
#include "server/job_manager.h"
#include "server/site_manager.h"
#include "server/users.h"

namespace httplib {
class Server;
}

namespace fenestra {

// The body of the dashboard's POST /api/v1/jobs, {"job", "scene", "weatherEpw",
// "weatherName"} (server/web/README.md), as the SubmitJobRequest it stands for: the scene put
// into the job, the weather decoded from base64. InvalidArgument for what does not parse,
// with the part it is in as the status's payload (what the API's error names as `field`).
// The request's own checks are JobService.Submit's, after it.
absl::StatusOr<v1::SubmitJobRequest> ParseDashboardSubmission(const std::string& body);

class HttpGateway {
 public:
  // What the API serves from: the daemon's authenticator and managers (they outlive it).
  struct Services {
    const Authenticator& auth;
    JobManager& jobs;
    SiteManager& sites;
  };

  // Listens on config.http_listen() ("host:port"; port 0: any free one) and serves in
  // threads of its own. Unavailable when the address cannot be bound or the certificate
  // files do not load.
  static absl::StatusOr<std::unique_ptr<HttpGateway>> Start(const v1::DaemonConfig& config,
                                                            Services services);
  // Stops listening and waits for the requests in flight.
  ~HttpGateway();
  HttpGateway(const HttpGateway&) = delete;
  HttpGateway& operator=(const HttpGateway&) = delete;

  int port() const { return port_; }

 private:
  HttpGateway() = default;

  std::shared_ptr<const void> routes_;  // what the server's handlers call; outlives them
  std::unique_ptr<httplib::Server> server_;
  std::thread thread_;
  int port_ = 0;
};

}  // namespace fenestra
