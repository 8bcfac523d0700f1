#include "server/config.h"

#include <algorithm>

#include "absl/strings/str_cat.h"
#include "core/common/json_proto.h"
#include "core/dc/dc_backend.h"

namespace fenestra {

absl::StatusOr<v1::DaemonConfig> ReadConfigFile(const std::string& path) {
  v1::DaemonConfig config;
  absl::Status status = ReadJsonProtoFile(path, "configuration", &config);
  if (!status.ok()) return status;
  return config;
}

absl::StatusOr<v1::DaemonConfig> ResolveConfig(v1::DaemonConfig config) {
  auto invalid = [](const std::string& field, const std::string& why) {
    return absl::InvalidArgumentError(absl::StrCat("configuration: ", field, " ", why));
  };
  if (config.listen_address().empty()) config.set_listen_address("localhost:50051");
  if (config.data_dir().empty()) config.set_data_dir("fenestra-data");
  if (config.worker_threads() < 0) return invalid("worker_threads", "must be >= 0");
  if (config.backend().empty()) config.set_backend("auto");
  // By default one worker per visible GPU (jobs spread over the GPUs), else one
  if (config.worker_threads() == 0) {
    config.set_worker_threads(config.backend() == "cpu" ? 1 : std::max(1, CudaDevices()));
  }
  if (config.backend() != "cpu" && config.backend() != "cuda" && config.backend() != "auto") {
    return invalid("backend",
                   absl::StrCat("must be cpu, cuda or auto, got '", config.backend(), "'"));
  }
  if (config.shutdown_grace_seconds() < 0) {
    return invalid("shutdown_grace_seconds", "must be >= 0");
  }
  if (config.shutdown_grace_seconds() == 0) config.set_shutdown_grace_seconds(10);
  if (config.log_level().empty()) config.set_log_level("info");
  static const char* kLevels[] = {"trace", "debug", "info", "warn", "error", "critical", "off"};
  if (std::find(std::begin(kLevels), std::end(kLevels), config.log_level()) == std::end(kLevels)) {
    return invalid("log_level", absl::StrCat("must be trace, debug, info, warn, error, critical or "
                                             "off, got '",
                                             config.log_level(), "'"));
  }

  v1::Limits& limits = *config.mutable_limits();
  auto fill = [&](auto value, auto fallback, const char* field, auto set) -> absl::Status {
    if (value < 0) return invalid(absl::StrCat("limits.", field), "must be >= 0");
    if (value == 0) set(fallback);
    return absl::OkStatus();
  };
  for (absl::Status s : {
           fill(limits.max_outdoor_paths(), int64_t{1'000'000'000}, "max_outdoor_paths",
                [&](int64_t v) { limits.set_max_outdoor_paths(v); }),
           fill(limits.max_indoor_paths_per_sensor(), int64_t{10'000'000},
                "max_indoor_paths_per_sensor",
                [&](int64_t v) { limits.set_max_indoor_paths_per_sensor(v); }),
           fill(limits.max_sensors(), 10'000, "max_sensors",
                [&](int v) { limits.set_max_sensors(v); }),
           fill(limits.max_triangles(), int64_t{2'000'000}, "max_triangles",
                [&](int64_t v) { limits.set_max_triangles(v); }),
           fill(limits.max_evaluations(), 10'000, "max_evaluations",
                [&](int v) { limits.set_max_evaluations(v); }),
           fill(limits.max_message_bytes(), 64 << 20, "max_message_bytes",
                [&](int v) { limits.set_max_message_bytes(v); }),
           fill(limits.max_queued_jobs(), 64, "max_queued_jobs",
                [&](int v) { limits.set_max_queued_jobs(v); }),
           fill(limits.max_sites(), 1000, "max_sites", [&](int v) { limits.set_max_sites(v); }),
           fill(limits.max_data_dir_bytes(), kDefaultMaxDataDirBytes, "max_data_dir_bytes",
                [&](int64_t v) { limits.set_max_data_dir_bytes(v); }),
           fill(limits.max_concurrent_heavy_requests(), kDefaultMaxConcurrentHeavyRequests,
                "max_concurrent_heavy_requests",
                [&](int v) { limits.set_max_concurrent_heavy_requests(v); }),
       }) {
    if (!s.ok()) return s;
  }
  return config;
}

}  // namespace fenestra
