#pragma once

#include <grpcpp/completion_queue.h>
#include <grpcpp/server.h>

#include <memory>
#include <string>
#include <thread>

#include "absl/status/statusor.h"

namespace fenestra {

// The service names fenestrad's health checking answers for (grpc.health.v1.Health).
// Readiness, under "" and this name: SERVING while the daemon takes requests (its store
// open, its workers running), NOT_SERVING before that and from the start of a shutdown.
inline constexpr char kReadinessService[] = "fenestrad";
// Liveness: SERVING from the health port's start until the process stops.
inline constexpr char kLivenessService[] = "liveness";

// fenestrad's health port: the standard gRPC health service and nothing else, in
// plaintext, for probes that send no token and speak no TLS (Kubernetes' gRPC probes).
// It tells only SERVING or NOT_SERVING, so it may listen beyond loopback.
class HealthServer {
 public:
  // Starts serving on `address` ("host:port"; port 0 picks a free one): liveness SERVING,
  // readiness NOT_SERVING until SetReady(true). Unavailable naming the address when it
  // cannot listen there.
  static absl::StatusOr<std::unique_ptr<HealthServer>> Start(const std::string& address);
  // Stops serving.
  ~HealthServer();
  HealthServer(const HealthServer&) = delete;
  HealthServer& operator=(const HealthServer&) = delete;

  // The port listened on.
  int port() const { return port_; }
  // Reports readiness ("" and kReadinessService) as SERVING or NOT_SERVING.
  void SetReady(bool ready);

 private:
  HealthServer() = default;

  std::unique_ptr<grpc::ServerCompletionQueue> queue_;
  std::unique_ptr<grpc::Server> server_;
  std::thread poller_;
  int port_ = 0;
};

}  // namespace fenestra
