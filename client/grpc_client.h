#pragma once

#include <grpcpp/grpcpp.h>

#include <memory>
#include <optional>
#include <string>

#include "absl/functional/function_ref.h"
#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "fenestra/v1/service.grpc.pb.h"

namespace CLI {
class App;
}  // namespace CLI

namespace fenestra {

// The environment variable that holds the bearer token when --token-file is not given.
inline constexpr char kTokenEnvironmentVariable[] = "FENESTRA_TOKEN";

// How to reach fenestrad: the flags of every site and job command.
struct ServerOptions {
  std::string address = "localhost:50051";
  double timeout_seconds = 30;  // deadline of every unary call [s]
  std::string tls_ca_file;      // PEM CA that signed fenestrad's certificate; TLS when set
  std::string tls_cert_file;    // PEM client certificate chain (mTLS), with tls_key_file
  std::string tls_key_file;     // PEM private key of the client certificate
  std::string token_file;       // bearer token; when empty, FENESTRA_TOKEN
};

// Adds --server, --timeout, --tls-ca, --tls-cert, --tls-key and --token-file to a subcommand.
void AddServerOptions(CLI::App* command, ServerOptions& options);

// The bearer token: the content of `token_file` when given, else `environment_token` (the
// value of FENESTRA_TOKEN; null when unset), without surrounding whitespace; nullopt when
// neither is given. Errors name the file or the variable, never the token: an unreadable
// file, an empty token, a character a request header cannot carry (only visible ASCII).
absl::StatusOr<std::optional<std::string>> LoadToken(const std::string& token_file,
                                                     const char* environment_token);

// A typed client of fenestrad's SiteService and JobService. Every call carries the bearer
// token (`authorization: Bearer <token>` metadata) when one is configured, every unary call
// the --timeout deadline. Errors come back as statuses a user can act on: "cannot reach
// fenestrad at ..." when the server is down, "... did not answer within N s" when a
// deadline passed, "fenestrad refused the token ..." for UNAUTHENTICATED, else the server's
// code and message (e.g. "INVALID_ARGUMENT: job.budget: ...").
class FenestraClient {
 public:
  // Reads the TLS files and the token (--token-file, else FENESTRA_TOKEN from the
  // environment) and opens a channel (keepalive pings every 30 s). Errors name the flag
  // and its file. The connection itself is made by the first call.
  static absl::StatusOr<FenestraClient> Connect(const ServerOptions& options);

  absl::StatusOr<v1::SiteInfo> RegisterSite(const v1::RegisterSiteRequest& request);
  absl::StatusOr<v1::SiteInfo> GetSite(const std::string& id);
  absl::StatusOr<v1::ListSitesResponse> ListSites();
  absl::Status DeleteSite(const std::string& id);

  absl::StatusOr<v1::JobInfo> SubmitJob(const v1::SubmitJobRequest& request);
  absl::StatusOr<v1::JobInfo> GetJob(const std::string& id);
  absl::StatusOr<v1::ListJobsResponse> ListJobs(const v1::ListJobsRequest& request);
  absl::StatusOr<v1::JobInfo> CancelJob(const std::string& id);
  // Forgets an ended job (JobService.Delete).
  absl::Status DeleteJob(const std::string& id);
  // Passes the job's events to `on_event` as they come, until fenestrad closes the stream
  // (after the job's last event). No deadline: keepalive pings notice a dead connection.
  absl::Status WatchJob(const std::string& id,
                        absl::FunctionRef<void(const v1::JobEvent&)> on_event);

  // A bearer token goes to a host other than this machine without TLS.
  bool SendsTokenInClear() const;

 private:
  FenestraClient(const ServerOptions& options,
                 std::shared_ptr<grpc::ChannelCredentials> credentials,
                 std::optional<std::string> token);

  // A context with the token's metadata and, when `with_deadline`, the unary deadline.
  std::unique_ptr<grpc::ClientContext> NewContext(bool with_deadline) const;
  // One unary call through `method` of `stub`.
  template <typename Stub, typename Request, typename Response>
  absl::StatusOr<Response> Call(Stub& stub,
                                grpc::Status (Stub::*method)(grpc::ClientContext*, const Request&,
                                                             Response*),
                                const Request& request) const;
  // The status a user sees for a call's gRPC status.
  absl::Status ToStatus(const grpc::Status& status) const;

  ServerOptions options_;
  std::optional<std::string> token_;
  std::shared_ptr<grpc::Channel> channel_;
  std::unique_ptr<v1::SiteService::Stub> sites_;
  std::unique_ptr<v1::JobService::Stub> jobs_;
};

// A client for a CLI command: Fail()s on a bad flag or file, warns on stderr when the
// token would travel unencrypted to another host.
FenestraClient ConnectOrFail(const ServerOptions& options);

}  // namespace fenestra
