// The health port on its own, in this process: a real gRPC server on loopback called by the
// standard health client, the Fenestra stubs and a generic stub.
#include "server/health.h"

#include <gmock/gmock.h>
#include <grpcpp/generic/generic_stub.h>
#include <gtest/gtest.h>

#include <future>

#include "fenestra/v1/service.grpc.pb.h"
#include "tests/server/health_client.h"

namespace fenestra {
namespace {

using ::testing::HasSubstr;

std::unique_ptr<HealthServer> StartOnLoopback() {
  absl::StatusOr<std::unique_ptr<HealthServer>> health = HealthServer::Start("127.0.0.1:0");
  EXPECT_TRUE(health.ok()) << health.status();
  if (!health.ok()) return nullptr;
  EXPECT_GT((*health)->port(), 0);
  return *std::move(health);
}

std::string Address(const HealthServer& health) {
  return "127.0.0.1:" + std::to_string(health.port());
}

TEST(HealthServerTest, LiveAtOnceReadyWhenTold) {
  std::unique_ptr<HealthServer> health = StartOnLoopback();
  ASSERT_NE(health, nullptr);
  const HealthClient client(Address(*health));
  EXPECT_EQ(client.Check(kLivenessService), HealthCheckResponse::SERVING);
  EXPECT_EQ(client.Check(kReadinessService), HealthCheckResponse::NOT_SERVING);
  EXPECT_EQ(client.Check(""), HealthCheckResponse::NOT_SERVING);

  health->SetReady(true);
  EXPECT_EQ(client.Check(kReadinessService), HealthCheckResponse::SERVING);
  EXPECT_EQ(client.Check(""), HealthCheckResponse::SERVING);
  EXPECT_EQ(client.Check(kLivenessService), HealthCheckResponse::SERVING);

  health->SetReady(false);
  EXPECT_EQ(client.Check(kReadinessService), HealthCheckResponse::NOT_SERVING);
  EXPECT_EQ(client.Check(""), HealthCheckResponse::NOT_SERVING);
  EXPECT_EQ(client.Check(kLivenessService), HealthCheckResponse::SERVING);

  // A service it does not know is NOT_FOUND, which probes count as a failure
  grpc::Status call;
  EXPECT_EQ(client.Check("fenestra.v1.JobService", &call), HealthCheckResponse::UNKNOWN);
  EXPECT_EQ(call.error_code(), grpc::StatusCode::NOT_FOUND);
}

TEST(HealthServerTest, WatchStreamsReadinessChanges) {
  std::unique_ptr<HealthServer> health = StartOnLoopback();
  ASSERT_NE(health, nullptr);
  HealthClient client(Address(*health));
  grpc::ClientContext context;
  context.set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(10));
  grpc::health::v1::HealthCheckRequest request;
  request.set_service(kReadinessService);
  auto reader = client.stub().Watch(&context, request);
  HealthCheckResponse response;
  ASSERT_TRUE(reader->Read(&response));
  EXPECT_EQ(response.status(), HealthCheckResponse::NOT_SERVING);
  health->SetReady(true);
  ASSERT_TRUE(reader->Read(&response));
  EXPECT_EQ(response.status(), HealthCheckResponse::SERVING);
  health->SetReady(false);
  ASSERT_TRUE(reader->Read(&response));
  EXPECT_EQ(response.status(), HealthCheckResponse::NOT_SERVING);
  context.TryCancel();
}

TEST(HealthServerTest, ServesNothingButHealth) {
  std::unique_ptr<HealthServer> health = StartOnLoopback();
  ASSERT_NE(health, nullptr);
  health->SetReady(true);
  auto channel = grpc::CreateChannel(Address(*health), grpc::InsecureChannelCredentials());

  // The Fenestra services
  grpc::ClientContext jobs_context;
  v1::ListJobsResponse jobs;
  EXPECT_EQ(v1::JobService::NewStub(channel)
                ->List(&jobs_context, v1::ListJobsRequest(), &jobs)
                .error_code(),
            grpc::StatusCode::UNIMPLEMENTED);
  grpc::ClientContext sites_context;
  v1::ListSitesResponse sites;
  EXPECT_EQ(v1::SiteService::NewStub(channel)
                ->List(&sites_context, v1::ListSitesRequest(), &sites)
                .error_code(),
            grpc::StatusCode::UNIMPLEMENTED);

  // Server reflection, which this process links (fenestrad serves it with auth none)
  grpc::GenericStub stub(channel);
  grpc::ClientContext context;
  grpc::Slice empty(std::string{});
  grpc::ByteBuffer request(&empty, 1), response;
  std::promise<grpc::Status> done;
  stub.UnaryCall(&context, "/grpc.reflection.v1alpha.ServerReflection/ServerReflectionInfo",
                 grpc::StubOptions(), &request, &response,
                 [&](grpc::Status status) { done.set_value(std::move(status)); });
  EXPECT_EQ(done.get_future().get().error_code(), grpc::StatusCode::UNIMPLEMENTED);
}

TEST(HealthServerTest, AnAddressInUseIsAClearError) {
  std::unique_ptr<HealthServer> first = StartOnLoopback();
  ASSERT_NE(first, nullptr);
  const std::string taken = Address(*first);
  absl::StatusOr<std::unique_ptr<HealthServer>> second = HealthServer::Start(taken);
  ASSERT_FALSE(second.ok());
  EXPECT_EQ(second.status().code(), absl::StatusCode::kUnavailable);
  EXPECT_THAT(second.status().message(), HasSubstr("cannot serve health checks on " + taken));
}

}  // namespace
}  // namespace fenestra
