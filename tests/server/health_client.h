// A client of the standard gRPC health service (grpc.health.v1.Health), as probes call it:
// plaintext, no token.
#pragma once

#include <grpcpp/grpcpp.h>

#include <chrono>
#include <memory>
#include <string>

#include "grpc/health/v1/health.grpc.pb.h"

namespace fenestra {

using HealthStatus = grpc::health::v1::HealthCheckResponse::ServingStatus;
using grpc::health::v1::HealthCheckResponse;

class HealthClient {
 public:
  // A plaintext channel to "host:port".
  explicit HealthClient(const std::string& address)
      : stub_(grpc::health::v1::Health::NewStub(
            grpc::CreateChannel(address, grpc::InsecureChannelCredentials()))) {}

  // Check(service): the status answered, or the call's error in `call` (e.g. NOT_FOUND for
  // a service the server does not know); UNKNOWN then.
  HealthStatus Check(const std::string& service, grpc::Status* call = nullptr) const {
    grpc::ClientContext context;
    context.set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(10));
    grpc::health::v1::HealthCheckRequest request;
    request.set_service(service);
    HealthCheckResponse response;
    const grpc::Status status = stub_->Check(&context, request, &response);
    if (call) *call = status;
    return status.ok() ? response.status() : HealthCheckResponse::UNKNOWN;
  }

  grpc::health::v1::Health::Stub& stub() { return *stub_; }

 private:
  std::unique_ptr<grpc::health::v1::Health::Stub> stub_;
};

}  // namespace fenestra
