// fenestrad: the Fenestra daemon. Serves SiteService and JobService (gRPC), runs jobs on
// worker threads, caches outdoor matrices and keeps jobs in data_dir/fenestra.db.
// Configuration: a JSON file (fenestra.v1.DaemonConfig, --config) and flags, which win.
#include <google/protobuf/stubs/logging.h>
#include <signal.h>
#include <spdlog/sinks/stdout_color_sinks.h>
#include <spdlog/spdlog.h>

#include <CLI/CLI.hpp>
#include <fstream>
#include <iostream>

#include "server/config.h"
#include "server/daemon.h"

int main(int argc, char** argv) {
  CLI::App app{"fenestrad: the Fenestra daylight optimization service"};
  std::string config_file, port_file;
  std::string listen, data_dir, backend, log_level;
  int workers = 0, max_sensors = 0, max_evaluations = 0, max_message_bytes = 0, max_queued_jobs = 0,
      max_sites = 0;
  int64_t max_outdoor_paths = 0, max_indoor_paths = 0, max_triangles = 0;
  double grace = 0;
  app.add_option("--config", config_file, "JSON configuration file (fenestra.v1.DaemonConfig)");
  app.add_option("--listen", listen, "host:port to listen on [localhost:50051]");
  app.add_option("--data-dir", data_dir,
                 "job store, outdoor cache and weather files [fenestra-data]");
  app.add_option(
      "--workers", workers,
      "jobs and site computations run at once [one per GPU, at least 1; 1 with --backend cpu]");
  app.add_option("--backend", backend, "tracer for jobs that name none: cpu, cuda, auto [auto]");
  app.add_option("--max-outdoor-paths", max_outdoor_paths, "limit: outdoor paths [1e9]");
  app.add_option("--max-indoor-paths", max_indoor_paths, "limit: indoor paths per sensor [1e7]");
  app.add_option("--max-sensors", max_sensors, "limit: sensors per scene [10000]");
  app.add_option("--max-triangles", max_triangles, "limit: triangles per scene [2e6]");
  app.add_option("--max-evaluations", max_evaluations, "limit: evaluations per job [10000]");
  app.add_option("--max-message-bytes", max_message_bytes, "limit: request size [64 MiB]");
  app.add_option("--max-queued-jobs", max_queued_jobs, "limit: jobs waiting [64]");
  app.add_option("--max-sites", max_sites, "limit: registered sites [1000]");
  app.add_option("--shutdown-grace", grace,
                 "seconds running jobs may go on after SIGTERM before they are interrupted [10]");
  app.add_option("--log-level", log_level, "trace, debug, info, warn, error [info]");
  app.add_option("--port-file", port_file, "write the port listened on to this file");
  CLI11_PARSE(app, argc, argv);

  auto logger = spdlog::stderr_color_mt("fenestrad");
  spdlog::set_default_logger(logger);
  spdlog::set_pattern("%Y-%m-%d %H:%M:%S.%e %^%l%$ %v");
  // Protobuf's own complaints (a request whose strings are not UTF-8) in the same format
  google::protobuf::SetLogHandler(
      [](google::protobuf::LogLevel, const char*, int, const std::string& message) {
        spdlog::warn("protobuf: {}", message);
      });

  // The file first, then the flags given
  fenestra::v1::DaemonConfig config;
  if (!config_file.empty()) {
    absl::StatusOr<fenestra::v1::DaemonConfig> read = fenestra::ReadConfigFile(config_file);
    if (!read.ok()) {
      spdlog::critical("{}", std::string(read.status().message()));
      return 2;
    }
    config = *read;
  }
  fenestra::v1::Limits& l = *config.mutable_limits();
  if (!listen.empty()) config.set_listen_address(listen);
  if (!data_dir.empty()) config.set_data_dir(data_dir);
  if (workers) config.set_worker_threads(workers);
  if (!backend.empty()) config.set_backend(backend);
  if (!log_level.empty()) config.set_log_level(log_level);
  if (grace) config.set_shutdown_grace_seconds(grace);
  if (max_outdoor_paths) l.set_max_outdoor_paths(max_outdoor_paths);
  if (max_indoor_paths) l.set_max_indoor_paths_per_sensor(max_indoor_paths);
  if (max_sensors) l.set_max_sensors(max_sensors);
  if (max_triangles) l.set_max_triangles(max_triangles);
  if (max_evaluations) l.set_max_evaluations(max_evaluations);
  if (max_message_bytes) l.set_max_message_bytes(max_message_bytes);
  if (max_queued_jobs) l.set_max_queued_jobs(max_queued_jobs);
  if (max_sites) l.set_max_sites(max_sites);
  absl::StatusOr<fenestra::v1::DaemonConfig> resolved = fenestra::ResolveConfig(config);
  if (!resolved.ok()) {
    spdlog::critical("{}", std::string(resolved.status().message()));
    return 2;
  }
  spdlog::set_level(spdlog::level::from_str(resolved->log_level()));

  // SIGTERM and SIGINT are taken by sigwait below, not by a handler in some thread
  sigset_t signals;
  sigemptyset(&signals);
  sigaddset(&signals, SIGTERM);
  sigaddset(&signals, SIGINT);
  pthread_sigmask(SIG_BLOCK, &signals, nullptr);
  signal(SIGPIPE, SIG_IGN);

  absl::StatusOr<std::unique_ptr<fenestra::Daemon>> daemon = fenestra::Daemon::Start(*resolved);
  if (!daemon.ok()) {
    spdlog::critical("{}", std::string(daemon.status().message()));
    return 1;
  }
  if (!port_file.empty()) {
    std::ofstream(port_file + ".tmp") << (*daemon)->port() << "\n";
    std::rename((port_file + ".tmp").c_str(), port_file.c_str());
  }
  int received = 0;
  sigwait(&signals, &received);
  spdlog::info("{} received: shutting down", received == SIGTERM ? "SIGTERM" : "SIGINT");
  (*daemon)->Shutdown();
  return 0;
}
