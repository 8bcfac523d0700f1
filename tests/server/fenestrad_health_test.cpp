// fenestrad's health port end to end: a real daemon (token auth, TLS on its main port) with
// --health-listen, called by the standard gRPC health client in plaintext and without a
// token, as Kubernetes' gRPC probes call it; and `fenestrad --check-config`.
#include <netinet/in.h>
#include <sys/socket.h>

#include "fenestra/v1/daemon.pb.h"
#include "tests/certificates.h"
#include "tests/server/fenestrad_harness.h"
#include "tests/server/health_client.h"

namespace fenestra {
namespace {

using namespace testing_fenestrad;
using ::testing::HasSubstr;

class FenestradHealthTest : public FenestradTest {
 protected:
  // The health port a started daemon wrote on the second line of its port file.
  static int HealthPort(const Daemon& d) {
    std::ifstream ports(d.data_dir() + ".port");
    int port = 0, health_port = 0;
    ports >> port >> health_port;
    EXPECT_GT(health_port, 0) << "no health port in " << d.data_dir() << ".port";
    return health_port;
  }
  static HealthClient Health(const Daemon& d) {
    return HealthClient("127.0.0.1:" + std::to_string(HealthPort(d)));
  }
  // `fenestrad user add NAME` on this test's data directory; the token it prints.
  std::string AddUser(const std::string& name) {
    const CliResult r =
        Daemon::RunCli({FENESTRAD, "user", "add", name, "--data-dir", dir_ + "/data"});
    EXPECT_EQ(r.code, 0) << r.err;
    std::string token = r.out;
    while (!token.empty() && token.back() == '\n') token.pop_back();
    return token;
  }
};

grpc::StatusCode ListJobs(const std::shared_ptr<grpc::Channel>& channel, const std::string& token) {
  grpc::ClientContext context;
  context.set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(10));
  if (!token.empty()) context.AddMetadata("authorization", "Bearer " + token);
  v1::ListJobsResponse response;
  return v1::JobService::NewStub(channel)
      ->List(&context, v1::ListJobsRequest(), &response)
      .error_code();
}

grpc::StatusCode ListSites(const std::shared_ptr<grpc::Channel>& channel,
                           const std::string& token) {
  grpc::ClientContext context;
  context.set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(10));
  if (!token.empty()) context.AddMetadata("authorization", "Bearer " + token);
  v1::ListSitesResponse response;
  return v1::SiteService::NewStub(channel)
      ->List(&context, v1::ListSitesRequest(), &response)
      .error_code();
}

TEST_F(FenestradHealthTest, PlaintextHealthBesideTlsAndTokensServingNothingElse) {
  const std::string ann = AddUser("ann");
  grpc::SslCredentialsOptions tls;
  tls.pem_root_certs = ReadFile(Certs().ca_cert);
  Daemon d(dir_ + "/data",
           {"--tls-cert", Certs().server_cert, "--tls-key", Certs().server_key, "--health-listen",
            "127.0.0.1:0"},
           grpc::SslCredentials(tls));
  d.Start();
  const int health_port = HealthPort(d);
  ASSERT_GT(health_port, 0);
  EXPECT_THAT(d.Log(), HasSubstr("health checks on 127.0.0.1:0 (port " +
                                 std::to_string(health_port) + ", plaintext"));

  // Ready and live, asked in plaintext without a token
  const HealthClient health = Health(d);
  EXPECT_EQ(health.Check(""), HealthCheckResponse::SERVING);
  EXPECT_EQ(health.Check("fenestrad"), HealthCheckResponse::SERVING);
  EXPECT_EQ(health.Check("liveness"), HealthCheckResponse::SERVING);
  grpc::Status unknown;
  health.Check("fenestra.v1.JobService", &unknown);
  EXPECT_EQ(unknown.error_code(), grpc::StatusCode::NOT_FOUND);

  // The main port still speaks only TLS and still wants a token
  EXPECT_EQ(ListJobs(d.channel(), ""), grpc::StatusCode::UNAUTHENTICATED);
  EXPECT_EQ(ListSites(d.channel(), ""), grpc::StatusCode::UNAUTHENTICATED);
  EXPECT_EQ(ListJobs(d.channel(), ann), grpc::StatusCode::OK);
  grpc::Status plaintext_to_tls;
  HealthClient(d.address()).Check("", &plaintext_to_tls);
  EXPECT_EQ(plaintext_to_tls.error_code(), grpc::StatusCode::UNAVAILABLE);

  // The health port has no other service, whatever the token
  auto health_channel = grpc::CreateChannel("127.0.0.1:" + std::to_string(health_port),
                                            grpc::InsecureChannelCredentials());
  for (const std::string& token : {std::string(), ann}) {
    EXPECT_EQ(ListJobs(health_channel, token), grpc::StatusCode::UNIMPLEMENTED);
    EXPECT_EQ(ListSites(health_channel, token), grpc::StatusCode::UNIMPLEMENTED);
  }
  EXPECT_EQ(d.Stop(), 0);
}

TEST_F(FenestradHealthTest, ReadinessFallsAtShutdownWhileLivenessHolds) {
  // A running job holds the shutdown in its grace period, long enough to look
  auto d = StartDaemon({"--health-listen", "127.0.0.1:0", "--shutdown-grace", "120"});
  const std::string id = Submit(*d, WriteJob("long", LongJob()));
  WaitJob(*d, id, Running);
  const HealthClient health = Health(*d);
  const HealthClient main_port(d->address());
  EXPECT_EQ(health.Check("fenestrad"), HealthCheckResponse::SERVING);
  EXPECT_EQ(main_port.Check("fenestrad"), HealthCheckResponse::SERVING);

  kill(d->pid(), SIGTERM);
  const auto deadline = Clock::now() + std::chrono::seconds(30);
  while (health.Check("fenestrad") != HealthCheckResponse::NOT_SERVING && Clock::now() < deadline) {
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  EXPECT_EQ(health.Check("fenestrad"), HealthCheckResponse::NOT_SERVING);
  EXPECT_EQ(health.Check(""), HealthCheckResponse::NOT_SERVING);
  EXPECT_EQ(health.Check("liveness"), HealthCheckResponse::SERVING);
  EXPECT_EQ(main_port.Check(""), HealthCheckResponse::NOT_SERVING);
  EXPECT_EQ(main_port.Check("fenestrad"), HealthCheckResponse::NOT_SERVING);
  EXPECT_THAT(d->Log(), HasSubstr("SIGTERM received"));
  d->Kill();
}

TEST_F(FenestradHealthTest, AHealthPortInUseStopsTheStart) {
  // A port this process holds
  const int held = socket(AF_INET, SOCK_STREAM, 0);
  sockaddr_in address{};
  address.sin_family = AF_INET;
  address.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  ASSERT_EQ(bind(held, reinterpret_cast<sockaddr*>(&address), sizeof address), 0);
  ASSERT_EQ(listen(held, 1), 0);
  socklen_t length = sizeof address;
  ASSERT_EQ(getsockname(held, reinterpret_cast<sockaddr*>(&address), &length), 0);
  const std::string taken = "127.0.0.1:" + std::to_string(ntohs(address.sin_port));

  Daemon d(dir_ + "/data", {"--auth", "none", "--health-listen", taken});
  EXPECT_EQ(d.RunToExit(), 1);
  EXPECT_THAT(d.Log(), HasSubstr("cannot serve health checks on " + taken));
  close(held);
}

TEST_F(FenestradHealthTest, CheckConfigPrintsTheResolvedConfigurationAndOpensNothing) {
  const std::string config = dir_ + "/fenestrad.json";
  std::ofstream(config) << R"({"listenAddress": "0.0.0.0:50051", "healthListen": "0.0.0.0:8081",
                              "dataDir": ")"
                        << dir_ << R"(/data", "limits": {"maxSites": 5}})";
  CliResult r = Daemon::RunCli({FENESTRAD, "--check-config", "--config", config, "--tls-cert",
                                "/nowhere/tls.crt", "--tls-key", "/nowhere/tls.key"});
  EXPECT_EQ(r.code, 0) << r.err;
  const v1::DaemonConfig resolved = FromJson<v1::DaemonConfig>(r.out);
  EXPECT_EQ(resolved.health_listen(), "0.0.0.0:8081");
  EXPECT_EQ(resolved.tls_cert_file(), "/nowhere/tls.crt");
  EXPECT_EQ(resolved.limits().max_sites(), 5);
  EXPECT_EQ(resolved.limits().max_sites_per_user(), 100);  // a default filled in
  EXPECT_FALSE(fs::exists(dir_ + "/data"));

  // Without TLS the same file is refused: the listen address is beyond loopback
  r = Daemon::RunCli({FENESTRAD, "--check-config", "--config", config});
  EXPECT_EQ(r.code, 2);
  EXPECT_THAT(r.err, HasSubstr("tls_cert_file and tls_key_file"));
  // The health port is another port than the main one
  r = Daemon::RunCli({FENESTRAD, "--check-config", "--config", config, "--allow-plaintext",
                      "--health-listen", "0.0.0.0:50051"});
  EXPECT_EQ(r.code, 2);
  EXPECT_THAT(r.err, HasSubstr("health_listen must be another address than listen_address"));
  // An unknown key
  std::ofstream(config) << R"({"listenAddress": "localhost:1", "healthListn": "0.0.0.0:8081"})";
  r = Daemon::RunCli({FENESTRAD, "--check-config", "--config", config});
  EXPECT_EQ(r.code, 2);
  EXPECT_THAT(r.err, HasSubstr("healthListn"));
}

}  // namespace
}  // namespace fenestra
