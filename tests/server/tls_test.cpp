#include "server/tls.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>

#include "tests/server/test_certificates.h"

namespace fenestra {
namespace {

using ::testing::HasSubstr;

class TlsTest : public testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = new std::string(testing::TempDir() + "/tls_test_" + std::to_string(getpid()));
    std::filesystem::remove_all(*dir_);
    std::filesystem::create_directories(*dir_);
    certs_ = new TestCertificates;
    MakeTestCertificates(*dir_, certs_);
  }
  static void TearDownTestSuite() {
    std::filesystem::remove_all(*dir_);
    delete dir_;
    delete certs_;
  }
  static v1::DaemonConfig Config(const std::string& cert, const std::string& key,
                                 const std::string& client_ca = "") {
    v1::DaemonConfig config;
    config.set_tls_cert_file(cert);
    config.set_tls_key_file(key);
    config.set_tls_client_ca_file(client_ca);
    return config;
  }
  static inline std::string* dir_ = nullptr;
  static inline TestCertificates* certs_ = nullptr;
};

TEST_F(TlsTest, MatchingFilesGiveTlsCredentials) {
  ASSERT_FALSE(HasFatalFailure());
  const TestCertificates& c = *certs_;
  EXPECT_TRUE(PortCredentials(Config(c.server_cert, c.server_key)).ok());
  EXPECT_TRUE(PortCredentials(Config(c.server_cert, c.server_key, c.ca)).ok());
  EXPECT_TRUE(PortCredentials(v1::DaemonConfig()).ok());  // plaintext
}

TEST_F(TlsTest, BadFilesStopTheStartNamingTheFile) {
  const TestCertificates& c = *certs_;
  absl::Status status = PortCredentials(Config(*dir_ + "/missing.pem", c.server_key)).status();
  EXPECT_EQ(status.code(), absl::StatusCode::kInvalidArgument);
  EXPECT_THAT(status.message(), HasSubstr("tls_cert_file " + *dir_ + "/missing.pem"));
  // A key where the certificate should be, and the other way round
  EXPECT_THAT(PortCredentials(Config(c.server_key, c.server_key)).status().message(),
              HasSubstr("holds no PEM certificate"));
  EXPECT_THAT(PortCredentials(Config(c.server_cert, c.server_cert)).status().message(),
              HasSubstr("holds no PEM private key"));
  // The client's key is not the server certificate's
  EXPECT_THAT(PortCredentials(Config(c.server_cert, c.client_key)).status().message(),
              HasSubstr("is not the key of the certificate"));
  const std::string empty = *dir_ + "/empty.pem";
  std::ofstream(empty).close();
  EXPECT_THAT(PortCredentials(Config(c.server_cert, c.server_key, empty)).status().message(),
              HasSubstr("tls_client_ca_file " + empty));
  EXPECT_THAT(PortCredentials(Config(c.server_cert, c.server_key, c.server_key)).status().message(),
              HasSubstr("tls_client_ca_file"));
}

}  // namespace
}  // namespace fenestra
