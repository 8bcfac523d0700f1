// A throwaway PostgreSQL server for tests and benchmarks: Debian's postgresql-15 (initdb, pg_ctl)
// on a free loopback port, its data and unix socket in a folder of its own, trust authentication,
// fsync off (nothing here must survive a power loss). initdb refuses to run as root: as root, the
// server runs as the `postgres` user (runuser) in a folder that user owns.
#pragma once

#include <libpq-fe.h>
#include <netinet/in.h>
#include <pwd.h>
#include <sys/socket.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "tests/child_process.h"

namespace fenestra {

class PostgresServer {
 public:
  // The binaries of Debian's postgresql-15 package.
  static constexpr char kBin[] = "/usr/lib/postgresql/15/bin";

  // Creates the cluster in `dir` (replaced) and starts it; ok() says whether it runs.
  explicit PostgresServer(std::string dir) : dir_(std::move(dir)) {
    namespace fs = std::filesystem;
    if (!fs::exists(std::string(kBin) + "/initdb")) {
      error_ = "no PostgreSQL 15 (deploy/debian_packages.sh installs postgresql-15)";
      return;
    }
    fs::remove_all(dir_);
    fs::create_directories(dir_);
    if (getuid() == 0) {
      const passwd* user = getpwnam("postgres");
      if (!user) {
        error_ = "running as root and there is no postgres user to run PostgreSQL as";
        return;
      }
      if (chown(dir_.c_str(), user->pw_uid, user->pw_gid) != 0) {
        error_ = "cannot give " + dir_ + " to the postgres user";
        return;
      }
    }
    port_ = FreePort();
    const CommandResult init =
        AsServerUser({std::string(kBin) + "/initdb", "-D", dir_ + "/data", "--auth=trust", "-U",
                      "postgres", "-E", "UTF8", "--no-sync", "--locale=C"});
    if (init.exit_code != 0) {
      error_ = "initdb failed: " + init.output;
      return;
    }
    if (!Start()) error_ = "pg_ctl start failed: " + Log();
  }
  ~PostgresServer() {
    if (started_) {
      AsServerUser(
          {std::string(kBin) + "/pg_ctl", "-D", dir_ + "/data", "-m", "immediate", "-w", "stop"});
    }
    std::filesystem::remove_all(dir_);
  }
  PostgresServer(const PostgresServer&) = delete;
  PostgresServer& operator=(const PostgresServer&) = delete;

  bool ok() const { return started_; }
  const std::string& error() const { return error_; }
  int port() const { return port_; }
  // The URL of `database` on this server.
  std::string Url(const std::string& database = "postgres") const {
    return "postgresql://postgres@127.0.0.1:" + std::to_string(port_) + "/" + database;
  }
  // Creates an empty database; its URL, or "" (and why in error()) when it could not.
  std::string NewDatabase(const std::string& name) {
    PGconn* conn = PQconnectdb(Url().c_str());
    const std::string sql = "CREATE DATABASE \"" + name + "\"";
    PGresult* res = PQstatus(conn) == CONNECTION_OK ? PQexec(conn, sql.c_str()) : nullptr;
    const bool created = res && PQresultStatus(res) == PGRES_COMMAND_OK;
    if (!created) error_ = "CREATE DATABASE " + name + ": " + PQerrorMessage(conn);
    PQclear(res);
    PQfinish(conn);
    return created ? Url(name) : "";
  }
  // Stops the server at once (as a crash would); true when it stopped.
  bool Stop() {
    const CommandResult stop = AsServerUser(
        {std::string(kBin) + "/pg_ctl", "-D", dir_ + "/data", "-m", "immediate", "-w", "stop"});
    started_ = started_ && stop.exit_code != 0;
    return stop.exit_code == 0;
  }
  // Starts it (again) on the same port and data; true when it runs.
  bool Start() {
    const std::string options = "-p " + std::to_string(port_) + " -k " + dir_ +
                                " -c listen_addresses=127.0.0.1 -c fsync=off -c "
                                "full_page_writes=off -c max_connections=300";
    const CommandResult start = AsServerUser({std::string(kBin) + "/pg_ctl", "-D", dir_ + "/data",
                                              "-l", dir_ + "/log", "-o", options, "-w", "start"});
    started_ = start.exit_code == 0;
    return started_;
  }
  std::string Log() const {
    std::ifstream in(dir_ + "/log");
    std::stringstream text;
    text << in.rdbuf();
    return text.str();
  }

 private:
  // A port no one listens on now (the server binds it soon after).
  static int FreePort() {
    const int fd = socket(AF_INET, SOCK_STREAM, 0);
    sockaddr_in address{};
    address.sin_family = AF_INET;
    address.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    socklen_t length = sizeof address;
    int port = 0;
    if (bind(fd, reinterpret_cast<sockaddr*>(&address), sizeof address) == 0 &&
        getsockname(fd, reinterpret_cast<sockaddr*>(&address), &length) == 0) {
      port = ntohs(address.sin_port);
    }
    close(fd);
    return port;
  }
  // Runs a PostgreSQL binary as the user that owns the cluster.
  static CommandResult AsServerUser(std::vector<std::string> argv) {
    if (getuid() == 0) argv.insert(argv.begin(), {"/usr/sbin/runuser", "-u", "postgres", "--"});
    return RunCommand(argv);
  }

  std::string dir_;
  std::string error_;
  int port_ = 0;
  bool started_ = false;
};

}  // namespace fenestra
