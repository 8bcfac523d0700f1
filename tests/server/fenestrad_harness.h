// What the fenestrad tests share: a real fenestrad child process on a free localhost port
// with a temporary data directory, the fenestra client run against it, gRPC stubs, and
// tiny jobs (40000 outdoor paths, 2000 indoor paths per sensor).
#pragma once

#include <fcntl.h>
#include <gmock/gmock.h>
#include <google/protobuf/util/json_util.h>
#include <grpcpp/grpcpp.h>
#include <grpcpp/impl/codegen/client_unary_call.h>
#include <grpcpp/impl/codegen/sync_stream.h>
#include <gtest/gtest.h>
#include <poll.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <functional>
#include <optional>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "fenestra/v1/service.grpc.pb.h"
#include "tests/child_process.h"

namespace fenestra::testing_fenestrad {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

std::string ReadFile(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

// A child process; its stdout is read line by line through a pipe.
class Process {
 public:
  Process(std::vector<std::string> args, const std::string& stderr_path) {
    int fds[2];
    EXPECT_EQ(pipe2(fds, O_CLOEXEC), 0);
    const int err = OpenForChild(stderr_path, /*append=*/true);
    pid_ = Spawn(std::move(args), {{fds[1], STDOUT_FILENO}, {err, STDERR_FILENO}});
    close(err);
    close(fds[1]);
    out_ = fds[0];
  }
  ~Process() {
    if (pid_ > 0) {
      kill(pid_, SIGKILL);
      Wait();
    }
    close(out_);
  }
  // The next stdout line, or nothing at the end of the output or after `timeout_s`.
  std::optional<std::string> ReadLine(double timeout_s = 30) {
    const auto deadline = Clock::now() + std::chrono::duration<double>(timeout_s);
    while (true) {
      if (const size_t end = buffer_.find('\n'); end != std::string::npos) {
        std::string line = buffer_.substr(0, end);
        buffer_.erase(0, end + 1);
        return line;
      }
      const int left = static_cast<int>(
          std::chrono::duration_cast<std::chrono::milliseconds>(deadline - Clock::now()).count());
      if (left <= 0) return std::nullopt;
      pollfd p{out_, POLLIN, 0};
      if (poll(&p, 1, left) <= 0) return std::nullopt;
      char chunk[4096];
      const ssize_t n = read(out_, chunk, sizeof chunk);
      if (n <= 0) return std::nullopt;
      buffer_.append(chunk, n);
    }
  }
  void Signal(int signal) { kill(pid_, signal); }
  // The exit code (128 + signal when killed).
  int Wait() {
    const int code = WaitExit(pid_);
    pid_ = -1;
    return code;
  }

 private:
  pid_t pid_ = -1;
  int out_ = -1;
  std::string buffer_;
};

struct CliResult {
  int code;
  std::string out, err;
};

// A fenestrad child on 127.0.0.1 (a free port) with a data directory of its own. Its
// stubs connect with `credentials` (plaintext by default); Context() carries `token`.
class Daemon {
 public:
  Daemon(std::string data_dir, std::vector<std::string> flags,
         std::shared_ptr<grpc::ChannelCredentials> credentials = grpc::InsecureChannelCredentials())
      : data_dir_(std::move(data_dir)),
        flags_(std::move(flags)),
        credentials_(std::move(credentials)) {}
  ~Daemon() {
    if (pid_ > 0) Kill();
  }

  void Start() {
    pid_ = LaunchFenestrad(FENESTRAD, data_dir_, flags_, log_path());
    address_ = FenestradAddress(data_dir_);
    ASSERT_FALSE(address_.empty()) << "fenestrad did not start:\n" << Log();
    channel_ = grpc::CreateChannel(address_, credentials_);
    sites_ = v1::SiteService::NewStub(channel_);
    jobs_ = v1::JobService::NewStub(channel_);
  }
  // Starts a daemon that is expected to stop by itself (a failed start); its exit code.
  int RunToExit() {
    pid_ = LaunchFenestrad(FENESTRAD, data_dir_, flags_, log_path());
    return Signal(0);
  }
  // SIGTERM; the exit code.
  int Stop() { return Signal(SIGTERM); }
  int Kill() { return Signal(SIGKILL); }

  pid_t pid() const { return pid_; }
  const std::string& address() const { return address_; }
  // The token Context() sends ("" = none).
  void set_token(std::string token) { token_ = std::move(token); }
  // A context for one call, with "authorization: Bearer <token>" when a token is set. Its
  // deadline turns a daemon that stopped answering into a failed call.
  std::unique_ptr<grpc::ClientContext> Context() const {
    auto context = std::make_unique<grpc::ClientContext>();
    context->set_deadline(std::chrono::system_clock::now() + kCommandTimeout);
    if (!token_.empty()) context->AddMetadata("authorization", "Bearer " + token_);
    return context;
  }
  std::string log_path() const { return data_dir_ + ".log"; }
  std::string Log() const { return ReadFile(log_path()); }
  const std::string& data_dir() const { return data_dir_; }
  std::shared_ptr<grpc::Channel> channel() { return channel_; }
  v1::SiteService::Stub& sites() { return *sites_; }
  v1::JobService::Stub& jobs() { return *jobs_; }

  // Runs `fenestra ARGS --server <this daemon>`.
  CliResult Cli(std::vector<std::string> args) const {
    args.insert(args.begin(), FENESTRA_CLI);
    args.push_back("--server");
    args.push_back(address_);
    return RunCli(args);
  }
  static CliResult RunCli(std::vector<std::string> args) {
    const std::string base =
        testing::TempDir() + "/cli." + std::to_string(getpid()) + "." + std::to_string(counter_++);
    const int out = OpenForChild(base + ".out", /*append=*/false);
    const int err = OpenForChild(base + ".err", /*append=*/false);
    const pid_t pid =
        fenestra::Spawn(std::move(args), {{out, STDOUT_FILENO}, {err, STDERR_FILENO}});
    close(out);
    close(err);
    const int code = WaitExit(pid);
    CliResult result{code, ReadFile(base + ".out"), ReadFile(base + ".err")};
    fs::remove(base + ".out");
    fs::remove(base + ".err");
    return result;
  }
  // A Process running `fenestra ARGS --server <this daemon>`.
  std::unique_ptr<Process> Spawn(std::vector<std::string> args) const {
    args.insert(args.begin(), FENESTRA_CLI);
    args.push_back("--server");
    args.push_back(address_);
    return std::make_unique<Process>(args, data_dir_ + ".client.err");
  }

 private:
  // Sends `signal` (0: none) and waits for the exit; the exit code.
  int Signal(int signal) {
    if (pid_ <= 0) return -1;
    if (signal != 0) kill(pid_, signal);
    const int code = WaitExit(pid_);
    pid_ = -1;
    return code;
  }

  std::string data_dir_;
  std::vector<std::string> flags_;
  std::shared_ptr<grpc::ChannelCredentials> credentials_;
  std::string token_;
  pid_t pid_ = -1;
  std::string address_;
  std::shared_ptr<grpc::Channel> channel_;
  std::unique_ptr<v1::SiteService::Stub> sites_;
  std::unique_ptr<v1::JobService::Stub> jobs_;
  static inline int counter_ = 0;
};

template <typename Message>
Message FromJson(const std::string& json) {
  Message m;
  const auto status = google::protobuf::util::JsonStringToMessage(json, &m);
  EXPECT_TRUE(status.ok()) << status.message() << "\n" << json;
  return m;
}

std::string ToJson(const google::protobuf::Message& m) {
  std::string json;
  (void)google::protobuf::util::MessageToJsonString(m, &json);
  return json;
}

class FenestradTest : public testing::Test {
 protected:
  void SetUp() override {
    // Named by the test and the process, so that concurrent runs (other builds on the
    // machine) never share a folder, a data directory or a mount
    const auto* info = testing::UnitTest::GetInstance()->current_test_info();
    dir_ = testing::TempDir() + "/" + info->test_suite_name() + "_" + info->name() + "_" +
           std::to_string(getpid());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }

  void TearDown() override {
    if (!HasFailure()) fs::remove_all(dir_);
  }

  // `fenestrad user add NAME` on this test's data directory; the token it prints.
  std::string AddUser(const std::string& name, bool admin = false) {
    std::vector<std::string> args = {FENESTRAD, "user", "add", name, "--data-dir", dir_ + "/data"};
    if (admin) args.push_back("--admin");
    const CliResult r = Daemon::RunCli(args);
    EXPECT_EQ(r.code, 0) << r.err;
    std::string token = r.out;
    while (!token.empty() && token.back() == '\n') token.pop_back();
    return token;
  }

  // A daemon with auth none, so that the fenestra client drives it as the local user.
  std::unique_ptr<Daemon> StartDaemon(std::vector<std::string> flags = {}) {
    flags.insert(flags.begin(), {"--auth", "none"});
    auto daemon = std::make_unique<Daemon>(dir_ + "/data", std::move(flags));
    daemon->Start();
    return daemon;
  }

  // The city-office tilt job with tiny sampling (as tests/quick_job.h: the window in one
  // part, so that its matrices are small); the scene referenced by absolute path.
  v1::Job TinyJob(int evaluations = 6) const {
    v1::Job job = FromJson<v1::Job>(
        ReadFile(FENESTRA_SOURCE_DIR "/examples/city_office/alpha_max_quick.json"));
    job.set_scene_file(FENESTRA_SOURCE_DIR "/examples/city_office/scene.json");
    job.mutable_sampling()->set_outdoor_paths(40000);
    job.mutable_sampling()->set_indoor_paths_per_sensor(2000);
    job.mutable_sampling()->set_backend("cpu");
    job.mutable_sampling()->set_window_columns(1);
    job.mutable_sampling()->set_window_rows(1);
    job.mutable_budget()->set_max_evaluations(evaluations);
    job.mutable_budget()->set_failed_cycles_to_stop(-1);
    return job;
  }
  // A job that runs until cancelled (minutes).
  v1::Job LongJob() const { return TinyJob(5000); }

  std::string WriteJob(const std::string& name, const v1::Job& job) const {
    const std::string path = dir_ + "/" + name + ".json";
    std::ofstream(path) << ToJson(job);
    return path;
  }

  // The request `fenestra job submit` would send for `job`, built here for stub calls.
  v1::SubmitJobRequest InlineRequest(const v1::Job& job) const {
    v1::SubmitJobRequest request;
    *request.mutable_job() = job;
    v1::Scene scene = FromJson<v1::Scene>(ReadFile(job.scene_file()));
    scene.mutable_site()->clear_weather_file();
    request.mutable_job()->clear_scene_file();
    *request.mutable_job()->mutable_scene() = scene;
    request.set_weather_epw(
        ReadFile(FENESTRA_SOURCE_DIR "/examples/weather/URY_Montevideo.865800_IWEC.epw"));
    return request;
  }

  static v1::JobInfo GetJob(Daemon& d, const std::string& id) {
    v1::GetJobRequest request;
    request.set_id(id);
    v1::JobInfo info;
    EXPECT_TRUE(d.jobs().Get(d.Context().get(), request, &info).ok());
    return info;
  }
  static v1::SiteInfo GetSite(Daemon& d, const std::string& id) {
    v1::GetSiteRequest request;
    request.set_id(id);
    v1::SiteInfo info;
    EXPECT_TRUE(d.sites().Get(d.Context().get(), request, &info).ok());
    return info;
  }
  // Polls until `done(job)` or 60 s.
  static v1::JobInfo WaitJob(Daemon& d, const std::string& id,
                             const std::function<bool(const v1::JobInfo&)>& done) {
    const auto deadline = Clock::now() + std::chrono::seconds(60);
    v1::JobInfo info = GetJob(d, id);
    while (!done(info) && Clock::now() < deadline) {
      std::this_thread::sleep_for(std::chrono::milliseconds(50));
      info = GetJob(d, id);
    }
    EXPECT_TRUE(done(info)) << info.DebugString();
    return info;
  }
  static v1::SiteInfo WaitSiteReady(Daemon& d, const std::string& id) {
    const auto deadline = Clock::now() + std::chrono::seconds(60);
    v1::SiteInfo info = GetSite(d, id);
    while (info.state() == v1::SITE_STATE_COMPUTING && Clock::now() < deadline) {
      std::this_thread::sleep_for(std::chrono::milliseconds(50));
      info = GetSite(d, id);
    }
    EXPECT_EQ(info.state(), v1::SITE_STATE_READY) << info.error();
    return info;
  }
  // Polls until the daemon's log holds `text`, or 60 s.
  static void WaitLog(Daemon& d, const std::string& text) {
    const auto deadline = Clock::now() + std::chrono::seconds(60);
    while (d.Log().find(text) == std::string::npos && Clock::now() < deadline) {
      std::this_thread::sleep_for(std::chrono::milliseconds(50));
    }
    EXPECT_THAT(d.Log(), testing::HasSubstr(text));
  }
  // Whether a job has come to its end: succeeded, failed, cancelled or interrupted.
  static bool Ended(const v1::JobInfo& j) {
    return j.state() == v1::JOB_STATE_SUCCEEDED || j.state() == v1::JOB_STATE_FAILED ||
           j.state() == v1::JOB_STATE_CANCELLED || j.state() == v1::JOB_STATE_INTERRUPTED;
  }
  static bool Running(const v1::JobInfo& j) {
    return j.state() == v1::JOB_STATE_RUNNING && j.progress().evaluations() >= 2;
  }
  // Submits through the client; returns the job id.
  static std::string Submit(Daemon& d, const std::string& job_file,
                            std::vector<std::string> extra = {}) {
    std::vector<std::string> args = {"job", "submit", job_file, "--quiet"};
    args.insert(args.end(), extra.begin(), extra.end());
    const CliResult r = d.Cli(args);
    EXPECT_EQ(r.code, 0) << r.err;
    std::string id = r.out;
    while (!id.empty() && id.back() == '\n') id.pop_back();
    return id;
  }

  std::string dir_;
};

}  // namespace fenestra::testing_fenestrad
