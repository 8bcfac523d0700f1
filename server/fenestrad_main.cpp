// fenestrad: the Fenestra daemon. Serves SiteService and JobService (gRPC), runs jobs on
// worker threads, caches outdoor matrices and keeps jobs in data_dir/fenestra.db, or in a
// PostgreSQL database shared by any number of replicas (--store).
// Configuration: a JSON file (fenestra.v1.DaemonConfig, --config) and flags, which win.
// `fenestrad user add|list|revoke` manage the users of a daemon with token auth;
// `fenestrad migrate` copies a data directory into a PostgreSQL store.
// `fenestrad --check-config` checks a configuration without starting.
#include <google/protobuf/stubs/logging.h>
#include <google/protobuf/util/json_util.h>
#include <signal.h>
#include <spdlog/sinks/stdout_color_sinks.h>
#include <spdlog/spdlog.h>

#include <CLI/CLI.hpp>
#include <filesystem>
#include <fstream>
#include <iostream>

#include "absl/time/clock.h"
#include "absl/time/time.h"
#include "server/config.h"
#include "server/daemon.h"
#include "server/heavy_requests.h"
#include "server/log_safe.h"
#include "server/store/migrate.h"
#include "server/store/postgres_database.h"
#include "server/store/store.h"
#include "server/users.h"

namespace {

namespace fs = std::filesystem;

// The settings given as flags; 0, empty or false = not given.
struct Flags {
  std::string config_file, port_file;
  std::string listen, health_listen, http_listen, data_dir, backend, gpus, log_level, auth, store;
  std::string tls_cert, tls_key, tls_client_ca;
  bool allow_plaintext = false, check_config = false;
  int workers = 0, max_sensors = 0, max_evaluations = 0, max_message_bytes = 0, max_queued_jobs = 0,
      max_sites = 0, max_queued_jobs_per_user = 0, max_sites_per_user = 0, max_heavy_requests = 0,
      max_candidates_at_once = 0, max_http_requests_per_minute = 0;
  int64_t max_outdoor_paths = 0, max_indoor_paths = 0, max_triangles = 0,
          max_upload_bytes_per_user = 0, max_data_dir_bytes = 0, outdoor_memory_bytes = 0;
  double grace = 0, lease_seconds = 0;
};

void AddDaemonFlags(CLI::App& app, Flags& f) {
  app.add_option("--config", f.config_file, "JSON configuration file (fenestra.v1.DaemonConfig)");
  app.add_option("--listen", f.listen, "host:port to listen on [localhost:50051]");
  app.add_option("--health-listen", f.health_listen,
                 "host:port of a plaintext port serving only gRPC health checks, for probes "
                 "(services liveness, fenestrad and \"\") [none]");
  app.add_option("--http", f.http_listen,
                 "host:port of the web dashboard (HTTPS with --tls-cert/--tls-key; plain HTTP "
                 "only on loopback or with --allow-plaintext) [none]");
  app.add_option("--max-http-requests-per-minute", f.max_http_requests_per_minute,
                 "limit: dashboard requests per client address and minute [1200]");
  app.add_option("--data-dir", f.data_dir,
                 "job store, users, outdoor cache and weather files [fenestra-data]");
  app.add_option("--store", f.store,
                 "PostgreSQL URL postgresql://user@host:port/db shared by any number of "
                 "replicas [SQLite in --data-dir]");
  app.add_option("--lease-seconds", f.lease_seconds,
                 "how long a replica's claim on running work lasts unrenewed; another replica "
                 "takes the work over after it [10]");
  app.add_option("--outdoor-memory-bytes", f.outdoor_memory_bytes,
                 "outdoor matrices kept in memory after use [1 GiB]");
  app.add_option(
      "--workers", f.workers,
      "jobs and site computations run at once [one per GPU, at least 1; 1 with --backend cpu]");
  app.add_option("--backend", f.backend, "tracer for jobs that name none: cpu, cuda, auto [auto]");
  app.add_option("--gpus", f.gpus,
                 "GPUs the workers share out (one each by default): all, or device indices "
                 "such as 0,2 [all]");
  app.add_option("--tls-cert", f.tls_cert, "TLS certificate chain (PEM) [none: plaintext]");
  app.add_option("--tls-key", f.tls_key, "TLS private key (PEM) of --tls-cert");
  app.add_option("--tls-client-ca", f.tls_client_ca,
                 "CA certificates (PEM) that client certificates must chain to; clients "
                 "without one are refused (mutual TLS)");
  app.add_flag("--allow-plaintext", f.allow_plaintext,
               "serve plaintext on a non-loopback address (behind a TLS-terminating proxy)");
  app.add_option("--auth", f.auth,
                 "token: every call carries a user's token (fenestrad user add); none: "
                 "every caller is the local administrator, loopback only [token]");
  app.add_option("--max-outdoor-paths", f.max_outdoor_paths, "limit: outdoor paths [1e9]");
  app.add_option("--max-indoor-paths", f.max_indoor_paths, "limit: indoor paths per sensor [1e7]");
  app.add_option("--max-sensors", f.max_sensors, "limit: sensors per scene [10000]");
  app.add_option("--max-triangles", f.max_triangles, "limit: triangles per scene [2e6]");
  app.add_option("--max-evaluations", f.max_evaluations, "limit: evaluations per job [10000]");
  app.add_option("--max-message-bytes", f.max_message_bytes, "limit: request size [64 MiB]");
  app.add_option("--max-queued-jobs", f.max_queued_jobs, "limit: jobs waiting [64]");
  app.add_option("--max-sites", f.max_sites, "limit: registered sites [1000]");
  app.add_option("--max-queued-jobs-per-user", f.max_queued_jobs_per_user,
                 "limit: jobs waiting per user [8]");
  app.add_option("--max-sites-per-user", f.max_sites_per_user, "limit: sites per user [100]");
  app.add_option("--max-upload-bytes-per-user", f.max_upload_bytes_per_user,
                 "limit: weather files a user's sites and queued or running jobs hold [256 MiB]");
  app.add_option("--max-data-dir-bytes", f.max_data_dir_bytes,
                 "limit: bytes under the data directory [10 GiB]");
  app.add_option("--max-heavy-requests", f.max_heavy_requests,
                 "limit: requests of 1 MiB or more (registrations, submissions, site "
                 "scenes sent back) processed at once [2]");
  app.add_option("--max-candidates-at-once", f.max_candidates_at_once,
                 "limit: designs one job may ask to evaluate at once, each with its own copy "
                 "of the job's indoor records [4]");
  app.add_option("--shutdown-grace", f.grace,
                 "seconds running jobs may go on after SIGTERM before they are interrupted [10]");
  app.add_option("--log-level", f.log_level, "trace, debug, info, warn, error [info]");
  app.add_option("--port-file", f.port_file,
                 "write the port listened on to this file (then, each on a line of its own, "
                 "the health port with --health-listen and the dashboard's with --http)");
  app.add_flag("--check-config", f.check_config,
               "check the configuration (--config and the flags given), print it with its "
               "defaults as JSON and exit (0: valid, 2: not) without opening or serving "
               "anything");
}

// The flags given, on top of `config`.
void ApplyFlags(const Flags& f, fenestra::v1::DaemonConfig& config) {
  fenestra::v1::Limits& l = *config.mutable_limits();
  if (!f.listen.empty()) config.set_listen_address(f.listen);
  if (!f.health_listen.empty()) config.set_health_listen(f.health_listen);
  if (!f.http_listen.empty()) config.set_http_listen(f.http_listen);
  if (f.max_http_requests_per_minute) {
    l.set_max_http_requests_per_minute(f.max_http_requests_per_minute);
  }
  if (!f.data_dir.empty()) config.set_data_dir(f.data_dir);
  if (!f.store.empty()) config.set_store(f.store);
  if (f.lease_seconds) config.set_lease_seconds(f.lease_seconds);
  if (f.outdoor_memory_bytes) config.set_outdoor_memory_bytes(f.outdoor_memory_bytes);
  if (f.workers) config.set_worker_threads(f.workers);
  if (!f.backend.empty()) config.set_backend(f.backend);
  if (!f.gpus.empty()) config.set_gpus(f.gpus);
  if (!f.log_level.empty()) config.set_log_level(f.log_level);
  if (f.grace) config.set_shutdown_grace_seconds(f.grace);
  if (!f.tls_cert.empty()) config.set_tls_cert_file(f.tls_cert);
  if (!f.tls_key.empty()) config.set_tls_key_file(f.tls_key);
  if (!f.tls_client_ca.empty()) config.set_tls_client_ca_file(f.tls_client_ca);
  if (f.allow_plaintext) config.set_allow_plaintext(true);
  if (!f.auth.empty()) config.set_auth(f.auth);
  if (f.max_outdoor_paths) l.set_max_outdoor_paths(f.max_outdoor_paths);
  if (f.max_indoor_paths) l.set_max_indoor_paths_per_sensor(f.max_indoor_paths);
  if (f.max_sensors) l.set_max_sensors(f.max_sensors);
  if (f.max_triangles) l.set_max_triangles(f.max_triangles);
  if (f.max_evaluations) l.set_max_evaluations(f.max_evaluations);
  if (f.max_message_bytes) l.set_max_message_bytes(f.max_message_bytes);
  if (f.max_queued_jobs) l.set_max_queued_jobs(f.max_queued_jobs);
  if (f.max_sites) l.set_max_sites(f.max_sites);
  if (f.max_queued_jobs_per_user) l.set_max_queued_jobs_per_user(f.max_queued_jobs_per_user);
  if (f.max_sites_per_user) l.set_max_sites_per_user(f.max_sites_per_user);
  if (f.max_upload_bytes_per_user) l.set_max_upload_bytes_per_user(f.max_upload_bytes_per_user);
  if (f.max_data_dir_bytes) l.set_max_data_dir_bytes(f.max_data_dir_bytes);
  if (f.max_heavy_requests) l.set_max_concurrent_heavy_requests(f.max_heavy_requests);
  if (f.max_candidates_at_once) l.set_max_candidates_at_once(f.max_candidates_at_once);
}

// `fenestrad user ...`: what was asked, on the store in `data_dir` or `store`.
struct UserCommand {
  std::string name, data_dir, store;
  bool admin = false;
  CLI::App *add = nullptr, *list = nullptr, *revoke = nullptr;
};

void AddUserCommands(CLI::App& app, UserCommand& c) {
  CLI::App* user =
      app.add_subcommand("user",
                         "manage the users of a daemon with token auth (kept in DIR/fenestra.db "
                         "or the --store database; a running daemon sees changes at once)");
  user->require_subcommand(1);
  c.add = user->add_subcommand("add", "add a user; prints its new token, once, on stdout");
  c.add->add_option("name", c.name, "user name: letters, digits, '.', '_', '-'")->required();
  c.add->add_flag("--admin", c.admin, "the user sees and acts on every user's jobs and sites");
  c.list = user->add_subcommand("list", "list the users (never their tokens)");
  c.revoke = user->add_subcommand("revoke", "revoke a user's token; its calls fail from now on");
  c.revoke->add_option("name", c.name, "user name")->required();
  for (CLI::App* command : {c.add, c.list, c.revoke}) {
    CLI::Option* dir = command->add_option("--data-dir", c.data_dir, "the daemon's data directory");
    CLI::Option* store =
        command->add_option("--store", c.store, "the replicas' PostgreSQL store (a URL)");
    dir->excludes(store);
  }
}

// `fenestrad migrate`: what was asked.
struct MigrateCommand {
  std::string from, to;
  bool overwrite = false;
  CLI::App* command = nullptr;
};

void AddMigrateCommand(CLI::App& app, MigrateCommand& c) {
  c.command = app.add_subcommand(
      "migrate",
      "copy a data directory (users, jobs, sites, weather files, outdoor matrices) into a "
      "PostgreSQL store for replicas; no fenestrad may run on the directory meanwhile");
  c.command->add_option("--from", c.from, "sqlite:DIR, the data directory")->required();
  c.command->add_option("--to", c.to, "postgresql://user@host:port/database")->required();
  c.command->add_flag("--overwrite", c.overwrite,
                      "replace what the target store holds (by default it must be empty)");
}

int RunMigrateCommand(const MigrateCommand& c) {
  if (!c.from.starts_with("sqlite:")) {
    std::cerr << "fenestrad: --from must be sqlite:DIR (a fenestrad data directory)\n";
    return 2;
  }
  const absl::Status migrated =
      fenestra::MigrateDataDir(c.from.substr(7), c.to, c.overwrite,
                               [](const std::string& line) { std::cerr << line << "\n"; });
  if (!migrated.ok()) {
    std::cerr << "fenestrad: " << migrated.message() << "\n";
    return 1;
  }
  std::cerr << "copied " << c.from << " into " << fenestra::RedactPostgresUrl(c.to)
            << "; start the replicas with --store on it\n";
  return 0;
}

std::string FormatUnixMs(int64_t unix_ms) {
  return absl::FormatTime("%Y-%m-%d %H:%M:%S UTC", absl::FromUnixMillis(unix_ms),
                          absl::UTCTimeZone());
}

int RunUserCommand(const UserCommand& c) {
  if (c.store.empty() == c.data_dir.empty()) {
    std::cerr << "fenestrad: give the daemon's --data-dir, or its --store\n";
    return 2;
  }
  absl::StatusOr<std::unique_ptr<fenestra::Store>> store = absl::InternalError("not opened");
  if (!c.store.empty()) {
    store = fenestra::OpenStoreUrl(c.store, 1);
  } else {
    const fs::path db = fs::path(c.data_dir) / "fenestra.db";
    if (!*c.add && !fs::exists(db)) {
      std::cerr << "fenestrad: no " << db.string() << " (is --data-dir the daemon's?)\n";
      return 1;
    }
    std::error_code error;
    fs::create_directories(c.data_dir, error);
    store = fenestra::OpenStoreUrl("sqlite:" + c.data_dir, 1);
  }
  if (!store.ok()) {
    std::cerr << "fenestrad: " << store.status().message() << "\n";
    return 1;
  }
  if (*c.add) {
    absl::StatusOr<std::string> token = fenestra::AddUser(**store, c.name, c.admin);
    if (!token.ok()) {
      std::cerr << "fenestrad: " << token.status().message() << "\n";
      return 1;
    }
    std::cerr << "user " << c.name << (c.admin ? " (administrator)" : "")
              << " added; its token follows, shown this once (the daemon keeps only its "
                 "SHA-256):\n";
    std::cout << *token << std::endl;
    return 0;
  }
  if (*c.revoke) {
    const absl::Status revoked = (*store)->RevokeUser(c.name, absl::ToUnixMillis(absl::Now()));
    if (!revoked.ok()) {
      std::cerr << "fenestrad: " << revoked.message() << "\n";
      return 1;
    }
    std::cerr << "user " << c.name << ": token revoked\n";
    return 0;
  }
  absl::StatusOr<std::vector<fenestra::UserRecord>> users = (*store)->LoadUsers();
  if (!users.ok()) {
    std::cerr << "fenestrad: " << users.status().message() << "\n";
    return 1;
  }
  std::printf("%-24s %-6s %-24s %s\n", "NAME", "ADMIN", "CREATED", "REVOKED");
  for (const fenestra::UserRecord& u : *users) {
    std::printf("%-24s %-6s %-24s %s\n", u.name.c_str(), u.admin ? "yes" : "no",
                FormatUnixMs(u.created_unix_ms).c_str(),
                u.revoked_unix_ms ? FormatUnixMs(u.revoked_unix_ms).c_str() : "-");
  }
  return 0;
}

// Runs the daemon until SIGTERM or SIGINT.
int Serve(const fenestra::v1::DaemonConfig& config, const std::string& port_file) {
  // SIGTERM and SIGINT are taken by sigwait below, not by a handler in some thread
  sigset_t signals;
  sigemptyset(&signals);
  sigaddset(&signals, SIGTERM);
  sigaddset(&signals, SIGINT);
  pthread_sigmask(SIG_BLOCK, &signals, nullptr);
  signal(SIGPIPE, SIG_IGN);

  absl::StatusOr<std::unique_ptr<fenestra::Daemon>> daemon = fenestra::Daemon::Start(config);
  if (!daemon.ok()) {
    spdlog::critical("{}", std::string(daemon.status().message()));
    return 1;
  }
  if (!port_file.empty()) {
    std::ofstream ports(port_file + ".tmp");
    ports << (*daemon)->port() << "\n";
    if ((*daemon)->health_port() != 0) ports << (*daemon)->health_port() << "\n";
    if ((*daemon)->http_port() != 0) ports << (*daemon)->http_port() << "\n";
    ports.close();
    std::rename((port_file + ".tmp").c_str(), port_file.c_str());
  }
  int received = 0;
  sigwait(&signals, &received);
  spdlog::info("{} received: shutting down", received == SIGTERM ? "SIGTERM" : "SIGINT");
  (*daemon)->Shutdown();
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  fenestra::ReleaseLargeBlocksWhenFreed();
  CLI::App app{"fenestrad: the Fenestra daylight optimization service"};
  Flags flags;
  UserCommand user;
  MigrateCommand migrate;
  AddDaemonFlags(app, flags);
  AddUserCommands(app, user);
  AddMigrateCommand(app, migrate);
  CLI11_PARSE(app, argc, argv);
  // Logs go to stderr (stdout carries only what a command prints: a new token)
  auto logger = spdlog::stderr_color_mt("fenestrad");
  spdlog::set_default_logger(logger);
  spdlog::set_pattern("%Y-%m-%d %H:%M:%S.%e %^%l%$ %v");
  if (*user.add || *user.list || *user.revoke) {
    spdlog::set_level(spdlog::level::warn);
    return RunUserCommand(user);
  }
  if (*migrate.command) return RunMigrateCommand(migrate);

  // Protobuf's own complaints (a request whose strings are not UTF-8) in the same format
  google::protobuf::SetLogHandler(
      [](google::protobuf::LogLevel, const char*, int, const std::string& message) {
        spdlog::warn("protobuf: {}", fenestra::LogSafe(message));
      });

  // The file first, then the flags given
  fenestra::v1::DaemonConfig config;
  if (!flags.config_file.empty()) {
    absl::StatusOr<fenestra::v1::DaemonConfig> read = fenestra::ReadConfigFile(flags.config_file);
    if (!read.ok()) {
      spdlog::critical("{}", std::string(read.status().message()));
      return 2;
    }
    config = *read;
  }
  ApplyFlags(flags, config);
  absl::StatusOr<fenestra::v1::DaemonConfig> resolved = fenestra::ResolveConfig(config);
  if (!resolved.ok()) {
    spdlog::critical("{}", std::string(resolved.status().message()));
    return 2;
  }
  if (flags.check_config) {
    std::string json;
    google::protobuf::util::JsonPrintOptions options;
    options.add_whitespace = true;
    options.always_print_primitive_fields = true;
    (void)google::protobuf::util::MessageToJsonString(*resolved, &json, options);
    std::cout << json;
    return 0;
  }
  spdlog::set_level(spdlog::level::from_str(resolved->log_level()));
  return Serve(*resolved, flags.port_file);
}
