// Child processes for tests: a command run to its end with its output captured, and a
// fenestrad on a free loopback port with a data directory of its own.
#pragma once

#include <algorithm>
#include <fcntl.h>
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/prctl.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <fstream>
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
  if (pipe(fds) != 0) return {-1, "pipe failed"};
  const pid_t pid = fork();
  if (pid == 0) {
    dup2(fds[1], STDOUT_FILENO);
    dup2(fds[1], STDERR_FILENO);
    close(fds[0]);
    close(fds[1]);
    execve(argv[0].c_str(), child_process_internal::Pointers(argv).data(),
           child_process_internal::Pointers(env).data());
    _exit(127);
  }
  close(fds[1]);
  std::string output;
  char chunk[4096];
  for (ssize_t n; (n = read(fds[0], chunk, sizeof chunk)) > 0;) output.append(chunk, n);
  close(fds[0]);
  int status = 0;
  waitpid(pid, &status, 0);
  return {child_process_internal::ExitCode(status), output};
}

// fenestrad on 127.0.0.1 (a free port, read from its --port-file) with `data_dir`; its log
// goes to data_dir + ".log". Killed when destroyed.
class FenestradProcess {
 public:
  FenestradProcess(const std::string& fenestrad, const std::string& data_dir,
                   std::vector<std::string> flags = {})
      : log_path_(data_dir + ".log") {
    const std::string port_file = data_dir + ".port";
    std::filesystem::remove(port_file);
    std::vector<std::string> argv = {fenestrad, "--listen",    "127.0.0.1:0", "--data-dir",
                                     data_dir,  "--port-file", port_file};
    // One local user unless the test asks for tokens (loopback only, as the daemon requires)
    if (std::find(flags.begin(), flags.end(), "--auth") == flags.end()) {
      argv.insert(argv.end(), {"--auth", "none"});
    }
    argv.insert(argv.end(), flags.begin(), flags.end());
    pid_ = fork();
    if (pid_ == 0) {
      prctl(PR_SET_PDEATHSIG, SIGKILL);  // no daemon outlives a crashed test
      const int log = open(log_path_.c_str(), O_WRONLY | O_CREAT | O_APPEND, 0644);
      dup2(log, STDOUT_FILENO);
      dup2(log, STDERR_FILENO);
      execv(argv[0].c_str(), child_process_internal::Pointers(argv).data());
      _exit(127);
    }
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(20);
    while (!std::filesystem::exists(port_file) && std::chrono::steady_clock::now() < deadline) {
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
    std::ifstream port(port_file);
    int number = 0;
    if (port >> number) address_ = "127.0.0.1:" + std::to_string(number);
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
