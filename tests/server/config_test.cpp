#include "server/config.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <thread>
#include <vector>

#include "core/dc/dc_backend.h"

namespace fenestra {
namespace {

using ::testing::HasSubstr;

TEST(ConfigTest, EmptyConfigGetsTheDocumentedDefaults) {
  absl::StatusOr<v1::DaemonConfig> config = ResolveConfig(v1::DaemonConfig());
  ASSERT_TRUE(config.ok()) << config.status();
  EXPECT_EQ(config->listen_address(), "localhost:50051");
  EXPECT_EQ(config->data_dir(), "fenestra-data");
  EXPECT_EQ(config->worker_threads(), std::max(1, CudaDevices()));  // one per GPU
  EXPECT_EQ(config->backend(), "auto");
  EXPECT_EQ(config->gpus(), "all");
  EXPECT_EQ(config->shutdown_grace_seconds(), 10);
  EXPECT_EQ(config->limits().max_outdoor_paths(), 1'000'000'000);
  EXPECT_EQ(config->limits().max_indoor_paths_per_sensor(), 10'000'000);
  EXPECT_EQ(config->limits().max_sensors(), 10'000);
  EXPECT_EQ(config->limits().max_triangles(), 2'000'000);
  EXPECT_EQ(config->limits().max_evaluations(), 10'000);
  EXPECT_EQ(config->limits().max_message_bytes(), 64 << 20);
  EXPECT_EQ(config->limits().max_queued_jobs(), 64);
  EXPECT_EQ(config->limits().max_sites(), 1000);
  EXPECT_EQ(config->limits().max_data_dir_bytes(), int64_t{10} << 30);
  EXPECT_EQ(config->limits().max_concurrent_heavy_requests(), 2);
  EXPECT_EQ(config->limits().max_candidates_at_once(), 4);
  EXPECT_EQ(config->limits().max_http_requests_per_minute(), 1200);
  EXPECT_EQ(config->http_listen(), "");  // no dashboard
  EXPECT_EQ(config->limits().max_queued_jobs_per_user(), 8);
  EXPECT_EQ(config->limits().max_sites_per_user(), 100);
  EXPECT_EQ(config->limits().max_upload_bytes_per_user(), 256 << 20);
  EXPECT_EQ(config->auth(), "token");
  EXPECT_TRUE(config->tls_cert_file().empty());
  EXPECT_FALSE(config->allow_plaintext());
  EXPECT_TRUE(config->store().empty());  // SQLite in data_dir
  EXPECT_EQ(config->lease_seconds(), 10);
  EXPECT_EQ(config->outdoor_memory_bytes(), int64_t{1} << 30);
}

TEST(ConfigTest, GpusAreAllOrDistinctVisibleDeviceIndices) {
  EXPECT_THAT(*ParseGpuList("all", 4), ::testing::ElementsAre(0, 1, 2, 3));
  EXPECT_TRUE(ParseGpuList("all", 0)->empty());
  EXPECT_THAT(*ParseGpuList("2,0", 4), ::testing::ElementsAre(2, 0));
  EXPECT_THAT(*ParseGpuList(" 1", 4), ::testing::ElementsAre(1));
  EXPECT_THAT(ParseGpuList("4", 4).status().message(), HasSubstr("there is no GPU 4 (4 visible"));
  EXPECT_THAT(ParseGpuList("0", 0).status().message(), HasSubstr("none visible"));
  EXPECT_THAT(ParseGpuList("1,1", 4).status().message(), HasSubstr("GPU 1 is listed twice"));
  EXPECT_THAT(ParseGpuList("-1", 4).status().message(), HasSubstr("there is no GPU -1"));
  for (const char* bad : {"", "0,", "one", "0;1", "1.5", "all,0"}) {
    EXPECT_THAT(ParseGpuList(bad, 4).status().message(), HasSubstr("gpus must be")) << bad;
  }
  // Through the configuration: a device this host lacks is refused at start
  v1::DaemonConfig config;
  config.set_gpus("99");
  EXPECT_THAT(ResolveConfig(config).status().message(),
              HasSubstr("configuration: gpus: there is no GPU 99"));
}

// The workers share out the GPUs of `gpus`; a worker's thread takes only its own in turn, and
// other threads keep the process's. The share-out is index arithmetic, so it runs without a GPU.
TEST(ConfigTest, WorkersShareOutTheGpus) {
  UseCudaDevices({3, 1, 2});
  EXPECT_THAT(WorkerCudaDevices(0, 3), ::testing::ElementsAre(3));
  EXPECT_THAT(WorkerCudaDevices(2, 3), ::testing::ElementsAre(2));
  EXPECT_THAT(WorkerCudaDevices(4, 6), ::testing::ElementsAre(1));  // more workers: shared
  EXPECT_THAT(WorkerCudaDevices(0, 2), ::testing::ElementsAre(3, 2));
  EXPECT_THAT(WorkerCudaDevices(1, 2), ::testing::ElementsAre(1));
  EXPECT_THAT(WorkerCudaDevices(0, 1), ::testing::ElementsAre(3, 1, 2));
  EXPECT_EQ(CudaDevicesInUse(), 3);
  {
    const ThreadCudaDevices mine(WorkerCudaDevices(0, 2));
    EXPECT_EQ(CudaDevicesInUse(), 2);
    std::vector<int> taken;
    for (int k = 0; k < 5; ++k) taken.push_back(NextCudaDevice());
    EXPECT_THAT(taken, ::testing::ElementsAre(3, 2, 3, 2, 3));
    std::thread other([] { EXPECT_EQ(CudaDevicesInUse(), 3); });
    other.join();
    {
      const ThreadCudaDevices none({});  // empty: this thread's devices stay
      EXPECT_EQ(CudaDevicesInUse(), 2);
    }
  }
  EXPECT_EQ(CudaDevicesInUse(), 3);
  UseCudaDevices({});
  EXPECT_EQ(WorkerCudaDevices(0, 2).empty(), CudaDevices() == 0);  // every visible GPU
}

// A job's lanes take the GPUs after its first lane's in turn, on the job's thread's GPUs,
// whatever other backends take meanwhile. Index arithmetic again, so it runs without a GPU.
TEST(ConfigTest, AJobsLanesTakeTheGpusAfterItsFirst) {
  UseCudaDevices({3, 1, 2});
  std::vector<int> lanes;
  for (int lane = 0; lane < 4; ++lane) lanes.push_back(LaneCudaDevice(1, lane));
  EXPECT_THAT(lanes, ::testing::ElementsAre(1, 2, 3, 1));  // more lanes than GPUs: in turn
  for (int k = 0; k < 3; ++k) NextCudaDevice();            // other stages' backends
  EXPECT_EQ(LaneCudaDevice(1, 1), 2);
  EXPECT_EQ(LaneCudaDevice(3, 1), 1);
  EXPECT_EQ(LaneCudaDevice(0, 1), 0);  // a GPU not in use: the lanes stay on it
  {
    const ThreadCudaDevices worker({2});  // a daemon worker's thread: its GPU only
    EXPECT_EQ(LaneCudaDevice(2, 1), 2);
    EXPECT_EQ(LaneCudaDevice(2, 2), 2);
  }
  UseCudaDevices({});
}

TEST(ConfigTest, TheStoreIsSqliteOrAPostgresqlUrlAndLeasesAreNotTooShort) {
  v1::DaemonConfig config;
  config.set_store("postgresql://fenestra@db.example.org:5432/fenestra");
  EXPECT_TRUE(ResolveConfig(config).ok());
  config.set_store("postgres://fenestra@db/fenestra");
  EXPECT_TRUE(ResolveConfig(config).ok());
  config.set_store("mysql://fenestra@db/fenestra");
  EXPECT_THAT(ResolveConfig(config).status().message(),
              HasSubstr("store must be empty (SQLite in data_dir) or a PostgreSQL URL"));
  config = v1::DaemonConfig();
  config.set_lease_seconds(0.1);
  EXPECT_THAT(ResolveConfig(config).status().message(),
              HasSubstr("lease_seconds must be at least 0.3 s"));
  config.set_lease_seconds(-1);
  EXPECT_THAT(ResolveConfig(config).status().message(), HasSubstr("lease_seconds"));
  config = v1::DaemonConfig();
  config.set_outdoor_memory_bytes(-1);
  EXPECT_THAT(ResolveConfig(config).status().message(), HasSubstr("outdoor_memory_bytes"));
}

TEST(ConfigTest, LoopbackAddresses) {
  for (const char* local :
       {"localhost:50051", "LocalHost:1", "127.0.0.1:50051", "127.8.9.10:0", "[::1]:50051",
        "ipv4:127.0.0.1:5", "ipv6:[::1]:5", "[::ffff:127.0.0.1]:5", "unix:/run/fenestra.sock"}) {
    EXPECT_TRUE(IsLoopbackAddress(local)) << local;
  }
  for (const char* exposed :
       {"0.0.0.0:50051", "[::]:50051", ":50051", "192.168.1.4:50051", "fenestra.example.org:50051",
        "localhost.example.org:1", "128.0.0.1:5", "[::2]:5", "[::1:5"}) {
    EXPECT_FALSE(IsLoopbackAddress(exposed)) << exposed;
  }
}

TEST(ConfigTest, BeyondLoopbackNeedsTlsAndTokens) {
  v1::DaemonConfig config;
  config.set_listen_address("0.0.0.0:50051");
  absl::Status status = ResolveConfig(config).status();
  EXPECT_EQ(status.code(), absl::StatusCode::kInvalidArgument);
  EXPECT_THAT(status.message(), HasSubstr("tls_cert_file and tls_key_file"));
  EXPECT_THAT(status.message(), HasSubstr("allow_plaintext"));
  config.set_allow_plaintext(true);
  EXPECT_TRUE(ResolveConfig(config).ok());
  config.set_allow_plaintext(false);
  config.set_tls_cert_file("server.crt");
  EXPECT_THAT(ResolveConfig(config).status().message(), HasSubstr("go together"));
  config.set_tls_key_file("server.key");
  EXPECT_TRUE(ResolveConfig(config).ok());
  // auth none: loopback only, TLS or not
  config.set_auth("none");
  status = ResolveConfig(config).status();
  EXPECT_EQ(status.code(), absl::StatusCode::kInvalidArgument);
  EXPECT_THAT(status.message(), HasSubstr("auth none"));
  EXPECT_THAT(status.message(), HasSubstr("loopback"));
  config.set_listen_address("127.0.0.1:0");
  EXPECT_TRUE(ResolveConfig(config).ok());
  config.set_auth("password");
  EXPECT_THAT(ResolveConfig(config).status().message(), HasSubstr("auth must be token or none"));
  // The dashboard's port on the same terms, and on a port of its own
  config = v1::DaemonConfig();
  config.set_http_listen("0.0.0.0:8080");
  status = ResolveConfig(config).status();
  EXPECT_EQ(status.code(), absl::StatusCode::kInvalidArgument);
  EXPECT_THAT(status.message(), HasSubstr("http_listen"));
  EXPECT_THAT(status.message(), HasSubstr("allow_plaintext"));
  config.set_tls_cert_file("server.crt");
  config.set_tls_key_file("server.key");
  EXPECT_TRUE(ResolveConfig(config).ok());
  config.set_auth("none");
  EXPECT_THAT(ResolveConfig(config).status().message(), HasSubstr("loopback http_listen"));
  config = v1::DaemonConfig();
  config.set_http_listen("localhost:50051");
  EXPECT_THAT(ResolveConfig(config).status().message(), HasSubstr("another address"));
  // Client certificates are checked on top of the server's TLS
  config = v1::DaemonConfig();
  config.set_tls_client_ca_file("ca.pem");
  EXPECT_THAT(ResolveConfig(config).status().message(), HasSubstr("tls_client_ca_file"));
  config = v1::DaemonConfig();
  config.mutable_limits()->set_max_upload_bytes_per_user(-1);
  EXPECT_THAT(ResolveConfig(config).status().message(),
              HasSubstr("limits.max_upload_bytes_per_user"));
}

TEST(ConfigTest, BadValuesNameTheField) {
  v1::DaemonConfig config;
  config.set_backend("opencl");
  EXPECT_THAT(ResolveConfig(config).status().message(), HasSubstr("backend"));
  config = v1::DaemonConfig();
  config.mutable_limits()->set_max_sensors(-1);
  EXPECT_THAT(ResolveConfig(config).status().message(), HasSubstr("limits.max_sensors"));
  config = v1::DaemonConfig();
  config.set_log_level("loud");
  EXPECT_THAT(ResolveConfig(config).status().message(), HasSubstr("log_level"));
}

TEST(ConfigTest, ReadsJsonAndRejectsUnknownFields) {
  const std::string path = testing::TempDir() + "/fenestrad_config_test.json";
  std::ofstream(path) << R"({"listenAddress": "0.0.0.0:6000", "workerThreads": 3,
                             "limits": {"maxQueuedJobs": 5}})";
  absl::StatusOr<v1::DaemonConfig> config = ReadConfigFile(path);
  ASSERT_TRUE(config.ok()) << config.status();
  EXPECT_EQ(config->listen_address(), "0.0.0.0:6000");
  EXPECT_EQ(config->worker_threads(), 3);
  EXPECT_EQ(config->limits().max_queued_jobs(), 5);

  std::ofstream(path) << R"({"listen": "x"})";
  absl::Status status = ReadConfigFile(path).status();
  EXPECT_EQ(status.code(), absl::StatusCode::kInvalidArgument);
  EXPECT_THAT(status.message(), HasSubstr(path));
  EXPECT_EQ(ReadConfigFile(path + ".missing").status().code(), absl::StatusCode::kNotFound);
}

TEST(ConfigTest, ExampleConfigurationResolves) {
  absl::StatusOr<v1::DaemonConfig> config =
      ReadConfigFile(FENESTRA_SOURCE_DIR "/deploy/fenestrad.example.json");
  ASSERT_TRUE(config.ok()) << config.status();
  absl::StatusOr<v1::DaemonConfig> resolved = ResolveConfig(*config);
  ASSERT_TRUE(resolved.ok()) << resolved.status();
  // All interfaces, so TLS and tokens
  EXPECT_FALSE(IsLoopbackAddress(resolved->listen_address()));
  EXPECT_FALSE(resolved->tls_cert_file().empty());
  EXPECT_FALSE(resolved->allow_plaintext());
  EXPECT_EQ(resolved->auth(), "token");
}

TEST(ConfigTest, HealthPortIsOffByDefaultAndAnotherAddressThanTheMainPort) {
  v1::DaemonConfig config;
  absl::StatusOr<v1::DaemonConfig> resolved = ResolveConfig(config);
  ASSERT_TRUE(resolved.ok()) << resolved.status();
  EXPECT_TRUE(resolved->health_listen().empty());

  // Plaintext beyond loopback, beside a main port with TLS: it tells only health
  config.set_listen_address("0.0.0.0:50051");
  config.set_tls_cert_file("server.crt");
  config.set_tls_key_file("server.key");
  config.set_health_listen("0.0.0.0:8081");
  resolved = ResolveConfig(config);
  ASSERT_TRUE(resolved.ok()) << resolved.status();
  EXPECT_EQ(resolved->health_listen(), "0.0.0.0:8081");

  config.set_health_listen("0.0.0.0:50051");
  const absl::Status status = ResolveConfig(config).status();
  EXPECT_EQ(status.code(), absl::StatusCode::kInvalidArgument);
  EXPECT_THAT(status.message(), HasSubstr("health_listen must be another address"));
  // Port 0 picks a free port for each
  config.set_listen_address("127.0.0.1:0");
  config.set_health_listen("127.0.0.1:0");
  EXPECT_TRUE(ResolveConfig(config).ok());
}

}  // namespace
}  // namespace fenestra
