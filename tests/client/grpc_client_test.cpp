// The typed fenestrad client: against a real fenestrad on loopback (states, JSON, error
// mapping), against a recording fenestra.v1 server in this process (the token's metadata,
// TLS and mTLS with openssl-made certificates), and through the fenestra executable.
#include "client/grpc_client.h"

#include <arpa/inet.h>
#include <gmock/gmock.h>
#include <google/protobuf/util/json_util.h>
#include <google/protobuf/util/message_differencer.h>
#include <gtest/gtest.h>
#include <netinet/in.h>
#include <stdlib.h>
#include <sys/socket.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <thread>

#include "client/cli_util.h"
#include "client/job_request.h"
#include "tests/certificates.h"
#include "tests/child_process.h"
#include "tests/client/recording_server.h"

namespace fenestra {
namespace {

namespace fs = std::filesystem;
using ::testing::ElementsAre;
using ::testing::HasSubstr;
using ::testing::Not;
using ::testing::StartsWith;

// A loopback socket: listening (connections are accepted by the kernel and never answered)
// or closed again at once (nothing listens on its port). Returns "127.0.0.1:PORT".
std::string LoopbackSocket(bool keep_listening, int* fd) {
  *fd = socket(AF_INET, SOCK_STREAM, 0);
  sockaddr_in address{};
  address.sin_family = AF_INET;
  address.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  EXPECT_EQ(bind(*fd, reinterpret_cast<sockaddr*>(&address), sizeof address), 0);
  socklen_t size = sizeof address;
  getsockname(*fd, reinterpret_cast<sockaddr*>(&address), &size);
  if (keep_listening) {
    EXPECT_EQ(listen(*fd, 8), 0);
  } else {
    close(*fd);
    *fd = -1;
  }
  return "127.0.0.1:" + std::to_string(ntohs(address.sin_port));
}

FenestraClient ConnectTo(const ServerOptions& options) {
  absl::StatusOr<FenestraClient> client = FenestraClient::Connect(options);
  EXPECT_TRUE(client.ok()) << client.status();
  return *std::move(client);
}

class GrpcClientTest : public testing::Test {
 protected:
  static void SetUpTestSuite() {
    const absl::StatusOr<TestCertificates>& made = ProcessTestCertificates();
    ASSERT_TRUE(made.ok()) << made.status();
    certificates_ = &*made;
  }

  void SetUp() override {
    unsetenv(kTokenEnvironmentVariable);
    dir_ = testing::TempDir() + "/grpc_client_test_" +
           testing::UnitTest::GetInstance()->current_test_info()->name();
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override {
    unsetenv(kTokenEnvironmentVariable);
    if (!HasFailure()) fs::remove_all(dir_);
  }

  // A file in the test's folder holding `content`; its path.
  std::string WriteFile(const std::string& name, const std::string& content) const {
    const std::string path = dir_ + "/" + name;
    std::ofstream(path) << content;
    return path;
  }
  ServerOptions Options(const std::string& address, const std::string& token = "") const {
    ServerOptions options;
    options.address = address;
    options.timeout_seconds = 10;
    if (!token.empty()) options.token_file = WriteFile("token", token);
    return options;
  }
  static std::shared_ptr<grpc::ServerCredentials> Tls(bool require_client_certificate) {
    return ServerTlsCredentials(*certificates_, require_client_certificate);
  }

  static inline const TestCertificates* certificates_ = nullptr;
  std::string dir_;
};

// ---------------------------------------------------------------------------------------
// The token
// ---------------------------------------------------------------------------------------

TEST_F(GrpcClientTest, TokenFileWinsOverTheEnvironmentAndIsTrimmed) {
  const std::string file = WriteFile("token", "  from-file.abc_DEF-123~+/=\n\n");
  absl::StatusOr<std::optional<std::string>> token = LoadToken(file, "from-environment");
  ASSERT_TRUE(token.ok()) << token.status();
  EXPECT_EQ(*token, "from-file.abc_DEF-123~+/=");
  token = LoadToken("", "\tfrom-environment \n");
  ASSERT_TRUE(token.ok()) << token.status();
  EXPECT_EQ(*token, "from-environment");
  token = LoadToken("", nullptr);
  ASSERT_TRUE(token.ok()) << token.status();
  EXPECT_EQ(*token, std::nullopt);
}

TEST_F(GrpcClientTest, BadTokensAreRefusedNamingTheirSourceNotTheToken) {
  struct Case {
    std::string file_content;  // with a file; else `environment`
    const char* environment;
    std::string message;
  };
  const std::string file = dir_ + "/token";
  for (const Case& c : std::vector<Case>{
           {" \n\t", nullptr, "--token-file " + file + ": the token is empty"},
           {"", " \n", "FENESTRA_TOKEN: the token is empty"},
           {"s3cret tail", nullptr, "--token-file " + file + ": the token's character 7 cannot go"},
           {"s3cret\nsecond-line", nullptr,
            "the token's character 7 cannot go in a request header"},
           {"", "s3cr\xc3\xa9t", "FENESTRA_TOKEN: the token's character 5 cannot go"},
           {"", "s3cret\x7f", "FENESTRA_TOKEN: the token's character 7 cannot go"},
       }) {
    if (!c.file_content.empty()) WriteFile("token", c.file_content);
    const absl::StatusOr<std::optional<std::string>> token =
        LoadToken(c.environment ? "" : file, c.environment);
    ASSERT_FALSE(token.ok()) << c.message;
    EXPECT_EQ(token.status().code(), absl::StatusCode::kInvalidArgument);
    EXPECT_THAT(token.status().message(), HasSubstr(c.message));
    EXPECT_THAT(token.status().message(), Not(HasSubstr("s3cr")));
  }
  // An unreadable file: a missing one and a directory
  absl::StatusOr<std::optional<std::string>> token = LoadToken(dir_ + "/missing", nullptr);
  EXPECT_EQ(token.status().message(),
            "--token-file " + dir_ + "/missing: cannot open (No such file or directory)");
  token = LoadToken(dir_, nullptr);
  EXPECT_EQ(token.status().message(), "--token-file " + dir_ + ": cannot open (a directory)");
}

TEST_F(GrpcClientTest, TheTokenGoesWithEveryCall) {
  RecordingServer server(grpc::InsecureServerCredentials());
  FenestraClient client = ConnectTo(Options(server.address(), "tok-123\n"));
  ASSERT_TRUE(client.RegisterSite(v1::RegisterSiteRequest()).ok());
  ASSERT_TRUE(client.GetSite("site-1").ok());
  ASSERT_TRUE(client.ListSites().ok());
  ASSERT_TRUE(client.DeleteSite("site-1").ok());
  ASSERT_TRUE(client.SubmitJob(v1::SubmitJobRequest()).ok());
  ASSERT_TRUE(client.GetJob("job-1").ok());
  ASSERT_TRUE(client.ListJobs(v1::ListJobsRequest()).ok());
  ASSERT_TRUE(client.CancelJob("job-1").ok());
  std::vector<v1::JobEvent::KindCase> events;
  ASSERT_TRUE(
      client.WatchJob("job-1", [&](const v1::JobEvent& e) { events.push_back(e.kind_case()); })
          .ok());
  EXPECT_THAT(events, ElementsAre(v1::JobEvent::kSnapshot, v1::JobEvent::kProgress,
                                  v1::JobEvent::kFinished));
  std::vector<std::string> methods;
  for (const RecordingServer::Call& call : server.calls()) {
    methods.push_back(call.method);
    EXPECT_EQ(call.authorization, "Bearer tok-123") << call.method;
  }
  EXPECT_THAT(methods, ElementsAre("SiteService.Register", "SiteService.Get", "SiteService.List",
                                   "SiteService.Delete", "JobService.Submit", "JobService.Get",
                                   "JobService.List", "JobService.Cancel", "JobService.Watch"));
}

TEST_F(GrpcClientTest, NoTokenNoAuthorizationMetadata) {
  RecordingServer server(grpc::InsecureServerCredentials());
  FenestraClient client = ConnectTo(Options(server.address()));
  ASSERT_TRUE(client.ListJobs(v1::ListJobsRequest()).ok());
  ASSERT_EQ(server.calls().size(), 1u);
  EXPECT_EQ(server.calls()[0].authorization, "(none)");
}

TEST_F(GrpcClientTest, UnauthenticatedSaysTheTokenWasRefused) {
  RecordingServer server(grpc::InsecureServerCredentials(), "right");
  FenestraClient wrong = ConnectTo(Options(server.address(), "wrong"));
  const absl::Status refused = wrong.GetJob("job-1").status();
  EXPECT_EQ(refused.code(), absl::StatusCode::kUnauthenticated);
  EXPECT_EQ(refused.message(),
            "fenestrad refused the token (invalid bearer token): set --token-file or "
            "FENESTRA_TOKEN");
  EXPECT_EQ(wrong.WatchJob("job-1", [](const v1::JobEvent&) {}).message(), refused.message());
  const absl::Status missing = ConnectTo(Options(server.address())).ListSites().status();
  EXPECT_EQ(missing.message(),
            "fenestrad wants a token (invalid bearer token): set --token-file or FENESTRA_TOKEN");
  EXPECT_TRUE(ConnectTo(Options(server.address(), "right")).ListSites().ok());
}

TEST_F(GrpcClientTest, TheTokenTravelsInClearOnlyToThisMachine) {
  ServerOptions options = Options("fenestra.example.org:50051", "tok");
  EXPECT_TRUE(ConnectTo(options).SendsTokenInClear());
  options.address = "dns:///fenestra.example.org:50051";
  EXPECT_TRUE(ConnectTo(options).SendsTokenInClear());
  for (const std::string local : {"localhost:50051", "127.0.0.1:50051", "ipv4:127.0.0.1:50051",
                                  "[::1]:50051", "unix:/run/fenestrad.sock"}) {
    options.address = local;
    EXPECT_FALSE(ConnectTo(options).SendsTokenInClear()) << local;
  }
  options.address = "fenestra.example.org:50051";
  options.tls_ca_file = certificates_->ca_cert;
  EXPECT_FALSE(ConnectTo(options).SendsTokenInClear());
  EXPECT_FALSE(ConnectTo(Options("fenestra.example.org:50051")).SendsTokenInClear());
}

// ---------------------------------------------------------------------------------------
// TLS
// ---------------------------------------------------------------------------------------

TEST_F(GrpcClientTest, TlsServerVerifiedWithTheGivenCaGetsTheToken) {
  RecordingServer server(Tls(false), "tok");
  ServerOptions options = Options(server.address(), "tok");
  options.tls_ca_file = certificates_->ca_cert;
  FenestraClient client = ConnectTo(options);
  absl::StatusOr<v1::ListSitesResponse> sites = client.ListSites();
  ASSERT_TRUE(sites.ok()) << sites.status();
  EXPECT_EQ(sites->sites(0).id(), "site-1");
  ASSERT_EQ(server.calls().size(), 1u);
  EXPECT_EQ(server.calls()[0].authorization, "Bearer tok");
}

TEST_F(GrpcClientTest, TlsServerIsNotReachedWithAnotherCaOrWithoutTls) {
  RecordingServer server(Tls(false));
  ServerOptions options = Options(server.address());
  options.tls_ca_file = certificates_->other_ca_cert;
  absl::Status status = ConnectTo(options).ListJobs(v1::ListJobsRequest()).status();
  EXPECT_EQ(status.code(), absl::StatusCode::kUnavailable);
  EXPECT_THAT(std::string(status.message()),
              StartsWith("cannot reach fenestrad at " + server.address() + " over TLS ("));
  EXPECT_THAT(status.message(),
              HasSubstr("); is it running, and does it serve TLS with a certificate signed by "
                        "the --tls-ca CA?"));
  options.tls_ca_file.clear();
  status = ConnectTo(options).ListJobs(v1::ListJobsRequest()).status();
  EXPECT_THAT(std::string(status.message()),
              StartsWith("cannot reach fenestrad at " + server.address() + " ("));
  EXPECT_TRUE(server.calls().empty());
}

TEST_F(GrpcClientTest, MutualTlsNeedsTheClientCertificate) {
  RecordingServer server(Tls(true));
  ServerOptions options = Options(server.address());
  options.tls_ca_file = certificates_->ca_cert;
  const absl::Status without = ConnectTo(options).ListSites().status();
  EXPECT_THAT(std::string(without.message()), StartsWith("cannot reach fenestrad at "));
  options.tls_cert_file = certificates_->client_cert;
  options.tls_key_file = certificates_->client_key;
  const absl::Status with = ConnectTo(options).ListSites().status();
  EXPECT_TRUE(with.ok()) << with;
  EXPECT_EQ(server.calls().size(), 1u);
}

TEST_F(GrpcClientTest, SecurityFlagsAreCheckedBeforeConnecting) {
  const std::string not_pem = WriteFile("ca.txt", "not a certificate\n");
  struct Case {
    std::string ca, cert, key;
    std::string message;
  };
  for (const Case& c : std::vector<Case>{
           {dir_ + "/missing.pem", "", "",
            "--tls-ca " + dir_ + "/missing.pem: cannot open (No such file or directory)"},
           {not_pem, "", "", "--tls-ca " + not_pem + ": not a PEM file (no \"-----BEGIN\" line)"},
           {certificates_->ca_cert, certificates_->client_cert, "",
            "--tls-cert and --tls-key go together"},
           {certificates_->ca_cert, "", certificates_->client_key,
            "--tls-cert and --tls-key go together"},
           {"", certificates_->client_cert, certificates_->client_key, "--tls-cert needs --tls-ca"},
           {certificates_->ca_cert, certificates_->client_cert, dir_ + "/missing.key",
            "--tls-key " + dir_ + "/missing.key: cannot open"},
       }) {
    ServerOptions options = Options("127.0.0.1:1");
    options.tls_ca_file = c.ca;
    options.tls_cert_file = c.cert;
    options.tls_key_file = c.key;
    const absl::StatusOr<FenestraClient> client = FenestraClient::Connect(options);
    ASSERT_FALSE(client.ok()) << c.message;
    EXPECT_EQ(client.status().code(), absl::StatusCode::kInvalidArgument);
    EXPECT_THAT(client.status().message(), HasSubstr(c.message));
  }
  ServerOptions options = Options("127.0.0.1:1");
  options.timeout_seconds = 0;
  EXPECT_EQ(FenestraClient::Connect(options).status().message(), "--timeout must be more than 0 s");
}

// ---------------------------------------------------------------------------------------
// The fenestra executable
// ---------------------------------------------------------------------------------------

TEST_F(GrpcClientTest, TheCliTakesTheTokenFromItsFlagElseTheEnvironment) {
  RecordingServer server(grpc::InsecureServerCredentials());
  const std::string file = WriteFile("token", "from-file\n");
  const std::vector<std::string> list = {FENESTRA_CLI, "job", "list", "--server", server.address()};
  std::vector<std::string> with_file = list;
  with_file.insert(with_file.end(), {"--token-file", file});
  CommandResult run = RunCommand(list, {"FENESTRA_TOKEN=from-environment"});
  EXPECT_EQ(run.exit_code, 0) << run.output;
  EXPECT_THAT(run.output, HasSubstr("job-1"));
  run = RunCommand(with_file, {"FENESTRA_TOKEN=from-environment"});
  EXPECT_EQ(run.exit_code, 0) << run.output;
  run = RunCommand(list, {"FENESTRA_TOKEN=two words"});
  EXPECT_EQ(run.exit_code, 1);
  EXPECT_THAT(run.output,
              HasSubstr("error: FENESTRA_TOKEN: the token's character 4 cannot go in a request "
                        "header (only visible ASCII, no spaces)"));
  std::vector<std::string> authorizations;
  for (const RecordingServer::Call& call : server.calls()) {
    authorizations.push_back(call.authorization);
  }
  EXPECT_THAT(authorizations, ElementsAre("Bearer from-environment", "Bearer from-file"));
}

TEST_F(GrpcClientTest, TheCliWatchesAJobOverMutualTls) {
  RecordingServer server(Tls(true), "tok");
  const CommandResult run =
      RunCommand({FENESTRA_CLI, "job", "watch", "job-1", "--server", server.address(), "--tls-ca",
                  certificates_->ca_cert, "--tls-cert", certificates_->client_cert, "--tls-key",
                  certificates_->client_key, "--token-file", WriteFile("token", "tok")});
  EXPECT_EQ(run.exit_code, 0) << run.output;
  EXPECT_THAT(run.output, HasSubstr("job-1 (recorded): queued"));
  EXPECT_THAT(run.output, HasSubstr("job-1 succeeded"));
  EXPECT_THAT(run.output, Not(HasSubstr("warning")));
  ASSERT_EQ(server.calls().size(), 1u);
  EXPECT_EQ(server.calls()[0].authorization, "Bearer tok");
}

TEST_F(GrpcClientTest, TheCliWarnsWhenTheTokenWouldTravelInClear) {
  // Nothing is reached there: the warning comes before the call
  const CommandResult run =
      RunCommand({FENESTRA_CLI, "site", "list", "--server", "fenestra.invalid:1", "--timeout", "1"},
                 {"FENESTRA_TOKEN=tok"});
  EXPECT_EQ(run.exit_code, 1);
  EXPECT_THAT(run.output, HasSubstr("warning: the token goes to fenestra.invalid:1 unencrypted; "
                                    "give --tls-ca to use TLS"));
}

// ---------------------------------------------------------------------------------------
// A real fenestrad
// ---------------------------------------------------------------------------------------

// The city-office tilt job with tiny sampling (40000 outdoor paths, 2000 indoor paths per
// sensor, 3 evaluations), as `fenestra job submit` sends it.
v1::SubmitJobRequest TinyJobRequest() {
  absl::StatusOr<v1::SubmitJobRequest> request =
      SubmitRequestFromJobFile(FENESTRA_SOURCE_DIR "/examples/city_office/alpha_max_quick.json");
  EXPECT_TRUE(request.ok()) << request.status();
  v1::Job& job = *request->mutable_job();
  job.mutable_sampling()->set_outdoor_paths(40000);
  job.mutable_sampling()->set_indoor_paths_per_sensor(2000);
  job.mutable_sampling()->set_backend("cpu");
  job.mutable_budget()->set_max_evaluations(3);
  job.mutable_budget()->set_failed_cycles_to_stop(-1);
  return *request;
}

template <typename Message>
Message FromJson(const std::string& json) {
  Message message;
  EXPECT_TRUE(google::protobuf::util::JsonStringToMessage(json, &message).ok()) << json;
  return message;
}

class FenestradClientTest : public GrpcClientTest {
 protected:
  void SetUp() override {
    GrpcClientTest::SetUp();
    daemon_ = std::make_unique<FenestradProcess>(FENESTRAD, dir_ + "/data");
    ASSERT_FALSE(daemon_->address().empty()) << "fenestrad did not start:\n" << daemon_->Log();
  }
  void TearDown() override {
    if (HasFailure()) std::cerr << daemon_->Log();
    daemon_.reset();
    GrpcClientTest::TearDown();
  }
  std::unique_ptr<FenestradProcess> daemon_;
};

TEST_F(FenestradClientTest, SiteStatesAndJson) {
  FenestraClient client = ConnectTo(Options(daemon_->address()));
  const v1::SubmitJobRequest job = TinyJobRequest();
  v1::RegisterSiteRequest request;
  *request.mutable_scene() = job.job().scene();
  *request.mutable_sampling() = job.job().sampling();
  request.set_weather_epw(job.weather_epw());
  absl::StatusOr<v1::SiteInfo> site = client.RegisterSite(request);
  ASSERT_TRUE(site.ok()) << site.status();
  EXPECT_EQ(StateName(site->state()), "computing");
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(60);
  while (site.ok() && site->state() == v1::SITE_STATE_COMPUTING &&
         std::chrono::steady_clock::now() < deadline) {
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
    site = client.GetSite(site->id());
  }
  ASSERT_TRUE(site.ok()) << site.status();
  EXPECT_EQ(StateName(site->state()), "ready") << site->error();

  // One line of JSON that reads back as the same message; indented JSON reads back too
  const std::string line = ToJson(*site, JsonLayout::kLine);
  EXPECT_EQ(line.find('\n'), std::string::npos);
  EXPECT_THAT(line, HasSubstr("\"state\":\"SITE_STATE_READY\""));
  EXPECT_TRUE(
      google::protobuf::util::MessageDifferencer::Equals(FromJson<v1::SiteInfo>(line), *site));
  const std::string indented = ToJson(*site, JsonLayout::kIndented);
  EXPECT_THAT(indented, HasSubstr("\n"));
  EXPECT_TRUE(
      google::protobuf::util::MessageDifferencer::Equals(FromJson<v1::SiteInfo>(indented), *site));

  absl::StatusOr<v1::ListSitesResponse> sites = client.ListSites();
  ASSERT_TRUE(sites.ok()) << sites.status();
  ASSERT_EQ(sites->sites_size(), 1);
  EXPECT_EQ(sites->sites(0).id(), site->id());
  ASSERT_TRUE(client.DeleteSite(site->id()).ok());
  const absl::Status gone = client.GetSite(site->id()).status();
  EXPECT_EQ(gone.code(), absl::StatusCode::kNotFound);
  EXPECT_THAT(std::string(gone.message()), StartsWith("NOT_FOUND: "));
  EXPECT_THAT(gone.message(), HasSubstr(site->id()));
}

TEST_F(FenestradClientTest, JobEventsStatesAndResultFile) {
  FenestraClient client = ConnectTo(Options(daemon_->address()));
  absl::StatusOr<v1::JobInfo> job = client.SubmitJob(TinyJobRequest());
  ASSERT_TRUE(job.ok()) << job.status();
  EXPECT_THAT(StateName(job->state()), testing::AnyOf("queued", "running"));
  EXPECT_FALSE(IsFinalState(job->state()));

  // Every event on one JSON line; the stream ends with the job
  std::vector<v1::JobEvent> events;
  const absl::Status watched = client.WatchJob(job->id(), [&](const v1::JobEvent& event) {
    const std::string line = ToJson(event, JsonLayout::kLine);
    EXPECT_EQ(line.find('\n'), std::string::npos);
    events.push_back(FromJson<v1::JobEvent>(line));
  });
  ASSERT_TRUE(watched.ok()) << watched;
  ASSERT_GE(events.size(), 3u);
  EXPECT_EQ(events.front().kind_case(), v1::JobEvent::kSnapshot);
  EXPECT_EQ(events.back().kind_case(), v1::JobEvent::kFinished);

  job = client.GetJob(job->id());
  ASSERT_TRUE(job.ok()) << job.status();
  EXPECT_EQ(StateName(job->state()), "succeeded");
  EXPECT_TRUE(IsFinalState(job->state()));
  EXPECT_EQ(job->result().evaluations(), 3);
  absl::StatusOr<v1::ListJobsResponse> jobs = client.ListJobs(v1::ListJobsRequest());
  ASSERT_TRUE(jobs.ok()) << jobs.status();
  ASSERT_EQ(jobs->jobs_size(), 1);
  EXPECT_EQ(StateName(jobs->jobs(0).state()), "succeeded");
  // Cancelling a finished job leaves it as it is
  absl::StatusOr<v1::JobInfo> cancelled = client.CancelJob(job->id());
  ASSERT_TRUE(cancelled.ok()) << cancelled.status();
  EXPECT_EQ(StateName(cancelled->state()), "succeeded");

  // The result file: proto field names, every field, read back as the same result
  const std::string path = dir_ + "/result.json";
  ASSERT_TRUE(WriteJsonFile(path, job->result()).ok());
  const std::string text = ReadFileBytes(path).value();
  EXPECT_THAT(text, HasSubstr("\"best_design\""));
  EXPECT_TRUE(google::protobuf::util::MessageDifferencer::Equals(FromJson<v1::JobResult>(text),
                                                                 job->result()));
}

TEST_F(FenestradClientTest, ServerErrorsKeepTheirCodeAndMessage) {
  FenestraClient client = ConnectTo(Options(daemon_->address()));
  const absl::Status unknown = client.GetJob("job-99").status();
  EXPECT_EQ(unknown.code(), absl::StatusCode::kNotFound);
  EXPECT_THAT(std::string(unknown.message()), StartsWith("NOT_FOUND: "));
  EXPECT_THAT(unknown.message(), HasSubstr("job-99"));
  EXPECT_EQ(client.WatchJob("job-99", [](const v1::JobEvent&) {}), unknown);
  v1::SubmitJobRequest empty_range = TinyJobRequest();
  empty_range.mutable_job()->mutable_variables(0)->set_lower(1);
  empty_range.mutable_job()->mutable_variables(0)->set_upper(0.5);
  const absl::Status invalid = client.SubmitJob(empty_range).status();
  EXPECT_EQ(invalid.code(), absl::StatusCode::kInvalidArgument);
  EXPECT_THAT(std::string(invalid.message()), StartsWith("INVALID_ARGUMENT: "));
}

TEST(GrpcClientErrorsTest, ServerDownSaysCannotReach) {
  int fd;
  ServerOptions options;
  options.address = LoopbackSocket(/*keep_listening=*/false, &fd);
  const absl::Status status = ConnectTo(options).ListJobs(v1::ListJobsRequest()).status();
  EXPECT_EQ(status.code(), absl::StatusCode::kUnavailable);
  EXPECT_THAT(std::string(status.message()),
              StartsWith("cannot reach fenestrad at " + options.address + " ("));
  EXPECT_THAT(status.message(), HasSubstr("); is it running?"));
}

// A JobService whose Get answers UNAVAILABLE, as fenestrad does while it shuts down.
class ShuttingDownJobs final : public v1::JobService::Service {
  grpc::Status Get(grpc::ServerContext*, const v1::GetJobRequest*, v1::JobInfo*) override {
    return grpc::Status(grpc::StatusCode::UNAVAILABLE, "fenestrad is shutting down");
  }
};

TEST(GrpcClientErrorsTest, TheServersOwnUnavailableKeepsItsMessage) {
  ShuttingDownJobs jobs;
  grpc::ServerBuilder builder;
  int port = 0;
  builder.AddListeningPort("127.0.0.1:0", grpc::InsecureServerCredentials(), &port);
  builder.RegisterService(&jobs);
  const std::unique_ptr<grpc::Server> server = builder.BuildAndStart();
  ASSERT_NE(server, nullptr);
  ServerOptions options;
  options.address = "127.0.0.1:" + std::to_string(port);
  const absl::Status status = ConnectTo(options).GetJob("job-1").status();
  EXPECT_EQ(status.code(), absl::StatusCode::kUnavailable);
  EXPECT_EQ(status.message(), "UNAVAILABLE: fenestrad is shutting down");
  server->Shutdown();
}

TEST(GrpcClientErrorsTest, SilentServerRunsIntoTheDeadline) {
  int fd;
  ServerOptions options;
  options.address = LoopbackSocket(/*keep_listening=*/true, &fd);
  options.timeout_seconds = 0.5;
  const absl::Status status = ConnectTo(options).GetSite("site-1").status();
  EXPECT_EQ(status.code(), absl::StatusCode::kDeadlineExceeded);
  EXPECT_EQ(status.message(),
            "fenestrad at " + options.address + " did not answer within 0.5 s (--timeout)");
  close(fd);
}

}  // namespace
}  // namespace fenestra
