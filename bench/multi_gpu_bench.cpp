// Several GPUs (bench/README.md, "Several GPUs"): one four-variable job with its lanes on 1 to
// all visible GPUs; then independent four-variable jobs, one worker thread per GPU as
// fenestrad runs them (WorkerCudaDevices: each worker's jobs on its own GPU), for 1 to all
// visible GPUs: jobs per second and the ratio to one GPU. Without a GPU it says so and exits
// with 1.
//   multi_gpu_bench [jobs per GPU (4)]
#include <atomic>
#include <chrono>
#include <cstdio>
#include <string>
#include <thread>
#include <vector>

#include "bench/bench_util.h"
#include "core/common/seconds.h"
#include "core/dc/dc_backend.h"
#include "core/optimize/job.h"

namespace fenestra {
namespace {

const std::string kRoot = FENESTRA_SOURCE_DIR;

}  // namespace
}  // namespace fenestra

int main(int argc, char** argv) {
  using namespace fenestra;
  const int per_gpu = argc > 1 ? std::stoi(argv[1]) : 4;
  const int visible = CudaDevices();
  if (visible == 0) {
    std::printf("no CUDA device\n");
    return 1;
  }
  for (int d = 0; d < visible; ++d) {
    absl::StatusOr<std::unique_ptr<DcBackend>> backend = MakeCudaBackend(d);
    std::printf("GPU %d: %s\n", d, backend.ok() ? (*backend)->Name().c_str() : "unavailable");
  }
  v1::Job job = ValueOrExit(ReadJobFile(kRoot + "/examples/city_office/four_variables.json"));
  job.mutable_sampling()->set_backend("cuda");
  const PreparedJob prepared = ValueOrExit(PrepareJob(job, kRoot + "/examples/city_office"));
  // One job across the GPUs: the four-variable job with 1 to 2 x visible candidates at once
  // (each lane a tracer on the next GPU in turn), twice each
  std::vector<int> all;
  for (int d = 0; d < visible; ++d) all.push_back(d);
  UseCudaDevices(all);
  ValueOrExit(RunJob(prepared, nullptr));  // warm-up: contexts, first launches
  for (int lanes = 1; lanes <= std::max(4, 2 * visible); ++lanes) {
    PreparedJob one = prepared;
    one.job.mutable_sampling()->set_candidates_at_once(lanes);
    for (int run = 0; run < 2; ++run) {
      const auto start = std::chrono::steady_clock::now();
      const v1::JobResult r = ValueOrExit(RunJob(one, nullptr));
      const double wall = SecondsSince(start);
      std::printf(
          "one job, %2d at once on %d GPU(s): %.3f s (outdoor %.3f s, evaluations %.3f s, final "
          "check %.3f s, the rest %.3f s), %d evaluations (+%d dropped), mean %.3f ms; best %.3f "
          "+- %.3f %%\n",
          lanes, std::min(lanes, visible), wall, r.timings().outdoor_seconds(),
          r.timings().evaluation_seconds(), r.final_check().seconds(),
          r.timings().total_seconds() - r.timings().outdoor_seconds() -
              r.timings().evaluation_seconds() - r.final_check().seconds(),
          r.evaluations(), r.evaluations_discarded(),
          1e3 * r.timings().evaluation_seconds() / std::max(1, r.evaluations()),
          r.best_value().value(), r.best_value().standard_error());
    }
  }

  double one_gpu = 0;
  for (int gpus = 1; gpus <= visible; gpus *= 2) {
    std::vector<int> devices;
    for (int d = 0; d < gpus; ++d) devices.push_back(d);
    UseCudaDevices(devices);
    ValueOrExit(RunJob(prepared, nullptr));  // warm-up: contexts, first launches
    const int jobs = per_gpu * gpus;
    std::atomic<int> next{0};
    std::vector<double> seconds(jobs);
    std::vector<std::string> errors;
    const auto start = std::chrono::steady_clock::now();
    std::vector<std::thread> workers;
    for (int w = 0; w < gpus; ++w) {
      workers.emplace_back([&, w] {
        const ThreadCudaDevices mine(WorkerCudaDevices(w, gpus));
        for (int k; (k = next.fetch_add(1)) < jobs;) {
          const auto job_start = std::chrono::steady_clock::now();
          absl::StatusOr<v1::JobResult> result = RunJob(prepared, nullptr);
          seconds[k] = result.ok() ? SecondsSince(job_start) : -1;
        }
      });
    }
    for (std::thread& worker : workers) worker.join();
    const double wall = SecondsSince(start);
    double slowest = 0, sum = 0;
    for (const double s : seconds) {
      if (s < 0) {
        std::printf("a job failed\n");
        return 1;
      }
      slowest = std::max(slowest, s);
      sum += s;
    }
    const double rate = jobs / wall;
    if (gpus == 1) one_gpu = rate;
    std::printf(
        "%d GPU(s), %d four-variable jobs on %d workers: %.2f s, %.3f jobs/s (%.2f x one GPU, "
        "%.2f of linear); a job %.2f s on average, %.2f s the slowest\n",
        gpus, jobs, gpus, wall, rate, rate / one_gpu, rate / one_gpu / gpus, sum / jobs, slowest);
  }
  return 0;
}
