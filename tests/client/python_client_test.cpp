// examples/python_client.py (run with /usr/bin/python3, stubs generated at run time) against
// a recording fenestra.v1 server in this process: the token it sends, TLS and mTLS, and its
// errors. Its run against a real fenestrad is in tests/server/fenestrad_test.cpp.
#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <stdlib.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>

#include "tests/child_process.h"
#include "tests/certificates.h"
#include "tests/client/recording_server.h"

namespace fenestra {
namespace {

namespace fs = std::filesystem;
using ::testing::ElementsAre;
using ::testing::HasSubstr;

class PythonClientTest : public testing::Test {
 protected:
  static void SetUpTestSuite() {
    unsetenv("FENESTRA_TOKEN");  // a token comes from the flags or a test's environment only
    const CommandResult grpc = RunCommand({"/usr/bin/python3", "-c", "import grpc"});
    ASSERT_EQ(grpc.exit_code, 0) << "/usr/bin/python3 needs python3-grpcio "
                                    "(deploy/debian_packages.sh):\n"
                                 << grpc.output;
    dir_ = new std::string(testing::TempDir() + "/python_client_test_" + std::to_string(getpid()));
    fs::remove_all(*dir_);
    fs::create_directories(*dir_);
    const absl::StatusOr<TestCertificates>& made = ProcessTestCertificates();
    ASSERT_TRUE(made.ok()) << made.status();
    certificates_ = &*made;
  }
  static void TearDownTestSuite() { fs::remove_all(*dir_); }

  // Runs the example against `server` with `flags` and `environment` ("NAME=value").
  static CommandResult RunExample(const RecordingServer& server, std::vector<std::string> flags,
                                  const std::vector<std::string>& environment = {}) {
    std::vector<std::string> argv = {
        "/usr/bin/python3", FENESTRA_SOURCE_DIR "/examples/python_client.py",
        "--server",         server.address(),
        "--timeout",        "10"};
    argv.insert(argv.end(), flags.begin(), flags.end());
    return RunCommand(argv, environment);
  }
  static std::string TokenFile(const std::string& name, const std::string& content) {
    const std::string path = *dir_ + "/" + name;
    std::ofstream(path) << content;
    return path;
  }
  static std::vector<std::string> Authorizations(const RecordingServer& server) {
    std::vector<std::string> values;
    for (const RecordingServer::Call& call : server.calls()) values.push_back(call.authorization);
    return values;
  }

  static inline std::string* dir_ = nullptr;
  static inline const TestCertificates* certificates_ = nullptr;
};

TEST_F(PythonClientTest, RunsAJobOverMutualTlsWithTheTokenOnEveryCall) {
  RecordingServer server(ServerTlsCredentials(*certificates_, true), "py-token");
  const CommandResult run =
      RunExample(server, {"--tls-ca", certificates_->ca_cert, "--tls-cert",
                          certificates_->client_cert, "--tls-key", certificates_->client_key,
                          "--token-file", TokenFile("token", "\n py-token \n")});
  ASSERT_EQ(run.exit_code, 0) << run.output;
  EXPECT_THAT(run.output, HasSubstr("site-1 ready"));
  EXPECT_THAT(run.output, HasSubstr("[1/1] best 50.00 ± 1.00 %"));
  EXPECT_THAT(run.output, HasSubstr("best design: alpha=0.5"));
  std::vector<std::string> methods;
  for (const RecordingServer::Call& call : server.calls()) methods.push_back(call.method);
  EXPECT_THAT(methods,
              ElementsAre("SiteService.Register", "JobService.Submit", "JobService.Watch"));
  EXPECT_THAT(Authorizations(server),
              ElementsAre("Bearer py-token", "Bearer py-token", "Bearer py-token"));
}

TEST_F(PythonClientTest, TokenFromTheEnvironmentUnlessTheFlagGivesOne) {
  RecordingServer server(grpc::InsecureServerCredentials());
  CommandResult run = RunExample(server, {}, {"FENESTRA_TOKEN=from-environment"});
  ASSERT_EQ(run.exit_code, 0) << run.output;
  run = RunExample(server, {"--token-file", TokenFile("flag_token", "from-file")},
                   {"FENESTRA_TOKEN=from-environment"});
  ASSERT_EQ(run.exit_code, 0) << run.output;
  run = RunExample(server, {});
  ASSERT_EQ(run.exit_code, 0) << run.output;
  const std::vector<std::string> sent = Authorizations(server);
  ASSERT_EQ(sent.size(), 9u);
  EXPECT_EQ(sent[0], "Bearer from-environment");
  EXPECT_EQ(sent[3], "Bearer from-file");
  EXPECT_EQ(sent[6], "(none)");
}

TEST_F(PythonClientTest, ClearErrors) {
  RecordingServer server(ServerTlsCredentials(*certificates_, false), "right");
  const std::string ca = certificates_->ca_cert;
  struct Case {
    std::vector<std::string> flags, environment;
    std::string message;
  };
  for (const Case& c : std::vector<Case>{
           {{"--tls-ca", ca, "--token-file", TokenFile("wrong", "wrong")},
            {},
            "error: fenestrad refused the token (invalid bearer token): set --token-file or "
            "FENESTRA_TOKEN"},
           {{"--tls-ca", ca},
            {},
            "error: fenestrad wants a token (invalid bearer token): set --token-file or "
            "FENESTRA_TOKEN"},
           {{"--tls-ca", ca, "--token-file", *dir_ + "/missing"},
            {},
            "error: --token-file " + *dir_ + "/missing: cannot open (No such file or directory)"},
           {{"--tls-ca", ca, "--token-file", TokenFile("empty", " \n")},
            {},
            "error: --token-file " + *dir_ + "/empty: the token is empty"},
           {{"--tls-ca", ca},
            {"FENESTRA_TOKEN=two words"},
            "error: FENESTRA_TOKEN: the token's character 4 cannot go in a request header"},
           {{"--tls-ca", certificates_->other_ca_cert, "--token-file", TokenFile("right", "right")},
            {},
            "error: cannot reach fenestrad at " + server.address() + ": the TLS handshake failed"},
           {{"--tls-cert", certificates_->client_cert, "--tls-key", certificates_->client_key},
            {},
            "error: --tls-cert needs --tls-ca"},
       }) {
    const CommandResult run = RunExample(server, c.flags, c.environment);
    EXPECT_EQ(run.exit_code, 1) << run.output;
    EXPECT_THAT(run.output, HasSubstr(c.message));
    EXPECT_THAT(run.output, testing::Not(HasSubstr("Traceback")));
  }
  EXPECT_THAT(Authorizations(server), ElementsAre("Bearer wrong", "(none)"));
}

}  // namespace
}  // namespace fenestra
