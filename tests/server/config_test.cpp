#include "server/config.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

namespace fenestra {
namespace {

using ::testing::HasSubstr;

TEST(ConfigTest, EmptyConfigGetsTheDocumentedDefaults) {
  absl::StatusOr<v1::DaemonConfig> config = ResolveConfig(v1::DaemonConfig());
  ASSERT_TRUE(config.ok()) << config.status();
  EXPECT_EQ(config->listen_address(), "localhost:50051");
  EXPECT_EQ(config->data_dir(), "fenestra-data");
  EXPECT_EQ(config->worker_threads(), 1);
  EXPECT_EQ(config->backend(), "auto");
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
  EXPECT_TRUE(ResolveConfig(*config).ok());
}

}  // namespace
}  // namespace fenestra
