// fenestrad's services in-process: a Daemon on a free loopback port (auth none), its log
// captured by a spdlog sink, called through the generated stubs and a generic stub.
#include "server/services.h"

#include <grpcpp/generic/generic_stub.h>
#include <spdlog/sinks/ostream_sink.h>
#include <spdlog/sinks/stdout_color_sinks.h>
#include <spdlog/spdlog.h>

#include <future>
#include <sstream>

#include "absl/strings/str_split.h"
#include "server/config.h"
#include "server/daemon.h"
#include "tests/server/fenestrad_harness.h"

namespace fenestra {
namespace {

using ::testing::HasSubstr;
using ::testing::StartsWith;

class ServicesTest : public testing_fenestrad::FenestradTest {
 protected:
  void SetUp() override {
    FenestradTest::SetUp();
    auto sink = std::make_shared<spdlog::sinks::ostream_sink_mt>(log_);
    sink->set_pattern("%l %v");
    spdlog::set_default_logger(std::make_shared<spdlog::logger>("services_test", sink));
    v1::DaemonConfig config;
    config.set_listen_address("127.0.0.1:0");
    config.set_data_dir(dir_ + "/data");
    config.set_backend("cpu");
    config.set_auth("none");
    absl::StatusOr<v1::DaemonConfig> resolved = ResolveConfig(config);
    ASSERT_TRUE(resolved.ok()) << resolved.status();
    absl::StatusOr<std::unique_ptr<Daemon>> daemon = Daemon::Start(*resolved);
    ASSERT_TRUE(daemon.ok()) << daemon.status();
    daemon_ = *std::move(daemon);
    channel_ = grpc::CreateChannel("127.0.0.1:" + std::to_string(daemon_->port()),
                                   grpc::InsecureChannelCredentials());
    jobs_ = v1::JobService::NewStub(channel_);
    sites_ = v1::SiteService::NewStub(channel_);
  }
  void TearDown() override {
    if (daemon_) daemon_->Shutdown();
    spdlog::set_default_logger(std::make_shared<spdlog::logger>(
        "stderr", std::make_shared<spdlog::sinks::stderr_color_sink_mt>()));
    FenestradTest::TearDown();
  }
  // The log so far, one entry per line.
  std::vector<std::string> LogLines() {
    spdlog::default_logger()->flush();
    return absl::StrSplit(log_.str(), '\n', absl::SkipEmpty());
  }

  std::ostringstream log_;
  std::unique_ptr<Daemon> daemon_;
  std::shared_ptr<grpc::Channel> channel_;
  std::unique_ptr<v1::JobService::Stub> jobs_;
  std::unique_ptr<v1::SiteService::Stub> sites_;
};

TEST_F(ServicesTest, ClientTextCannotForgeLogLines) {
  const std::string forged = "\ninfo job job-9 succeeded: best alpha=1.57 (forged)";
  v1::SubmitJobRequest request = InlineRequest(TinyJob(2));
  request.mutable_job()->set_name("tilt" + forged);
  grpc::ClientContext submit;
  v1::JobInfo job;
  const grpc::Status submitted = jobs_->Submit(&submit, request, &job);
  // Ids and messages that quote client text: a bad site id, an unknown job id
  request.set_site_id("site-7\r" + forged);
  grpc::ClientContext bad_site;
  v1::JobInfo unused;
  // (refused at the door: names and ids are one line of printable text)
  EXPECT_EQ(jobs_->Submit(&bad_site, request, &unused).error_code(),
            grpc::StatusCode::INVALID_ARGUMENT);
  grpc::ClientContext get;
  v1::GetJobRequest get_request;
  get_request.set_id("job-1\x1b[2K" + forged);
  EXPECT_EQ(jobs_->Get(&get, get_request, &unused).error_code(), grpc::StatusCode::NOT_FOUND);
  if (submitted.ok()) {
    grpc::ClientContext cancel;
    v1::CancelJobRequest cancel_request;
    cancel_request.set_id(job.id());
    EXPECT_TRUE(jobs_->Cancel(&cancel, cancel_request, &unused).ok());
  }

  const std::vector<std::string> lines = LogLines();
  ASSERT_GE(lines.size(), 3u);
  for (const std::string& line : lines) {
    EXPECT_THAT(line, ::testing::Not(StartsWith("info job job-9"))) << log_.str();
    EXPECT_EQ(line.find('\r'), std::string::npos) << line;
    EXPECT_EQ(line.find('\x1b'), std::string::npos) << line;
  }
  // The text is in the log, escaped, on the lines of the calls that sent it
  EXPECT_THAT(log_.str(), HasSubstr("\"tilt\\ninfo job job-9 succeeded"));
  EXPECT_THAT(log_.str(), HasSubstr("\"job-1\\x1b[2K\\ninfo job job-9"));
  if (submitted.ok()) {
    EXPECT_THAT(log_.str(), HasSubstr("queued by local (\"tilt\\ninfo job job-9"));
  }
}

TEST_F(ServicesTest, UndecodableRequestsAreInvalidArgumentNamingTheMessage) {
  grpc::GenericStub stub(channel_);
  // Field 1, length 5, but only 2 bytes follow
  const std::string garbage(
      "\x0a\x05"
      "ab",
      4);
  const std::vector<std::pair<std::string, std::string>> methods = {
      {"/fenestra.v1.SiteService/Register", "fenestra.v1.RegisterSiteRequest"},
      {"/fenestra.v1.SiteService/Get", "fenestra.v1.GetSiteRequest"},
      {"/fenestra.v1.SiteService/List", "fenestra.v1.ListSitesRequest"},
      {"/fenestra.v1.SiteService/Delete", "fenestra.v1.DeleteSiteRequest"},
      {"/fenestra.v1.JobService/Submit", "fenestra.v1.SubmitJobRequest"},
      {"/fenestra.v1.JobService/Get", "fenestra.v1.GetJobRequest"},
      {"/fenestra.v1.JobService/List", "fenestra.v1.ListJobsRequest"},
      {"/fenestra.v1.JobService/Cancel", "fenestra.v1.CancelJobRequest"},
      {"/fenestra.v1.JobService/Watch", "fenestra.v1.WatchJobRequest"},
  };
  for (const auto& [method, type] : methods) {
    grpc::ClientContext context;
    grpc::Slice slice(garbage);
    grpc::ByteBuffer request(&slice, 1), response;
    std::promise<grpc::Status> done;
    stub.UnaryCall(&context, method, grpc::StubOptions(), &request, &response,
                   [&](grpc::Status status) { done.set_value(std::move(status)); });
    const grpc::Status status = done.get_future().get();
    EXPECT_EQ(status.error_code(), grpc::StatusCode::INVALID_ARGUMENT) << method;
    EXPECT_EQ(status.error_message(), "request does not decode as " + type) << method;
  }
  // Still serving; the refusals are logged
  grpc::ClientContext context;
  v1::ListJobsResponse jobs;
  EXPECT_TRUE(jobs_->List(&context, v1::ListJobsRequest(), &jobs).ok());
  EXPECT_THAT(log_.str(), HasSubstr("rpc JobService.Watch"));
  EXPECT_THAT(log_.str(), HasSubstr("INVALID_ARGUMENT: request does not decode as"));
}

}  // namespace
}  // namespace fenestra
