#pragma once

#include <string>

#include "absl/status/statusor.h"
#include "fenestra/v1/daemon.pb.h"

namespace fenestra {

// Reads a daemon configuration file: the JSON form of fenestra.v1.DaemonConfig (protobuf's
// JSON mapping; unknown fields are errors). Errors name the file.
absl::StatusOr<v1::DaemonConfig> ReadConfigFile(const std::string& path);

// Fills in the defaults documented in daemon.proto and checks ranges; errors name the
// field. Refuses what would expose the daemon: auth "none" or plaintext (no TLS, no
// allow_plaintext) on a listen_address beyond loopback.
absl::StatusOr<v1::DaemonConfig> ResolveConfig(v1::DaemonConfig config);

// True when a listen address ("host:port", "[v6]:port", "unix:path") only accepts
// connections from this machine: localhost, 127.0.0.0/8, ::1, Unix sockets. Any other
// host, the wildcard addresses and names included, is not loopback.
bool IsLoopbackAddress(const std::string& listen_address);

}  // namespace fenestra
