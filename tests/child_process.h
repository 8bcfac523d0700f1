// Child processes for tests: a command run to its end with its output captured, and a
// fenestrad on a free loopback port with a data directory of its own.
#pragma once

#include <fcntl.h>
#include <gtest/gtest.h>
#include <poll.h>
#include <signal.h>
#include <sys/prctl.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <optional>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

namespace fenestra {

struct CommandResult {
  int exit_code;       // 128 + signal when killed
  std::string output;  // stdout and stderr together
};

namespace child_process_internal {

inline std::vector<char*> Pointers(std::vector<std::string>& strings) {
  std::vector<char*> pointers;
  for (std::string& s : strings) pointers.push_back(s.data());
  pointers.push_back(nullptr);
  return pointers;
}

inline int ExitCode(int status) {
  return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
}

}  // namespace child_process_internal

// Starts `argv` (argv[0] a path); its pid (exit code 127: it could not be executed).
// `redirects`: dup2(first, second) in the child, in order; no source may be an earlier
// target. `die_with_parent`: SIGKILL when the test process ends. `environment`: the whole
// environment ("NAME=value"), none for this process's. `close_from` >= 0: descriptors from
// that one on are closed.
//
// Everything the child needs is made before the fork: a test process has gRPC, database and
// sanitizer threads, one of which may hold the allocator's lock at the fork, so between fork
// and exec the child calls only async-signal-safe functions.
inline pid_t Spawn(std::vector<std::string> argv, const std::vector<std::pair<int, int>>& redirects,
                   bool die_with_parent = false,
                   std::optional<std::vector<std::string>> environment = std::nullopt,
                   int close_from = -1) {
  std::vector<char*> args = child_process_internal::Pointers(argv);
  std::vector<char*> env;
  if (environment) env = child_process_internal::Pointers(*environment);
  const pid_t pid = fork();
  if (pid == 0) {
    if (die_with_parent) prctl(PR_SET_PDEATHSIG, SIGKILL);
    for (const auto& [from, to] : redirects) dup2(from, to);
    if (close_from >= 0) close_range(close_from, ~0U, 0);
    if (environment) {
      execve(args[0], args.data(), env.data());
    } else {
      execv(args[0], args.data());
    }
    _exit(127);
  }
  return pid;
}

// A file opened for a child's output (appended or truncated), closed on exec so that only
// the dup2 copies reach the child.
inline int OpenForChild(const std::string& path, bool append) {
  return open(path.c_str(), O_WRONLY | O_CREAT | O_CLOEXEC | (append ? O_APPEND : O_TRUNC), 0644);
}

// How long a command may run before it counts as hung (the sanitizer build is slow).
inline constexpr std::chrono::seconds kCommandTimeout{600};

// Waits for `pid` to end, killing it after `timeout`; its exit code (128 + signal when
// killed, so a child that hung reads 137), or -1 where there is no such child to wait for.
inline int WaitExit(pid_t pid, std::chrono::seconds timeout = kCommandTimeout) {
  if (pid <= 0) return -1;
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  int status = 0;
  while (true) {
    const pid_t waited = waitpid(pid, &status, WNOHANG);
    if (waited == pid) return child_process_internal::ExitCode(status);
    if (waited < 0 && errno != EINTR) return -1;
    if (std::chrono::steady_clock::now() > deadline) {
      kill(pid, SIGKILL);
      pid_t killed;
      while ((killed = waitpid(pid, &status, 0)) < 0 && errno == EINTR) {
      }
      return killed == pid ? child_process_internal::ExitCode(status) : -1;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
}

// Runs `argv` (argv[0] a path) with this process's environment plus `environment`
// ("NAME=value"; a name given there replaces the inherited one) and waits for it.
inline CommandResult RunCommand(std::vector<std::string> argv,
                                const std::vector<std::string>& environment = {}) {
  std::vector<std::string> env;
  for (char** e = environ; *e != nullptr; ++e) {
    const std::string entry = *e;
    const std::string name = entry.substr(0, entry.find('='));
    bool replaced = false;
    for (const std::string& given : environment) replaced |= given.rfind(name + "=", 0) == 0;
    if (!replaced) env.push_back(entry);
  }
  env.insert(env.end(), environment.begin(), environment.end());
  int fds[2];
  if (pipe2(fds, O_CLOEXEC) != 0) return {-1, "pipe failed"};
  const pid_t pid = Spawn(std::move(argv), {{fds[1], STDOUT_FILENO}, {fds[1], STDERR_FILENO}},
                          /*die_with_parent=*/false, std::move(env));
  close(fds[1]);
  // Read until the output ends or the time is up; a child that hangs is killed by WaitExit
  const auto deadline = std::chrono::steady_clock::now() + kCommandTimeout;
  std::string output;
  char chunk[4096];
  for (pollfd p{fds[0], POLLIN, 0};;) {
    const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(
        deadline - std::chrono::steady_clock::now());
    if (left.count() <= 0) break;
    const int ready = poll(&p, 1, static_cast<int>(left.count()));
    if (ready < 0 && errno == EINTR) continue;
    if (ready <= 0) break;
    const ssize_t n = read(fds[0], chunk, sizeof chunk);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) break;
    output.append(chunk, n);
  }
  close(fds[0]);
  const auto left =
      std::chrono::duration_cast<std::chrono::seconds>(deadline - std::chrono::steady_clock::now());
  return {WaitExit(pid, std::max(left, std::chrono::seconds(1))), output};
}

// Starts fenestrad (path `fenestrad`) on 127.0.0.1, a free port it writes to
// data_dir + ".port", with `data_dir` and `flags`, its output appended to `log_path`; the
// daemon is killed when the test process ends (none outlives a crashed test). Its pid.
inline pid_t LaunchFenestrad(const std::string& fenestrad, const std::string& data_dir,
                             const std::vector<std::string>& flags, const std::string& log_path) {
  const std::string port_file = data_dir + ".port";
  std::filesystem::remove(port_file);
  std::vector<std::string> argv = {fenestrad, "--listen",    "127.0.0.1:0", "--data-dir",
                                   data_dir,  "--port-file", port_file};
  argv.insert(argv.end(), flags.begin(), flags.end());
  const int log = OpenForChild(log_path, /*append=*/true);
  const pid_t pid = Spawn(std::move(argv), {{log, STDOUT_FILENO}, {log, STDERR_FILENO}},
                          /*die_with_parent=*/true);
  close(log);
  return pid;
}

// "127.0.0.1:PORT" once the daemon LaunchFenestrad started on `data_dir` has written its
// port (waiting up to 20 s); empty when it has not.
inline std::string FenestradAddress(const std::string& data_dir) {
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(20);
  do {
    std::ifstream port(data_dir + ".port");
    if (int number = 0; port >> number) return "127.0.0.1:" + std::to_string(number);
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  } while (std::chrono::steady_clock::now() < deadline);
  return "";
}

// fenestrad on 127.0.0.1 (LaunchFenestrad) with `data_dir`, one local user unless `flags`
// ask for tokens (loopback only, as the daemon requires); its log goes to data_dir + ".log".
// Killed when destroyed.
class FenestradProcess {
 public:
  FenestradProcess(const std::string& fenestrad, const std::string& data_dir,
                   std::vector<std::string> flags = {})
      : log_path_(data_dir + ".log") {
    if (std::find(flags.begin(), flags.end(), "--auth") == flags.end()) {
      flags.insert(flags.begin(), {"--auth", "none"});
    }
    pid_ = LaunchFenestrad(fenestrad, data_dir, flags, log_path_);
    address_ = FenestradAddress(data_dir);
  }
  ~FenestradProcess() {
    kill(pid_, SIGKILL);
    waitpid(pid_, nullptr, 0);
  }
  FenestradProcess(const FenestradProcess&) = delete;
  FenestradProcess& operator=(const FenestradProcess&) = delete;

  // "127.0.0.1:PORT"; empty when the daemon did not start (see Log()).
  const std::string& address() const { return address_; }
  std::string Log() const {
    std::ifstream in(log_path_);
    std::stringstream text;
    text << in.rdbuf();
    return text.str();
  }

 private:
  std::string log_path_;
  pid_t pid_ = -1;
  std::string address_;
};

}  // namespace fenestra
