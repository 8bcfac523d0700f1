#include "server/config.h"

#include <arpa/inet.h>

#include <algorithm>
#include <cmath>
#include <string_view>
#include <utility>

#include "absl/strings/ascii.h"
#include "absl/strings/match.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/strip.h"
#include "core/common/json_proto.h"
#include "core/dc/dc_backend.h"
#include "server/store/store.h"

namespace fenestra {
namespace {

// Defaults of the settings added with users and with the data-directory limits
// (daemon.proto documents them)
constexpr char kDefaultAuth[] = "token";
constexpr int kDefaultMaxQueuedJobsPerUser = 8;
constexpr int kDefaultMaxSitesPerUser = 100;
constexpr int64_t kDefaultMaxUploadBytesPerUser = int64_t{256} << 20;
constexpr int64_t kDefaultMaxDataDirBytes = int64_t{10} << 30;
constexpr int kDefaultMaxConcurrentHeavyRequests = 2;
// Defaults of the settings added with several candidates at once (daemon.proto documents them)
constexpr int kDefaultMaxCandidatesAtOnce = 4;
constexpr int kDefaultMaxHttpRequestsPerMinute = 1200;
// Defaults of the settings added with replicas (daemon.proto documents them)
constexpr double kDefaultLeaseSeconds = 10;
constexpr int64_t kDefaultOutdoorMemoryBytes = int64_t{1} << 30;
// A lease shorter than this would be renewed too often to be worth holding [s]
constexpr double kMinLeaseSeconds = 0.3;

// InvalidArgument "configuration: FIELD WHY".
absl::Status Invalid(const std::string& field, const std::string& why) {
  return absl::InvalidArgumentError(absl::StrCat("configuration: ", field, " ", why));
}

// Checks auth and TLS against the listen address: what leaves this machine is encrypted
// and authenticated unless the configuration says otherwise in so many words.
absl::Status CheckExposure(const v1::DaemonConfig& config) {
  if (config.auth() != "token" && config.auth() != "none") {
    return Invalid("auth", absl::StrCat("must be token or none, got '", config.auth(), "'"));
  }
  if (config.tls_cert_file().empty() != config.tls_key_file().empty()) {
    return Invalid("tls_cert_file and tls_key_file",
                   "(--tls-cert, --tls-key) go together: give both or neither");
  }
  if (!config.tls_client_ca_file().empty() && config.tls_cert_file().empty()) {
    return Invalid("tls_client_ca_file",
                   "(--tls-client-ca) needs tls_cert_file and tls_key_file: client certificates "
                   "are checked on top of the server's TLS");
  }
  // The gRPC port and the dashboard's answer the same callers the same way
  for (const auto& [field, address] :
       {std::pair<const char*, const std::string&>{"listen_address", config.listen_address()},
        {"http_listen", config.http_listen()}}) {
    if (address.empty() || IsLoopbackAddress(address)) continue;
    if (config.auth() == "none") {
      return Invalid("auth",
                     absl::StrCat("none makes every caller an administrator, so it is "
                                  "allowed only on a loopback ",
                                  field, " (localhost, 127.0.0.1, [::1]), not on '", address,
                                  "'; use auth token with users from `fenestrad user add`"));
    }
    if (config.tls_cert_file().empty() && !config.allow_plaintext()) {
      return Invalid(
          field,
          absl::StrCat("'", address,
                       "' is reachable from other machines, and without TLS tokens and scenes "
                       "would cross the network in clear: give tls_cert_file and tls_key_file "
                       "(--tls-cert, --tls-key), or set allow_plaintext (--allow-plaintext) when "
                       "a proxy in front terminates TLS"));
    }
  }
  return absl::OkStatus();
}

// Fills the limits left 0 with their defaults; InvalidArgument naming a negative one.
absl::Status ResolveLimits(v1::Limits& limits) {
  auto fill = [&](auto value, auto fallback, const char* field, auto set) -> absl::Status {
    if (value < 0) return Invalid(absl::StrCat("limits.", field), "must be >= 0");
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
           fill(limits.max_queued_jobs_per_user(), kDefaultMaxQueuedJobsPerUser,
                "max_queued_jobs_per_user", [&](int v) { limits.set_max_queued_jobs_per_user(v); }),
           fill(limits.max_sites_per_user(), kDefaultMaxSitesPerUser, "max_sites_per_user",
                [&](int v) { limits.set_max_sites_per_user(v); }),
           fill(limits.max_upload_bytes_per_user(), kDefaultMaxUploadBytesPerUser,
                "max_upload_bytes_per_user",
                [&](int64_t v) { limits.set_max_upload_bytes_per_user(v); }),
           fill(limits.max_data_dir_bytes(), kDefaultMaxDataDirBytes, "max_data_dir_bytes",
                [&](int64_t v) { limits.set_max_data_dir_bytes(v); }),
           fill(limits.max_concurrent_heavy_requests(), kDefaultMaxConcurrentHeavyRequests,
                "max_concurrent_heavy_requests",
                [&](int v) { limits.set_max_concurrent_heavy_requests(v); }),
           fill(limits.max_candidates_at_once(), kDefaultMaxCandidatesAtOnce,
                "max_candidates_at_once", [&](int v) { limits.set_max_candidates_at_once(v); }),
           fill(limits.max_http_requests_per_minute(), kDefaultMaxHttpRequestsPerMinute,
                "max_http_requests_per_minute",
                [&](int v) { limits.set_max_http_requests_per_minute(v); }),
       }) {
    if (!s.ok()) return s;
  }
  return absl::OkStatus();
}

}  // namespace

bool IsLoopbackAddress(const std::string& listen_address) {
  absl::string_view address = listen_address;
  if (absl::StartsWith(address, "unix:") || absl::StartsWith(address, "unix-abstract:")) {
    return true;
  }
  for (absl::string_view scheme : {"ipv4:", "ipv6:"}) absl::ConsumePrefix(&address, scheme);
  std::string host;
  if (absl::StartsWith(address, "[")) {
    const size_t end = address.find(']');
    if (end == absl::string_view::npos) return false;
    host = std::string(address.substr(1, end - 1));
  } else {
    host = std::string(address.substr(0, address.rfind(':')));
  }
  if (absl::AsciiStrToLower(host) == "localhost") return true;
  in_addr v4{};
  if (inet_pton(AF_INET, host.c_str(), &v4) == 1) return (ntohl(v4.s_addr) >> 24) == 127;
  in6_addr v6{};
  if (inet_pton(AF_INET6, host.c_str(), &v6) == 1) {
    if (IN6_IS_ADDR_LOOPBACK(&v6)) return true;
    return IN6_IS_ADDR_V4MAPPED(&v6) && v6.s6_addr[12] == 127;
  }
  return false;
}

absl::StatusOr<v1::DaemonConfig> ReadConfigFile(const std::string& path) {
  v1::DaemonConfig config;
  absl::Status status = ReadJsonProtoFile(path, "configuration", &config);
  if (!status.ok()) return status;
  return config;
}

absl::StatusOr<v1::DaemonConfig> ResolveConfig(v1::DaemonConfig config) {
  if (config.listen_address().empty()) config.set_listen_address("localhost:50051");
  if (config.data_dir().empty()) config.set_data_dir("fenestra-data");
  if (!config.health_listen().empty() && config.health_listen() == config.listen_address() &&
      !absl::EndsWith(config.listen_address(), ":0")) {
    return Invalid("health_listen", absl::StrCat("must be another address than listen_address ('",
                                                 config.listen_address(),
                                                 "'): the health port serves only "
                                                 "health checks, in plaintext"));
  }
  if (!config.http_listen().empty() && !absl::EndsWith(config.http_listen(), ":0") &&
      (config.http_listen() == config.listen_address() ||
       config.http_listen() == config.health_listen())) {
    return Invalid("http_listen", "must be another address than listen_address and health_listen");
  }
  if (config.worker_threads() < 0) return Invalid("worker_threads", "must be >= 0");
  if (config.backend().empty()) config.set_backend("auto");
  if (config.gpus().empty()) config.set_gpus("all");
  absl::StatusOr<std::vector<int>> gpus = ParseGpuList(config.gpus(), CudaDevices());
  if (!gpus.ok()) {
    return absl::InvalidArgumentError(absl::StrCat("configuration: ", gpus.status().message()));
  }
  // By default one worker per GPU (jobs spread over the GPUs), else one
  if (config.worker_threads() == 0) {
    config.set_worker_threads(
        config.backend() == "cpu" ? 1 : std::max(1, static_cast<int>(gpus->size())));
  }
  if (config.backend() != "cpu" && config.backend() != "cuda" && config.backend() != "auto") {
    return Invalid("backend",
                   absl::StrCat("must be cpu, cuda or auto, got '", config.backend(), "'"));
  }
  if (config.shutdown_grace_seconds() < 0) {
    return Invalid("shutdown_grace_seconds", "must be >= 0");
  }
  if (config.shutdown_grace_seconds() == 0) config.set_shutdown_grace_seconds(10);
  if (config.log_level().empty()) config.set_log_level("info");
  if (config.auth().empty()) config.set_auth(kDefaultAuth);
  if (!config.store().empty() && !IsPostgresUrl(config.store())) {
    return Invalid("store",
                   "must be empty (SQLite in data_dir) or a PostgreSQL URL "
                   "postgresql://user@host:port/database");
  }
  if (config.lease_seconds() < 0 || !std::isfinite(config.lease_seconds())) {
    return Invalid("lease_seconds", "must be a finite number >= 0");
  }
  if (config.lease_seconds() == 0) config.set_lease_seconds(kDefaultLeaseSeconds);
  if (config.lease_seconds() < kMinLeaseSeconds) {
    return Invalid("lease_seconds", absl::StrCat("must be at least ", kMinLeaseSeconds, " s"));
  }
  if (config.outdoor_memory_bytes() < 0) return Invalid("outdoor_memory_bytes", "must be >= 0");
  if (config.outdoor_memory_bytes() == 0) {
    config.set_outdoor_memory_bytes(kDefaultOutdoorMemoryBytes);
  }
  if (absl::Status s = CheckExposure(config); !s.ok()) return s;
  static const char* kLevels[] = {"trace", "debug", "info", "warn", "error", "critical", "off"};
  if (std::find(std::begin(kLevels), std::end(kLevels), config.log_level()) == std::end(kLevels)) {
    return Invalid("log_level", absl::StrCat("must be trace, debug, info, warn, error, critical or "
                                             "off, got '",
                                             config.log_level(), "'"));
  }

  if (absl::Status s = ResolveLimits(*config.mutable_limits()); !s.ok()) return s;
  return config;
}

}  // namespace fenestra
