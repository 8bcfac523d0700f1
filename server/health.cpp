#include "server/health.h"

#include <grpcpp/ext/proto_server_reflection_plugin.h>
#include <grpcpp/grpcpp.h>
#include <grpcpp/health_check_service_interface.h>

#include <chrono>

#include "absl/strings/str_cat.h"

namespace fenestra {
namespace {

// Keeps gRPC's reflection plugin, which adds itself to every server of a process that
// links it, off the health port.
class NoReflection final : public grpc::ServerBuilderOption {
 public:
  void UpdateArguments(grpc::ChannelArguments*) override {}
  void UpdatePlugins(std::vector<std::unique_ptr<grpc::ServerBuilderPlugin>>* plugins) override {
    std::erase_if(*plugins, [](const std::unique_ptr<grpc::ServerBuilderPlugin>& plugin) {
      return dynamic_cast<grpc::reflection::ProtoServerReflectionPlugin*>(plugin.get()) != nullptr;
    });
  }
};

// Takes events off `queue` until it is shut down and empty.
void Drain(grpc::CompletionQueue& queue) {
  void* tag = nullptr;
  bool ok = false;
  while (queue.Next(&tag, &ok)) {
  }
}

}  // namespace

absl::StatusOr<std::unique_ptr<HealthServer>> HealthServer::Start(const std::string& address) {
  // gRPC++'s built-in health service is the only service the server registers
  grpc::EnableDefaultHealthCheckService(true);
  std::unique_ptr<HealthServer> health(new HealthServer);
  grpc::ServerBuilder builder;
  builder.SetOption(std::make_unique<NoReflection>());
  builder.AddListeningPort(address, grpc::InsecureServerCredentials(), &health->port_);
  // Health requests and answers are a few bytes
  builder.SetMaxReceiveMessageSize(4096);
  // A port another process holds is an error, not a port shared with it
  builder.AddChannelArgument(GRPC_ARG_ALLOW_REUSEPORT, 0);
  // gRPC++ adds its health service when the server starts, after the builder has made sure
  // that some completion queue is polled; this one, polled by a thread of its own, is it,
  // and carries the UNIMPLEMENTED answers to calls of any other method
  health->queue_ = builder.AddCompletionQueue();
  health->server_ = builder.BuildAndStart();
  if (!health->server_ || health->port_ == 0) {
    health->server_.reset();
    return absl::UnavailableError(
        absl::StrCat("cannot serve health checks on ", address, " (address in use?)"));
  }
  health->poller_ = std::thread(Drain, std::ref(*health->queue_));
  grpc::HealthCheckServiceInterface* service = health->server_->GetHealthCheckService();
  service->SetServingStatus(kLivenessService, true);
  health->SetReady(false);
  return health;
}

HealthServer::~HealthServer() {
  if (server_) {
    server_->Shutdown(std::chrono::system_clock::now() + std::chrono::seconds(1));
    server_->Wait();
  }
  if (!queue_) return;
  queue_->Shutdown();
  if (poller_.joinable()) {
    poller_.join();
  } else {
    Drain(*queue_);  // the server never started
  }
}

void HealthServer::SetReady(bool ready) {
  grpc::HealthCheckServiceInterface* service = server_->GetHealthCheckService();
  service->SetServingStatus("", ready);
  service->SetServingStatus(kReadinessService, ready);
}

}  // namespace fenestra
