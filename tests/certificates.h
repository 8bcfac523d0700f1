// Certificates for TLS tests, made with the openssl command.
#pragma once

#include <grpcpp/grpcpp.h>

#include <memory>
#include <string>

#include "absl/status/statusor.h"

namespace fenestra {

// Paths of PEM files: a CA; a server certificate it signed for 127.0.0.1 and localhost; a
// client certificate it signed; and another CA, which signed none of them.
struct TestCertificates {
  std::string ca_cert, server_cert, server_key, client_cert, client_key, other_ca_cert;
  std::string dir;  // the folder that holds them
};

// Makes the files in `dir` (P-256 keys, valid for a day); the error holds openssl's output.
absl::StatusOr<TestCertificates> MakeTestCertificates(const std::string& dir);

// The certificates of this test process: made on first use in a temporary folder of its own
// (ctest runs tests as processes side by side), which goes when the process ends.
const absl::StatusOr<TestCertificates>& ProcessTestCertificates();

// ProcessTestCertificates(), failing the running test (with openssl's output) and giving empty
// paths when they could not be made.
const TestCertificates& Certs();

// TLS with the server certificate; with `require_client_certificate`, only clients whose
// certificate the CA signed get in (mTLS).
std::shared_ptr<grpc::ServerCredentials> ServerTlsCredentials(const TestCertificates& files,
                                                              bool require_client_certificate);

}  // namespace fenestra
