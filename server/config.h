#pragma once

#include <string>

#include "absl/status/statusor.h"
#include "fenestra/v1/daemon.pb.h"

namespace fenestra {

// Reads a daemon configuration file: the JSON form of fenestra.v1.DaemonConfig (protobuf's
// JSON mapping; unknown fields are errors). Errors name the file.
absl::StatusOr<v1::DaemonConfig> ReadConfigFile(const std::string& path);

// Fills in the defaults documented in daemon.proto and checks ranges; errors name the
// field.
absl::StatusOr<v1::DaemonConfig> ResolveConfig(v1::DaemonConfig config);

}  // namespace fenestra
