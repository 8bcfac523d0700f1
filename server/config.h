#pragma once

#include <cstdint>
#include <string>

#include "absl/status/statusor.h"
#include "fenestra/v1/daemon.pb.h"

namespace fenestra {

// Defaults of limits.max_data_dir_bytes [bytes] and limits.max_concurrent_heavy_requests
// [requests] (daemon.proto).
inline constexpr int64_t kDefaultMaxDataDirBytes = int64_t{10} << 30;
inline constexpr int kDefaultMaxConcurrentHeavyRequests = 2;

// Reads a daemon configuration file: the JSON form of fenestra.v1.DaemonConfig (protobuf's
// JSON mapping; unknown fields are errors). Errors name the file.
absl::StatusOr<v1::DaemonConfig> ReadConfigFile(const std::string& path);

// Fills in the defaults documented in daemon.proto and checks ranges; errors name the
// field.
absl::StatusOr<v1::DaemonConfig> ResolveConfig(v1::DaemonConfig config);

}  // namespace fenestra
