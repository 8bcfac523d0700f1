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
};

// Makes the files in `dir` (P-256 keys, valid for a day); the error holds openssl's output.
absl::StatusOr<TestCertificates> MakeTestCertificates(const std::string& dir);

// The certificates of this test process: made on first use in a temporary folder, which
// goes when the process ends.
const absl::StatusOr<TestCertificates>& ProcessTestCertificates();

// TLS with the server certificate; with `require_client_certificate`, only clients whose
// certificate the CA signed get in (mTLS).
std::shared_ptr<grpc::ServerCredentials> ServerTlsCredentials(const TestCertificates& files,
                                                              bool require_client_certificate);

}  // namespace fenestra
