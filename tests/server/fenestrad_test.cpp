// fenestrad end to end: a real daemon on a free localhost port with a temporary data
// directory, driven through the fenestra client (and, for status codes, a gRPC stub).
// Jobs use tiny sampling (40000 outdoor paths, 2000 indoor paths per sensor).
#include <arpa/inet.h>
#include <fcntl.h>
#include <gmock/gmock.h>
#include <google/protobuf/util/json_util.h>
#include <grpcpp/grpcpp.h>
#include <grpcpp/impl/codegen/client_unary_call.h>
#include <grpcpp/impl/codegen/sync_stream.h>
#include <gtest/gtest.h>
#include <netinet/in.h>
#include <poll.h>
#include <signal.h>
#include <sys/prctl.h>
#include <sys/socket.h>
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

namespace fenestra {
namespace {

namespace fs = std::filesystem;
using ::testing::HasSubstr;
using Clock = std::chrono::steady_clock;

std::string ReadFile(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

std::vector<char*> Argv(std::vector<std::string>& args) {
  std::vector<char*> argv;
  for (std::string& a : args) argv.push_back(a.data());
  argv.push_back(nullptr);
  return argv;
}

// A child process; its stdout is read line by line through a pipe.
class Process {
 public:
  Process(std::vector<std::string> args, const std::string& stderr_path) {
    int fds[2];
    EXPECT_EQ(pipe(fds), 0);
    pid_ = fork();
    if (pid_ == 0) {
      dup2(fds[1], STDOUT_FILENO);
      const int err = open(stderr_path.c_str(), O_WRONLY | O_CREAT | O_APPEND, 0644);
      dup2(err, STDERR_FILENO);
      close(fds[0]);
      std::vector<char*> argv = Argv(args);
      execv(argv[0], argv.data());
      _exit(127);
    }
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
    int status = 0;
    waitpid(pid_, &status, 0);
    pid_ = -1;
    return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
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

// A fenestrad child on 127.0.0.1 (a free port) with a data directory of its own.
class Daemon {
 public:
  Daemon(std::string data_dir, std::vector<std::string> flags)
      : data_dir_(std::move(data_dir)), flags_(std::move(flags)) {}
  ~Daemon() {
    if (pid_ > 0) Kill();
  }

  void Start() {
    const std::string port_file = data_dir_ + ".port";
    fs::remove(port_file);
    std::vector<std::string> args = {FENESTRAD, "--listen",    "127.0.0.1:0", "--data-dir",
                                     data_dir_, "--port-file", port_file};
    args.insert(args.end(), flags_.begin(), flags_.end());
    pid_ = fork();
    if (pid_ == 0) {
      prctl(PR_SET_PDEATHSIG, SIGKILL);  // no daemon outlives a crashed test
      const int log = open(log_path().c_str(), O_WRONLY | O_CREAT | O_APPEND, 0644);
      dup2(log, STDERR_FILENO);
      dup2(log, STDOUT_FILENO);
      std::vector<char*> argv = Argv(args);
      execv(argv[0], argv.data());
      _exit(127);
    }
    const auto deadline = Clock::now() + std::chrono::seconds(20);
    while (!fs::exists(port_file) && Clock::now() < deadline) {
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
    ASSERT_TRUE(fs::exists(port_file)) << "fenestrad did not start:\n" << Log();
    address_ = "127.0.0.1:" + std::to_string(std::stoi(ReadFile(port_file)));
    channel_ = grpc::CreateChannel(address_, grpc::InsecureChannelCredentials());
    sites_ = v1::SiteService::NewStub(channel_);
    jobs_ = v1::JobService::NewStub(channel_);
  }
  // SIGTERM; the exit code.
  int Stop() { return Signal(SIGTERM); }
  int Kill() { return Signal(SIGKILL); }

  const std::string& address() const { return address_; }
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
    const pid_t pid = fork();
    if (pid == 0) {
      const int out = open((base + ".out").c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
      const int err = open((base + ".err").c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
      dup2(out, STDOUT_FILENO);
      dup2(err, STDERR_FILENO);
      std::vector<char*> argv = Argv(args);
      execv(argv[0], argv.data());
      _exit(127);
    }
    int status = 0;
    waitpid(pid, &status, 0);
    CliResult result{WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status),
                     ReadFile(base + ".out"), ReadFile(base + ".err")};
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
  int Signal(int signal) {
    if (pid_ <= 0) return -1;
    kill(pid_, signal);
    int status = 0;
    waitpid(pid_, &status, 0);
    pid_ = -1;
    return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
  }

  std::string data_dir_;
  std::vector<std::string> flags_;
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
    const auto* info = testing::UnitTest::GetInstance()->current_test_info();
    dir_ = testing::TempDir() + "/fenestrad_test_" + info->name();
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }

  void TearDown() override {
    if (!HasFailure()) fs::remove_all(dir_);
  }

  std::unique_ptr<Daemon> StartDaemon(std::vector<std::string> flags = {}) {
    auto daemon = std::make_unique<Daemon>(dir_ + "/data", std::move(flags));
    daemon->Start();
    return daemon;
  }

  // The city-office tilt job with tiny sampling; `edit` changes it further. Returns its
  // path (a job file next to nothing: the scene is referenced by absolute path).
  v1::Job TinyJob(int evaluations = 6) const {
    v1::Job job = FromJson<v1::Job>(
        ReadFile(FENESTRA_SOURCE_DIR "/examples/city_office/alpha_max_quick.json"));
    job.set_scene_file(FENESTRA_SOURCE_DIR "/examples/city_office/scene.json");
    job.mutable_sampling()->set_outdoor_paths(40000);
    job.mutable_sampling()->set_indoor_paths_per_sensor(2000);
    job.mutable_sampling()->set_backend("cpu");
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
    grpc::ClientContext context;
    v1::GetJobRequest request;
    request.set_id(id);
    v1::JobInfo info;
    EXPECT_TRUE(d.jobs().Get(&context, request, &info).ok());
    return info;
  }
  static v1::SiteInfo GetSite(Daemon& d, const std::string& id) {
    grpc::ClientContext context;
    v1::GetSiteRequest request;
    request.set_id(id);
    v1::SiteInfo info;
    EXPECT_TRUE(d.sites().Get(&context, request, &info).ok());
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

TEST_F(FenestradTest, SiteMatrixIsComputedOnceReusedByJobsAndLoadedAfterRestart) {
  auto d = StartDaemon();
  const std::string job_file = WriteJob("tiny", TinyJob());
  CliResult r = d->Cli({"site", "add", "--job", job_file, "--wait", "--json"});
  ASSERT_EQ(r.code, 0) << r.err;
  const v1::SiteInfo site = FromJson<v1::SiteInfo>(r.out);
  EXPECT_EQ(site.state(), v1::SITE_STATE_READY);
  EXPECT_EQ(site.computations(), 1);
  EXPECT_GT(site.compute_seconds(), 0);

  // Two jobs on the site: neither traces the outdoor matrix again
  for (int k = 1; k <= 2; ++k) {
    r = d->Cli({"job", "submit", job_file, "--site", site.id(), "--watch"});
    ASSERT_EQ(r.code, 0) << r.err;
    EXPECT_THAT(r.out, HasSubstr("[6/6] best"));
    EXPECT_THAT(r.out, HasSubstr("best design: alpha="));
    const v1::JobInfo job = GetJob(*d, "job-" + std::to_string(k));
    EXPECT_EQ(job.state(), v1::JOB_STATE_SUCCEEDED);
    EXPECT_TRUE(job.outdoor_reused());
    EXPECT_EQ(job.result().timings().outdoor_seconds(), 0);
    EXPECT_THAT(d->Cli({"job", "show", job.id()}).out,
                HasSubstr("outdoor matrix: reused from the cache"));
    std::cout << "outdoor matrix: traced in " << site.compute_seconds() << " s, reused by job-" << k
              << " in " << job.outdoor_seconds() << " s\n";
  }
  EXPECT_EQ(GetSite(*d, site.id()).jobs_reused(), 2);
  r = d->Cli({"job", "result", "job-2"});
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_THAT(r.out, HasSubstr("best design: alpha="));
  EXPECT_THAT(r.out, HasSubstr("succeeded"));
  r = d->Cli({"job", "list"});
  EXPECT_THAT(r.out, HasSubstr("job-2      succeeded"));
  r = d->Cli({"site", "list"});
  EXPECT_THAT(r.out, HasSubstr("site-1     ready"));

  // A restarted daemon loads the matrix from disk instead of tracing it
  EXPECT_EQ(d->Stop(), 0);
  d->Start();
  r = d->Cli({"site", "show", site.id(), "--json"});
  ASSERT_EQ(r.code, 0) << r.err;
  const v1::SiteInfo reloaded = FromJson<v1::SiteInfo>(r.out);
  EXPECT_EQ(reloaded.state(), v1::SITE_STATE_READY);
  EXPECT_TRUE(reloaded.loaded_from_disk());
  EXPECT_EQ(reloaded.computations(), 1);
  EXPECT_THAT(d->Log(), HasSubstr("1 matrices loaded"));
  const std::string id = Submit(*d, job_file, {"--site", site.id()});
  const v1::JobInfo job =
      WaitJob(*d, id, [](const v1::JobInfo& j) { return j.state() == v1::JOB_STATE_SUCCEEDED; });
  EXPECT_TRUE(job.outdoor_reused());
  EXPECT_EQ(GetSite(*d, site.id()).jobs_reused(), 3);
}

TEST_F(FenestradTest, TwoJobsAtOnceWatchReconnectCancelAndResult) {
  auto d = StartDaemon({"--workers", "2"});
  const std::string watched = Submit(*d, WriteJob("watched", TinyJob(60)));
  const std::string other = Submit(*d, WriteJob("long", LongJob()));
  WaitJob(*d, other, Running);

  // Watch, disconnect after the first progress event
  {
    auto watch = d->Spawn({"job", "watch", watched, "--json"});
    std::optional<std::string> line = watch->ReadLine();
    ASSERT_TRUE(line);
    EXPECT_TRUE(FromJson<v1::JobEvent>(*line).has_snapshot());
    do {
      line = watch->ReadLine();
      ASSERT_TRUE(line);
    } while (!FromJson<v1::JobEvent>(*line).has_progress());
    watch->Signal(SIGKILL);
  }
  // Reconnect: a snapshot with the progress so far comes first, then live events
  auto watch = d->Spawn({"job", "watch", watched, "--json"});
  std::optional<std::string> line = watch->ReadLine();
  ASSERT_TRUE(line);
  const v1::JobEvent snapshot = FromJson<v1::JobEvent>(*line);
  ASSERT_TRUE(snapshot.has_snapshot()) << *line;
  EXPECT_EQ(snapshot.snapshot().state(), v1::JOB_STATE_RUNNING);
  EXPECT_GE(snapshot.snapshot().progress().evaluations(), 1);
  EXPECT_GT(snapshot.sequence(), 0);
  line = watch->ReadLine();
  ASSERT_TRUE(line);
  EXPECT_GT(FromJson<v1::JobEvent>(*line).sequence(), snapshot.sequence());

  // Cancel the other job while it runs: it stops at its next checkpoint
  CliResult r = d->Cli({"job", "cancel", other});
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_THAT(r.out, HasSubstr("cancelling"));
  const v1::JobInfo cancelled =
      WaitJob(*d, other, [](const v1::JobInfo& j) { return j.state() == v1::JOB_STATE_CANCELLED; });
  EXPECT_GT(cancelled.result().evaluations(), 0);
  EXPECT_EQ(cancelled.result().stop_reason(), "cancelled");

  // The watched job ends; its result
  std::optional<v1::JobEvent> last;
  while ((line = watch->ReadLine(120))) last = FromJson<v1::JobEvent>(*line);
  EXPECT_EQ(watch->Wait(), 0);
  ASSERT_TRUE(last);
  ASSERT_TRUE(last->has_finished());
  EXPECT_EQ(last->finished().evaluations(), 60);
  r = d->Cli({"job", "result", watched, "--json"});
  ASSERT_EQ(r.code, 0) << r.err;
  const v1::JobResult result = FromJson<v1::JobResult>(r.out);
  EXPECT_EQ(result.best_design().size(), 4u);
  EXPECT_GE(result.history_size(), 60);  // cached repeats included
  r = d->Cli({"job", "result", other});
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_THAT(r.out, HasSubstr("cancelled"));
  // Watching a finished job: its snapshot, then the stream ends
  r = d->Cli({"job", "watch", other});
  EXPECT_EQ(r.code, 1);
  EXPECT_THAT(r.out, HasSubstr("cancelled"));
}

TEST_F(FenestradTest, SigkillDuringAJobThenRestart) {
  auto d = StartDaemon();
  const std::string tiny = WriteJob("tiny", TinyJob());
  CliResult r = d->Cli({"site", "add", "--job", tiny, "--wait"});
  ASSERT_EQ(r.code, 0) << r.err;
  const std::string running = Submit(*d, WriteJob("long", LongJob()), {"--site", "site-1"});
  const std::string queued = Submit(*d, tiny, {"--site", "site-1"});
  WaitJob(*d, running, Running);
  EXPECT_EQ(GetJob(*d, queued).state(), v1::JOB_STATE_QUEUED);
  EXPECT_EQ(d->Kill(), 128 + SIGKILL);

  d->Start();
  const v1::JobInfo failed = GetJob(*d, running);
  EXPECT_EQ(failed.state(), v1::JOB_STATE_FAILED);
  EXPECT_EQ(failed.error(), "daemon stopped while running");
  EXPECT_GE(failed.progress().evaluations(), 2);
  r = d->Cli({"job", "show", running});
  EXPECT_THAT(r.out, HasSubstr("daemon stopped while running"));
  // The queued job was queued again and runs; the site's matrix came from disk
  const v1::JobInfo resumed = WaitJob(
      *d, queued, [](const v1::JobInfo& j) { return j.state() == v1::JOB_STATE_SUCCEEDED; });
  EXPECT_TRUE(resumed.outdoor_reused());
  const v1::SiteInfo site = GetSite(*d, "site-1");
  EXPECT_EQ(site.state(), v1::SITE_STATE_READY);
  EXPECT_TRUE(site.loaded_from_disk());
  EXPECT_EQ(site.computations(), 1);
  r = d->Cli({"job", "submit", tiny, "--site", "site-1", "--watch"});
  EXPECT_EQ(r.code, 0) << r.err;
  EXPECT_THAT(r.out, HasSubstr("best design:"));
}

TEST_F(FenestradTest, SigtermInterruptsARunningJobAndKeepsQueuedOnes) {
  auto d = StartDaemon({"--shutdown-grace", "0.3"});
  const std::string running = Submit(*d, WriteJob("long", LongJob()));
  const std::string queued = Submit(*d, WriteJob("tiny", TinyJob()));
  WaitJob(*d, running, Running);
  auto watch = d->Spawn({"job", "watch", running, "--json"});
  ASSERT_TRUE(watch->ReadLine());  // the snapshot

  const auto start = Clock::now();
  EXPECT_EQ(d->Stop(), 0);
  EXPECT_LT(std::chrono::duration<double>(Clock::now() - start).count(), 10);
  std::optional<std::string> line, last;
  while ((line = watch->ReadLine(10))) last = line;
  ASSERT_TRUE(last);
  EXPECT_TRUE(FromJson<v1::JobEvent>(*last).has_interrupted()) << *last;
  EXPECT_THAT(d->Log(), HasSubstr("interrupted by the shutdown"));

  d->Start();
  const v1::JobInfo interrupted = GetJob(*d, running);
  EXPECT_EQ(interrupted.state(), v1::JOB_STATE_INTERRUPTED);
  EXPECT_GT(interrupted.result().evaluations(), 0);
  WaitJob(*d, queued, [](const v1::JobInfo& j) { return j.state() == v1::JOB_STATE_SUCCEEDED; });
}

TEST_F(FenestradTest, CorruptCacheFileIsDetectedAndRecomputed) {
  auto d = StartDaemon();
  CliResult r = d->Cli({"site", "add", "--job", WriteJob("tiny", TinyJob()), "--wait"});
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_EQ(d->Stop(), 0);

  std::vector<fs::path> files;
  for (const auto& f : fs::directory_iterator(d->data_dir() + "/outdoor")) files.push_back(f);
  ASSERT_EQ(files.size(), 1u);
  std::string bytes = ReadFile(files[0]);
  bytes[bytes.size() / 2] ^= 0x10;
  std::ofstream(files[0], std::ios::binary | std::ios::trunc) << bytes;

  d->Start();
  EXPECT_THAT(d->Log(), HasSubstr("SHA-256 checksum mismatch"));
  const v1::SiteInfo site = WaitSiteReady(*d, "site-1");
  EXPECT_EQ(site.computations(), 2);
  EXPECT_FALSE(site.loaded_from_disk());
  // The recomputed file is sound again
  EXPECT_EQ(d->Stop(), 0);
  d->Start();
  EXPECT_TRUE(GetSite(*d, "site-1").loaded_from_disk());
}

TEST_F(FenestradTest, ObjMeshesAreSentInlineAsPolygons) {
  auto d = StartDaemon();
  // The city office plus a kiosk from an OBJ file: a 2 m tetrahedron, two groups
  v1::Scene scene =
      FromJson<v1::Scene>(ReadFile(FENESTRA_SOURCE_DIR "/examples/city_office/scene.json"));
  scene.mutable_site()->set_weather_file(FENESTRA_SOURCE_DIR
                                         "/examples/weather/URY_Montevideo.865800_IWEC.epw");
  v1::Surface& kiosk = *scene.add_surfaces();
  kiosk.set_name("kiosk");
  kiosk.set_material("city");
  kiosk.set_side(v1::SIDE_OUTDOOR);
  kiosk.mutable_obj()->set_path("kiosk.obj");
  (*kiosk.mutable_obj()->mutable_group_materials())["roof"] = "office";
  std::ofstream(dir_ + "/kiosk.obj") << "v 20 20 0\nv 22 20 0\nv 20 22 0\nv 20 20 2\n"
                                        "g walls\nf 1 3 2\nf 1 2 4\ng roof\nf 2 3 4\nf 1 4 3\n";
  std::ofstream(dir_ + "/scene.json") << ToJson(scene);

  CliResult r =
      d->Cli({"site", "add", dir_ + "/scene.json", "--outdoor-paths", "40000", "--wait", "--json"});
  ASSERT_EQ(r.code, 0) << r.err;
  const v1::SiteInfo site = FromJson<v1::SiteInfo>(r.out);
  EXPECT_EQ(site.state(), v1::SITE_STATE_READY);
  EXPECT_EQ(site.outdoor_triangles(), 100 + 4);
  const v1::SiteInfo full = GetSite(*d, site.id());
  int polygons = 0;
  for (const v1::Surface& s : full.scene().surfaces()) {
    EXPECT_FALSE(s.has_obj());
    if (s.name() == "kiosk") {
      ++polygons;
      EXPECT_EQ(s.polygon().vertices_size(), 3);
    }
  }
  EXPECT_EQ(polygons, 4);

  // A job on that scene runs
  v1::Job job = TinyJob(3);
  job.set_scene_file(dir_ + "/scene.json");
  r = d->Cli({"job", "submit", WriteJob("kiosk_job", job), "--watch"});
  EXPECT_EQ(r.code, 0) << r.err;
  EXPECT_THAT(r.out, HasSubstr("best design:"));
}

TEST_F(FenestradTest, BadRequestsGetTheRightCodeAndTheDaemonKeepsServing) {
  auto d = StartDaemon();
  auto submit = [&](const v1::SubmitJobRequest& request) {
    grpc::ClientContext context;
    v1::JobInfo info;
    return d->jobs().Submit(&context, request, &info);
  };
  auto expect = [](const grpc::Status& s, grpc::StatusCode code, const std::string& text) {
    EXPECT_EQ(s.error_code(), code) << s.error_message();
    EXPECT_THAT(s.error_message(), HasSubstr(text));
  };

  // Unknown ids
  CliResult r = d->Cli({"job", "show", "job-99"});
  EXPECT_EQ(r.code, 1);
  EXPECT_THAT(r.err, HasSubstr("NOT_FOUND: no job 'job-99'"));
  r = d->Cli({"job", "submit", WriteJob("tiny", TinyJob()), "--site", "site-7"});
  EXPECT_EQ(r.code, 1);
  EXPECT_THAT(r.err, HasSubstr("NOT_FOUND: no site 'site-7'"));
  r = d->Cli({"site", "rm", "site-7"});
  EXPECT_THAT(r.err, HasSubstr("NOT_FOUND"));
  r = d->Cli({"job", "cancel", "job-99"});
  EXPECT_THAT(r.err, HasSubstr("NOT_FOUND"));

  // An empty design range, an unknown variable
  v1::Job job = TinyJob();
  job.mutable_variables(0)->set_lower(1);
  job.mutable_variables(0)->set_upper(0.5);
  r = d->Cli({"job", "submit", WriteJob("empty_range", job)});
  EXPECT_EQ(r.code, 1);
  EXPECT_THAT(r.err, HasSubstr("INVALID_ARGUMENT"));
  EXPECT_THAT(r.err, HasSubstr("empty design range"));
  job = TinyJob();
  job.mutable_variables(0)->set_name("twist");
  expect(submit(InlineRequest(job)), grpc::StatusCode::INVALID_ARGUMENT, "unknown design variable");

  // A malformed scene, a scene by path, an OBJ path, no weather
  v1::SubmitJobRequest request = InlineRequest(TinyJob());
  request.mutable_job()->mutable_scene()->clear_window();
  expect(submit(request), grpc::StatusCode::INVALID_ARGUMENT, "window");
  request = InlineRequest(TinyJob());
  request.mutable_job()->mutable_scene()->mutable_window()->set_width_m(-1);
  expect(submit(request), grpc::StatusCode::INVALID_ARGUMENT, "window.width_m");
  request = InlineRequest(TinyJob());
  request.mutable_job()->set_scene_file("scene.json");
  expect(submit(request), grpc::StatusCode::INVALID_ARGUMENT, "path on the client");
  request = InlineRequest(TinyJob());
  request.mutable_job()->mutable_scene()->mutable_surfaces(0)->mutable_obj()->set_path("a.obj");
  expect(submit(request), grpc::StatusCode::INVALID_ARGUMENT, "send it inline");
  request = InlineRequest(TinyJob());
  request.clear_weather_epw();
  expect(submit(request), grpc::StatusCode::INVALID_ARGUMENT, "no weather file");
  {
    grpc::ClientContext context;
    v1::SiteInfo info;
    expect(d->sites().Register(&context, v1::RegisterSiteRequest(), &info),
           grpc::StatusCode::INVALID_ARGUMENT, "scene");
  }

  // A job whose outdoor part differs from its site's
  r = d->Cli({"site", "add", "--job", WriteJob("tiny", TinyJob()), "--wait"});
  ASSERT_EQ(r.code, 0) << r.err;
  job = TinyJob();
  job.mutable_sampling()->set_outdoor_paths(50000);
  request = InlineRequest(job);
  request.set_site_id("site-1");
  expect(submit(request), grpc::StatusCode::INVALID_ARGUMENT, "does not match site site-1");

  // Still serving
  r = d->Cli({"job", "submit", WriteJob("tiny", TinyJob()), "--site", "site-1", "--watch"});
  EXPECT_EQ(r.code, 0) << r.err;
  EXPECT_THAT(r.out, HasSubstr("best design:"));
}

TEST_F(FenestradTest, LimitsAreCheckedBeforeAnyWork) {
  auto d =
      StartDaemon({"--max-outdoor-paths", "100000", "--max-indoor-paths", "5000",
                   "--max-evaluations", "50", "--max-sensors", "20", "--max-triangles", "50000",
                   "--max-message-bytes", "3000000", "--max-queued-jobs", "1", "--max-sites", "1"});
  auto submit = [&](const v1::SubmitJobRequest& request) {
    grpc::ClientContext context;
    v1::JobInfo info;
    return d->jobs().Submit(&context, request, &info);
  };
  auto expect = [](const grpc::Status& s, grpc::StatusCode code, const std::string& text) {
    EXPECT_EQ(s.error_code(), code) << s.error_message();
    EXPECT_THAT(s.error_message(), HasSubstr(text));
  };
  v1::Job job = TinyJob();
  job.mutable_sampling()->set_outdoor_paths(200000);
  CliResult r = d->Cli({"job", "submit", WriteJob("paths", job)});
  EXPECT_EQ(r.code, 1);
  EXPECT_THAT(r.err, HasSubstr("INVALID_ARGUMENT: sampling.outdoor_paths is 200000, above this "
                               "server's limit max_outdoor_paths = 100000"));
  job = TinyJob();
  job.mutable_sampling()->set_indoor_paths_per_sensor(10000);
  expect(submit(InlineRequest(job)), grpc::StatusCode::INVALID_ARGUMENT,
         "max_indoor_paths_per_sensor");
  expect(submit(InlineRequest(TinyJob(100))), grpc::StatusCode::INVALID_ARGUMENT,
         "max_evaluations = 50");
  v1::SubmitJobRequest request = InlineRequest(TinyJob());
  v1::SensorGrid& grid = *request.mutable_job()->mutable_scene()->add_sensor_grids();
  grid.set_x_max_m(1);
  grid.set_y_max_m(1);
  grid.set_spacing_m(0.1);
  expect(submit(request), grpc::StatusCode::INVALID_ARGUMENT, "max_sensors = 20");
  job = TinyJob();
  job.mutable_variables(1)->set_lower(1e-5);  // the narrowest slats: 150000 of them
  job.mutable_variables(1)->set_fixed(false);
  expect(submit(InlineRequest(job)), grpc::StatusCode::INVALID_ARGUMENT, "max_triangles = 50000");
  request = InlineRequest(TinyJob());
  request.mutable_job()->set_name(std::string(4'000'000, 'x'));
  expect(submit(request), grpc::StatusCode::RESOURCE_EXHAUSTED, "larger than max");

  // The queue holds one waiting job, the server one site
  const std::string running = Submit(*d, WriteJob("long", TinyJob(50)));
  WaitJob(*d, running, [](const v1::JobInfo& j) { return j.state() != v1::JOB_STATE_QUEUED; });
  const std::string waiting = Submit(*d, WriteJob("tiny", TinyJob()));
  r = d->Cli({"job", "submit", WriteJob("tiny", TinyJob())});
  EXPECT_EQ(r.code, 1);
  EXPECT_THAT(r.err, HasSubstr("RESOURCE_EXHAUSTED: the job queue is full"));
  EXPECT_THAT(r.err, HasSubstr("max_queued_jobs = 1"));
  r = d->Cli({"job", "cancel", waiting});
  EXPECT_THAT(r.out, HasSubstr("cancelled"));
  r = d->Cli({"job", "cancel", running});
  EXPECT_EQ(r.code, 0);
  r = d->Cli({"site", "add", "--job", WriteJob("tiny", TinyJob())});
  EXPECT_EQ(r.code, 0) << r.err;
  r = d->Cli({"site", "add", "--job", WriteJob("tiny", TinyJob())});
  EXPECT_EQ(r.code, 1);
  EXPECT_THAT(r.err, HasSubstr("RESOURCE_EXHAUSTED"));
  EXPECT_THAT(r.err, HasSubstr("max_sites"));
}

TEST_F(FenestradTest, ClientSaysWhenTheServerIsDownOrSilent) {
  // Nothing listens on port 1
  CliResult r = Daemon::RunCli({FENESTRA_CLI, "job", "list", "--server", "127.0.0.1:1"});
  EXPECT_EQ(r.code, 1);
  EXPECT_THAT(r.err, HasSubstr("cannot reach fenestrad at 127.0.0.1:1"));
  // A socket that accepts connections but never answers
  const int silent = socket(AF_INET, SOCK_STREAM, 0);
  sockaddr_in address{};
  address.sin_family = AF_INET;
  address.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  ASSERT_EQ(bind(silent, reinterpret_cast<sockaddr*>(&address), sizeof address), 0);
  ASSERT_EQ(listen(silent, 8), 0);
  socklen_t size = sizeof address;
  getsockname(silent, reinterpret_cast<sockaddr*>(&address), &size);
  const std::string server = "127.0.0.1:" + std::to_string(ntohs(address.sin_port));
  r = Daemon::RunCli({FENESTRA_CLI, "site", "list", "--server", server, "--timeout", "1"});
  EXPECT_EQ(r.code, 1);
  EXPECT_THAT(r.err, HasSubstr("fenestrad at " + server + " did not answer within 1 s"));
  close(silent);
}

TEST_F(FenestradTest, HealthCheckingAndReflection) {
  auto d = StartDaemon();
  // grpc.health.v1.Health/Check with an empty request: SERVING is field 1 = 1
  grpc::ClientContext context;
  grpc::Slice empty(std::string{});
  grpc::ByteBuffer request(&empty, 1), response;
  const grpc::Status status = grpc::internal::BlockingUnaryCall(
      d->channel().get(),
      grpc::internal::RpcMethod("/grpc.health.v1.Health/Check",
                                grpc::internal::RpcMethod::NORMAL_RPC),
      &context, request, &response);
  ASSERT_TRUE(status.ok()) << status.error_message();
  std::vector<grpc::Slice> slices;
  ASSERT_TRUE(response.Dump(&slices).ok());
  std::string bytes;
  for (const grpc::Slice& s : slices)
    bytes.append(reinterpret_cast<const char*>(s.begin()), s.size());
  EXPECT_EQ(bytes, std::string("\x08\x01", 2));

  // grpc.reflection.v1alpha.ServerReflection: list_services (field 7, empty)
  grpc::ClientContext reflection_context;
  std::unique_ptr<grpc::ClientReaderWriter<grpc::ByteBuffer, grpc::ByteBuffer>> stream(
      grpc::internal::ClientReaderWriterFactory<grpc::ByteBuffer, grpc::ByteBuffer>::Create(
          d->channel().get(),
          grpc::internal::RpcMethod(
              "/grpc.reflection.v1alpha.ServerReflection/ServerReflectionInfo",
              grpc::internal::RpcMethod::BIDI_STREAMING),
          &reflection_context));
  grpc::Slice list_services("\x3a\x00", 2);
  ASSERT_TRUE(stream->Write(grpc::ByteBuffer(&list_services, 1)));
  stream->WritesDone();
  grpc::ByteBuffer answer;
  ASSERT_TRUE(stream->Read(&answer));
  slices.clear();
  ASSERT_TRUE(answer.Dump(&slices).ok());
  bytes.clear();
  for (const grpc::Slice& s : slices)
    bytes.append(reinterpret_cast<const char*>(s.begin()), s.size());
  EXPECT_THAT(bytes, HasSubstr("fenestra.v1.JobService"));
  EXPECT_THAT(bytes, HasSubstr("fenestra.v1.SiteService"));
  EXPECT_THAT(bytes, HasSubstr("grpc.health.v1.Health"));
  EXPECT_TRUE(stream->Finish().ok());
}

TEST_F(FenestradTest, PythonClientRegistersASiteAndRunsAJob) {
  if (Daemon::RunCli({"/usr/bin/python3", "-c", "import grpc, google.protobuf"}).code != 0) {
    GTEST_SKIP() << "/usr/bin/python3 has no grpc module (python3-grpcio)";
  }
  auto d = StartDaemon();
  const CliResult r = Daemon::RunCli(
      {"/usr/bin/python3", FENESTRA_SOURCE_DIR "/examples/python_client.py", "--server",
       d->address(), "--outdoor-paths", "40000", "--indoor-paths", "2000", "--evaluations", "6",
       FENESTRA_SOURCE_DIR "/examples/city_office/alpha_max_quick.json"});
  ASSERT_EQ(r.code, 0) << r.out << r.err;
  EXPECT_THAT(r.out, HasSubstr("site-1 ready"));
  EXPECT_THAT(r.out, HasSubstr("stage search"));
  EXPECT_THAT(r.out, HasSubstr("[6/6] best"));
  EXPECT_THAT(r.out, HasSubstr("best design: alpha="));
}

}  // namespace
}  // namespace fenestra
