#pragma once

#include <grpcpp/security/server_credentials.h>

#include <memory>

#include "absl/status/statusor.h"
#include "fenestra/v1/daemon.pb.h"

namespace fenestra {

// The credentials of the daemon's port: TLS with the configured certificate chain and
// key, asking for and verifying client certificates against tls_client_ca_file when it
// is set (mutual TLS); plaintext without tls_cert_file. The PEM files are read and
// checked here (a certificate, a private key that matches it, CA certificates), so a bad
// file stops the start with a message naming it.
absl::StatusOr<std::shared_ptr<grpc::ServerCredentials>> PortCredentials(
    const v1::DaemonConfig& config);

}  // namespace fenestra
