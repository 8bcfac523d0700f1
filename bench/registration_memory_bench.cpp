// The memory fenestrad takes for a large site registration: a real daemon (a child process
// with a temporary data directory) is sent the city office with 600 000 extra outdoor
// triangles (a 60 MB request) through gRPC, and its resident memory (/proc/PID/status
// VmRSS, sampled every 5 ms, and VmHWM, the kernel's peak) is recorded before, at the peak
// and after each step: the registration and its outdoor matrix, two more registrations,
// deleting every site. A SiteService.List during a registration is timed too.
//
//   registration_memory_bench [--triangles N] [--outdoor-paths N] [--fenestrad PATH]
#include <fcntl.h>
#include <grpcpp/grpcpp.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>
#include <thread>
#include <vector>

#include "core/common/seconds.h"
#include "fenestra/v1/service.grpc.pb.h"
#include "tests/child_process.h"
#include "tests/server/large_registration.h"

namespace fenestra {
namespace {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

// Samples the daemon's VmRSS every 5 ms while alive; Peak() is the largest since Reset().
class RssSampler {
 public:
  explicit RssSampler(pid_t pid) : pid_(pid), thread_([this] { Loop(); }) {}
  ~RssSampler() {
    stop_ = true;
    thread_.join();
  }
  void Reset() { peak_ = ProcessStatusMiB(pid_, "VmRSS"); }
  double Peak() const { return peak_; }

 private:
  void Loop() {
    while (!stop_) {
      const double rss = ProcessStatusMiB(pid_, "VmRSS");
      if (rss > peak_) peak_ = rss;
      std::this_thread::sleep_for(std::chrono::milliseconds(5));
    }
  }
  pid_t pid_;
  std::atomic<bool> stop_ = false;
  std::atomic<double> peak_ = 0;
  std::thread thread_;
};

// The command line's options.
struct Args {
  int triangles = 600'000;
  int64_t outdoor_paths = 40'000;
  std::string fenestrad = FENESTRAD;
};

// The command line: --triangles N, --outdoor-paths N, --fenestrad PATH.
Args ParseArgs(int argc, char** argv) {
  Args a;
  for (int i = 1; i + 1 < argc; i += 2) {
    if (std::string(argv[i]) == "--triangles") a.triangles = std::stoi(argv[i + 1]);
    if (std::string(argv[i]) == "--outdoor-paths") a.outdoor_paths = std::stoll(argv[i + 1]);
    if (std::string(argv[i]) == "--fenestrad") a.fenestrad = argv[i + 1];
  }
  return a;
}

// A running daemon: its temporary directory (data, log, port file), process and port.
struct Daemon {
  std::string dir;
  pid_t pid = 0;
  int port = 0;
};

// Starts fenestrad with the CPU backend, one worker and no authentication in a fresh
// temporary directory, and waits for the port it listens on.
Daemon StartDaemon(const std::string& fenestrad) {
  Daemon d;
  d.dir = fs::temp_directory_path() / ("registration_memory_bench." + std::to_string(getpid()));
  fs::remove_all(d.dir);
  fs::create_directories(d.dir);
  const std::string port_file = d.dir + "/port";
  const int log = OpenForChild(d.dir + "/fenestrad.log", /*append=*/false);
  d.pid = Spawn({fenestrad, "--listen", "127.0.0.1:0", "--data-dir", d.dir + "/data", "--port-file",
                 port_file, "--workers", "1", "--backend", "cpu", "--auth", "none"},
                {{log, STDERR_FILENO}}, /*die_with_parent=*/true);
  close(log);
  while (!fs::exists(port_file)) std::this_thread::sleep_for(std::chrono::milliseconds(20));
  std::ifstream(port_file) >> d.port;
  return d;
}

// Stops the daemon and removes its directory.
void StopDaemon(const Daemon& d) {
  kill(d.pid, SIGTERM);
  waitpid(d.pid, nullptr, 0);
  fs::remove_all(d.dir);
}

// A channel to the daemon's port that carries messages of up to 128 MiB.
std::shared_ptr<grpc::Channel> Connect(int port) {
  return grpc::CreateCustomChannel("127.0.0.1:" + std::to_string(port),
                                   grpc::InsecureChannelCredentials(), [] {
                                     grpc::ChannelArguments args;
                                     args.SetMaxSendMessageSize(128 << 20);
                                     args.SetMaxReceiveMessageSize(128 << 20);
                                     return args;
                                   }());
}

// The daemon's sites (empty if the call fails).
v1::ListSitesResponse ListSites(v1::SiteService::Stub& sites) {
  grpc::ClientContext context;
  v1::ListSitesResponse response;
  (void)sites.List(&context, v1::ListSitesRequest(), &response);
  return response;
}

// Waits until no site is computing.
void WaitReady(v1::SiteService::Stub& sites) {
  while (true) {
    bool computing = false;
    const v1::ListSitesResponse listed = ListSites(sites);
    for (const v1::SiteInfo& s : listed.sites()) {
      computing |= s.state() == v1::SITE_STATE_COMPUTING;
    }
    if (!computing) return;
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
}

// Prints a step's row a second after it ends: VmRSS before, the sampled peak, VmRSS after,
// VmHWM [MiB], and the step's seconds.
void SettleAndReport(const std::string& step, double before, double seconds,
                     const RssSampler& sampler, pid_t pid) {
  std::this_thread::sleep_for(std::chrono::seconds(1));
  std::printf("%-44s %8.0f %8.0f %8.0f %8.0f %7.1f\n", step.c_str(), before, sampler.Peak(),
              ProcessStatusMiB(pid, "VmRSS"), ProcessStatusMiB(pid, "VmHWM"), seconds);
  std::fflush(stdout);
}

// Registration k (its outdoor geometry shifted by 0.01 k) until its outdoor matrix is
// traced, with a List 300 ms into it: prints its row and when Register answered; false if
// Register fails.
bool RegisterAndReport(v1::SiteService::Stub& sites, RssSampler& sampler, pid_t pid, int triangles,
                       int64_t outdoor_paths, int k) {
  const v1::RegisterSiteRequest request = LargeRegistration(triangles, outdoor_paths, 0.01 * k);
  const double before = ProcessStatusMiB(pid, "VmRSS");
  sampler.Reset();
  const auto start = Clock::now();
  // A List while the registration is processed
  std::atomic<double> list_seconds = -1;
  std::thread lister([&] {
    std::this_thread::sleep_for(std::chrono::milliseconds(300));
    const auto list_start = Clock::now();
    ListSites(sites);
    list_seconds = SecondsSince(list_start);
  });
  grpc::ClientContext context;
  v1::SiteInfo info;
  const grpc::Status status = sites.Register(&context, request, &info);
  const double register_seconds = SecondsSince(start);
  const double register_peak = sampler.Peak();
  lister.join();
  if (!status.ok()) {
    std::fprintf(stderr, "Register: %s\n", status.error_message().c_str());
    return false;
  }
  WaitReady(sites);
  SettleAndReport("register " + info.id() + " (" + std::to_string(request.ByteSizeLong() >> 20) +
                      " MiB, " + std::to_string(triangles) + " triangles) and trace",
                  before, SecondsSince(start), sampler, pid);
  std::printf(
      "    Register answered in %.2f s (peak until then %.0f MiB); a List meanwhile "
      "took %.3f s\n",
      register_seconds, register_peak, list_seconds.load());
  return true;
}

// Deletes every site and prints the step's row.
void DeleteEverySite(v1::SiteService::Stub& sites, RssSampler& sampler, pid_t pid) {
  const double before = ProcessStatusMiB(pid, "VmRSS");
  sampler.Reset();
  const auto start = Clock::now();
  const v1::ListSitesResponse listed = ListSites(sites);
  for (const v1::SiteInfo& s : listed.sites()) {
    grpc::ClientContext context;
    v1::DeleteSiteRequest request;
    request.set_id(s.id());
    v1::DeleteSiteResponse response;
    (void)sites.Delete(&context, request, &response);
  }
  SettleAndReport("delete every site", before, SecondsSince(start), sampler, pid);
}

int Main(int argc, char** argv) {
  const Args args = ParseArgs(argc, argv);
  const Daemon daemon = StartDaemon(args.fenestrad);
  auto channel = Connect(daemon.port);
  auto sites = v1::SiteService::NewStub(channel);
  RssSampler sampler(daemon.pid);

  std::printf("fenestrad resident memory [MiB] (VmRSS before, sampled peak, after; VmHWM)\n");
  std::printf("%-44s %8s %8s %8s %8s %7s\n", "step", "before", "peak", "after", "VmHWM", "s");
  std::this_thread::sleep_for(std::chrono::seconds(1));
  bool registered = true;
  for (int k = 0; k < 3 && registered; ++k) {
    registered =
        RegisterAndReport(*sites, sampler, daemon.pid, args.triangles, args.outdoor_paths, k);
  }
  if (registered) DeleteEverySite(*sites, sampler, daemon.pid);
  StopDaemon(daemon);
  return registered ? 0 : 1;
}

}  // namespace
}  // namespace fenestra

int main(int argc, char** argv) { return fenestra::Main(argc, argv); }
