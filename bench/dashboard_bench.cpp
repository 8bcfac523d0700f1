// The web dashboard under load: fenestrad (CPU backend, one worker) runs JOBS tiny jobs
// submitted through its JSON API, first with no page open, then with PAGES headless Chromium
// pages signed in on the job list (each polling it and the sites every second). Per run: the
// wall time from the first submission to the last job's end (job throughput), the daemon's
// CPU time and its peak resident memory. With two cores or more the daemon runs on the first
// and the pages (and this program) on the others, so that what is measured is what serving the
// pages costs the daemon, not the browsers' own rendering taking its core.
//
// Usage: dashboard_bench [JOBS=50] [PAGES=20]
#include <google/protobuf/util/json_util.h>
#include <httplib.h>
#include <sched.h>
#include <signal.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <memory>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "absl/strings/escaping.h"
#include "fenestra/v1/job.pb.h"
#include "tests/child_process.h"
#include "tests/headless_chromium.h"

namespace fs = std::filesystem;
using fenestra::HeadlessChromium;

namespace {

// Runs this process, and the children it starts from now on, on cores [first, last].
void UseCores(int first, int last) {
  cpu_set_t set;
  CPU_ZERO(&set);
  for (int c = first; c <= last; ++c) CPU_SET(c, &set);
  if (sched_setaffinity(0, sizeof(set), &set) != 0) std::perror("sched_setaffinity");
}

std::string ReadFile(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

// The city-office tilt job with tiny sampling (as the tests' TinyJob), its scene and weather,
// as the dashboard's submission.
std::string SubmitBody(int evaluations) {
  fenestra::v1::Job job;
  (void)google::protobuf::util::JsonStringToMessage(
      ReadFile(FENESTRA_SOURCE_DIR "/examples/city_office/alpha_max_quick.json"), &job);
  job.clear_scene_file();
  job.set_name("bench");
  fenestra::v1::Sampling& s = *job.mutable_sampling();
  s.set_outdoor_paths(40000);
  s.set_indoor_paths_per_sensor(2000);
  s.set_backend("cpu");
  s.set_window_columns(1);
  s.set_window_rows(1);
  job.mutable_budget()->set_max_evaluations(evaluations);
  job.mutable_budget()->set_failed_cycles_to_stop(-1);
  std::string json;
  (void)google::protobuf::util::MessageToJsonString(job, &json);
  const std::string scene = ReadFile(FENESTRA_SOURCE_DIR "/examples/city_office/scene.json");
  const std::string weather =
      ReadFile(FENESTRA_SOURCE_DIR "/examples/weather/URY_Montevideo.865800_IWEC.epw");
  return "{\"job\": " + json + ", \"scene\": " + scene + ", \"weatherEpw\": \"" +
         absl::Base64Escape(weather) + "\", \"weatherName\": \"montevideo.epw\"}";
}

// The daemon's CPU time [s] and peak resident memory [MiB], from /proc.
std::pair<double, double> Usage(pid_t pid) {
  std::ifstream stat("/proc/" + std::to_string(pid) + "/stat");
  std::string field;
  std::vector<std::string> fields;
  while (stat >> field) fields.push_back(field);
  const double ticks = static_cast<double>(sysconf(_SC_CLK_TCK));
  const double cpu =
      fields.size() > 15 ? (std::stod(fields[13]) + std::stod(fields[14])) / ticks : 0;
  std::ifstream status("/proc/" + std::to_string(pid) + "/status");
  double hwm_mib = 0;
  for (std::string line; std::getline(status, line);) {
    if (line.rfind("VmHWM:", 0) == 0) hwm_mib = std::stod(line.substr(6)) / 1024;
  }
  return {cpu, hwm_mib};
}

struct Run {
  double wall_s = 0, cpu_s = 0, peak_mib = 0;
  int succeeded = 0;
};

Run RunOnce(const std::string& dir, int jobs, int pages) {
  fs::remove_all(dir);
  fs::create_directories(dir);
  const std::string data = dir + "/data";
  // A user, then the daemon
  const std::string token_file = dir + "/token";
  const int out = fenestra::OpenForChild(token_file, false);
  fenestra::WaitExit(fenestra::Spawn({FENESTRAD, "user", "add", "bench", "--data-dir", data},
                                     {{out, STDOUT_FILENO}}));
  close(out);
  std::string token = ReadFile(token_file);
  while (!token.empty() && token.back() == '\n') token.pop_back();
  const int cores = static_cast<int>(sysconf(_SC_NPROCESSORS_ONLN));
  if (cores >= 2) UseCores(0, 0);
  const pid_t daemon = fenestra::LaunchFenestrad(
      FENESTRAD, data,
      {"--http", "127.0.0.1:0", "--backend", "cpu", "--workers", "1", "--max-queued-jobs", "200",
       "--max-queued-jobs-per-user", "200", "--max-upload-bytes-per-user", "1000000000"},
      data + ".log");
  if (fenestra::FenestradAddress(data).empty()) {
    std::fprintf(stderr, "fenestrad did not start:\n%s\n", ReadFile(data + ".log").c_str());
    std::exit(1);
  }
  std::ifstream ports(data + ".port");
  int grpc_port = 0, http_port = 0;
  ports >> grpc_port >> http_port;
  const std::string origin = "http://127.0.0.1:" + std::to_string(http_port);

  if (cores >= 2) UseCores(1, cores - 1);
  // The pages, signed in on the list
  std::vector<std::unique_ptr<HeadlessChromium>> open;
  for (int p = 0; p < pages; ++p) {
    auto page = HeadlessChromium::Start(CHROMIUM_EXECUTABLE, dir + "/chromium" + std::to_string(p));
    if (!page.ok() || !(*page)->Load(origin + "/", 1280, 800).ok()) {
      std::fprintf(stderr, "page %d did not open\n", p);
      std::exit(1);
    }
    (void)(*page)->Evaluate("document.querySelector('#token').value = '" + token +
                            "'; document.querySelector('#sign-in-button').click(); true");
    open.push_back(*std::move(page));
  }

  httplib::Client client("127.0.0.1", http_port);
  client.set_read_timeout(60);
  const httplib::Headers auth = {{"Authorization", "Bearer " + token}};
  const std::string body = SubmitBody(6);
  const auto [cpu_before, peak_before] = Usage(daemon);
  (void)peak_before;
  const auto start = std::chrono::steady_clock::now();
  for (int j = 0; j < jobs; ++j) {
    httplib::Result r = client.Post("/api/v1/jobs", auth, body, "application/json");
    if (!r || r->status != 200) {
      std::fprintf(stderr, "submission %d: %d %s\n", j, r ? r->status : -1,
                   r ? r->body.c_str() : "no answer");
      std::exit(1);
    }
  }
  Run run;
  while (true) {
    httplib::Result r = client.Get("/api/v1/jobs", auth);
    const std::string& list = r ? r->body : "";
    auto count = [&](const std::string& s) {
      int n = 0;
      for (size_t at = list.find(s); at != std::string::npos; at = list.find(s, at + 1)) ++n;
      return n;
    };
    if (count("JOB_STATE_QUEUED") + count("JOB_STATE_RUNNING") == 0 && r && r->status == 200) {
      run.succeeded = count("JOB_STATE_SUCCEEDED");
      break;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(200));
  }
  run.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  const auto [cpu_after, peak] = Usage(daemon);
  run.cpu_s = cpu_after - cpu_before;
  run.peak_mib = peak;
  open.clear();
  kill(daemon, SIGTERM);
  fenestra::WaitExit(daemon);
  return run;
}

}  // namespace

int main(int argc, char** argv) {
  const int jobs = argc > 1 ? std::atoi(argv[1]) : 50;
  const int pages = argc > 2 ? std::atoi(argv[2]) : 20;
  const std::string dir =
      fs::temp_directory_path().string() + "/dashboard_bench." + std::to_string(getpid());
  std::printf(
      "# dashboard_bench: %d tiny jobs (6 evaluations each) through the JSON API, one "
      "CPU worker; %d pages polling the list each second in the second run\n",
      jobs, pages);
  for (int pass = 0; pass < 2; ++pass) {
    for (const int p : {0, pages}) {
      const Run r = RunOnce(dir, jobs, p);
      std::printf(
          "pages %2d: %d/%d succeeded, %.1f s (%.2f jobs/s), daemon CPU %.1f s, peak "
          "RSS %.0f MiB\n",
          p, r.succeeded, jobs, r.wall_s, r.succeeded / r.wall_s, r.cpu_s, r.peak_mib);
      std::fflush(stdout);
    }
  }
  fs::remove_all(dir);
  return 0;
}
