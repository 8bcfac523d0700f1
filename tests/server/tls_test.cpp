#include "server/tls.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>

#include "tests/certificates.h"

namespace fenestra {
namespace {

using ::testing::HasSubstr;

class TlsTest : public testing::Test {
 protected:
  static v1::DaemonConfig Config(const std::string& cert, const std::string& key,
                                 const std::string& client_ca = "") {
    v1::DaemonConfig config;
    config.set_tls_cert_file(cert);
    config.set_tls_key_file(key);
    config.set_tls_client_ca_file(client_ca);
    return config;
  }
};

TEST_F(TlsTest, MatchingFilesGiveTlsCredentials) {
  ASSERT_FALSE(HasFatalFailure());
  const TestCertificates& c = Certs();
  EXPECT_TRUE(PortCredentials(Config(c.server_cert, c.server_key)).ok());
  EXPECT_TRUE(PortCredentials(Config(c.server_cert, c.server_key, c.ca_cert)).ok());
  EXPECT_TRUE(PortCredentials(v1::DaemonConfig()).ok());  // plaintext
}

TEST_F(TlsTest, BadFilesStopTheStartNamingTheFile) {
  const TestCertificates& c = Certs();
  absl::Status status =
      PortCredentials(Config(Certs().dir + "/missing.pem", c.server_key)).status();
  EXPECT_EQ(status.code(), absl::StatusCode::kInvalidArgument);
  EXPECT_THAT(status.message(), HasSubstr("tls_cert_file " + Certs().dir + "/missing.pem"));
  // A key where the certificate should be, and the other way round
  EXPECT_THAT(PortCredentials(Config(c.server_key, c.server_key)).status().message(),
              HasSubstr("holds no PEM certificate"));
  EXPECT_THAT(PortCredentials(Config(c.server_cert, c.server_cert)).status().message(),
              HasSubstr("holds no PEM private key"));
  // The client's key is not the server certificate's
  EXPECT_THAT(PortCredentials(Config(c.server_cert, c.client_key)).status().message(),
              HasSubstr("is not the key of the certificate"));
  const std::string empty = Certs().dir + "/empty.pem";
  std::ofstream(empty).close();
  EXPECT_THAT(PortCredentials(Config(c.server_cert, c.server_key, empty)).status().message(),
              HasSubstr("tls_client_ca_file " + empty));
  EXPECT_THAT(PortCredentials(Config(c.server_cert, c.server_key, c.server_key)).status().message(),
              HasSubstr("tls_client_ca_file"));
}

}  // namespace
}  // namespace fenestra
