#include "tests/certificates.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <vector>

#include "absl/strings/str_cat.h"
#include "client/cli_util.h"
#include "tests/child_process.h"

namespace fenestra {
namespace {

// `openssl req -x509` making a key and a certificate for `subject`, signed by `ca` (self-
// signed when empty), with the X.509 extensions `extensions`.
absl::Status MakeCertificate(const std::string& dir, const std::string& name,
                             const std::string& subject, const std::string& ca,
                             const std::vector<std::string>& extensions) {
  std::vector<std::string> argv = {OPENSSL_EXECUTABLE,
                                   "req",
                                   "-x509",
                                   "-newkey",
                                   "ec",
                                   "-pkeyopt",
                                   "ec_paramgen_curve:prime256v1",
                                   "-nodes",
                                   "-days",
                                   "1",
                                   "-subj",
                                   "/CN=" + subject,
                                   "-keyout",
                                   dir + "/" + name + ".key",
                                   "-out",
                                   dir + "/" + name + ".crt"};
  if (!ca.empty()) {
    argv.insert(argv.end(), {"-CA", dir + "/" + ca + ".crt", "-CAkey", dir + "/" + ca + ".key"});
  }
  for (const std::string& extension : extensions) argv.insert(argv.end(), {"-addext", extension});
  const CommandResult result = RunCommand(argv);
  if (result.exit_code != 0) {
    return absl::InternalError(absl::StrCat("openssl req for ", name, ": ", result.output));
  }
  return absl::OkStatus();
}

}  // namespace

absl::StatusOr<TestCertificates> MakeTestCertificates(const std::string& dir) {
  const std::string leaf = "basicConstraints=critical,CA:FALSE";
  for (const absl::Status& status : {
           MakeCertificate(dir, "ca", "Fenestra test CA", "", {}),
           MakeCertificate(dir, "other_ca", "Another CA", "", {}),
           MakeCertificate(
               dir, "server", "fenestrad", "ca",
               {leaf, "subjectAltName=IP:127.0.0.1,DNS:localhost", "extendedKeyUsage=serverAuth"}),
           MakeCertificate(dir, "client", "fenestra client", "ca",
                           {leaf, "extendedKeyUsage=clientAuth"}),
       }) {
    if (!status.ok()) return status;
  }
  return TestCertificates{dir + "/ca.crt",
                          dir + "/server.crt",
                          dir + "/server.key",
                          dir + "/client.crt",
                          dir + "/client.key",
                          dir + "/other_ca.crt",
                          dir};
}

const absl::StatusOr<TestCertificates>& ProcessTestCertificates() {
  // The folder, removed at exit
  static const struct Folder {
    Folder() : path(testing::TempDir() + "/fenestra_certificates_" + std::to_string(getpid())) {
      std::filesystem::remove_all(path);
      std::filesystem::create_directories(path);
    }
    ~Folder() { std::filesystem::remove_all(path); }
    std::string path;
  } folder;
  static const absl::StatusOr<TestCertificates> certificates = MakeTestCertificates(folder.path);
  return certificates;
}

const TestCertificates& Certs() {
  const absl::StatusOr<TestCertificates>& certificates = ProcessTestCertificates();
  EXPECT_TRUE(certificates.ok()) << certificates.status();
  static const TestCertificates none;
  return certificates.ok() ? *certificates : none;
}

std::shared_ptr<grpc::ServerCredentials> ServerTlsCredentials(const TestCertificates& files,
                                                              bool require_client_certificate) {
  grpc::SslServerCredentialsOptions options(
      require_client_certificate ? GRPC_SSL_REQUEST_AND_REQUIRE_CLIENT_CERTIFICATE_AND_VERIFY
                                 : GRPC_SSL_DONT_REQUEST_CLIENT_CERTIFICATE);
  options.pem_root_certs = ReadFileBytes(files.ca_cert).value_or("");
  options.pem_key_cert_pairs.push_back({ReadFileBytes(files.server_key).value_or(""),
                                        ReadFileBytes(files.server_cert).value_or("")});
  return grpc::SslServerCredentials(options);
}

}  // namespace fenestra
