// A small fenestra.v1 server in the test process, for what the client sends.
#pragma once

#include <grpcpp/grpcpp.h>

#include <memory>
#include <mutex>
#include <string>
#include <vector>

namespace fenestra {

// Serves SiteService and JobService (the generated fenestra.v1 services) on a free
// 127.0.0.1 port and records the `authorization` metadata of every call. Answers are
// small and fixed: sites are ready ("site-1"), a submitted job is "job-1", Get finds it
// succeeded with alpha = 0.5, Watch streams a snapshot, one progress event and `finished`.
// With `required_token`, a call without "Bearer <required_token>" gets UNAUTHENTICATED.
class RecordingServer {
 public:
  struct Call {
    std::string method;         // e.g. "SiteService.Register"
    std::string authorization;  // the metadata value; "(none)" when absent
  };

  explicit RecordingServer(std::shared_ptr<grpc::ServerCredentials> credentials,
                           std::string required_token = "");
  ~RecordingServer();

  // "127.0.0.1:PORT"
  const std::string& address() const { return address_; }
  // Every call so far, in order.
  std::vector<Call> calls() const;

  // Records the call; the status it is to be answered with.
  grpc::Status Record(const grpc::ServerContext& context, const char* method);

 private:
  class Sites;
  class Jobs;

  std::string required_token_;
  std::unique_ptr<Sites> sites_;
  std::unique_ptr<Jobs> jobs_;
  std::unique_ptr<grpc::Server> server_;
  std::string address_;
  mutable std::mutex mutex_;
  std::vector<Call> calls_;
};

}  // namespace fenestra
