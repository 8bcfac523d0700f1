// What a search checkpoint costs: the four-variable city-office job
// (examples/city_office/four_variables.json, 500 evaluations) with 2000 indoor paths per
// sensor and 20000 outdoor paths on the CPU, without its final check (the sampling changes
// the values, not the checkpoint's size or cost). Prints, over the steps: the checkpoint's
// serialized size, the time RunJob spends between a step's end and handing out its
// checkpoint (building it), and the time to serialize it (what a store does with it); then
// the time to parse the last one, to hash the job, to resume from it (replay included,
// nothing left to evaluate), and to replay a search of as many steps alone.
//
//   search_checkpoint_bench
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <string>
#include <vector>

#include "bench/bench_util.h"
#include "core/optimize/job.h"
#include "core/optimize/vns.h"

namespace fenestra {
namespace {

using Clock = std::chrono::steady_clock;

double MicrosecondsSince(Clock::time_point start) {
  return std::chrono::duration<double, std::micro>(Clock::now() - start).count();
}

// Over the steps; the median stands for a step on a quiet machine (the machine is shared,
// bench/README.md, and a preempted step shows as the maximum).
struct Summary {
  double median = 0, max = 0, last = 0;
};

Summary Summarize(std::vector<double> values) {
  Summary s;
  s.last = values.back();
  std::sort(values.begin(), values.end());
  s.median = values[values.size() / 2];
  s.max = values.back();
  return s;
}

int Main() {
  v1::Job spec =
      ValueOrExit(ReadJobFile(FENESTRA_SOURCE_DIR "/examples/city_office/four_variables.json"));
  spec.mutable_sampling()->set_indoor_paths_per_sensor(2000);
  spec.mutable_sampling()->set_outdoor_paths(20000);
  spec.mutable_sampling()->set_backend("cpu");
  spec.mutable_sampling()->set_final_check(false);
  const PreparedJob job =
      ValueOrExit(PrepareJob(spec, FENESTRA_SOURCE_DIR "/examples/city_office"));

  // The job, its clock read at each checkpoint
  std::vector<double> build_us, serialize_us, sizes;
  std::string last;
  JobCallbacks callbacks;
  Clock::time_point start;
  callbacks.checkpoint = [&](const v1::SearchCheckpoint& checkpoint) {
    const double now_s = std::chrono::duration<double>(Clock::now() - start).count();
    const double step_end_s = checkpoint.history(checkpoint.history_size() - 1).elapsed_seconds();
    build_us.push_back(1e6 * (now_s - step_end_s));
    const Clock::time_point t0 = Clock::now();
    last = checkpoint.SerializeAsString();
    serialize_us.push_back(MicrosecondsSince(t0));
    sizes.push_back(static_cast<double>(last.size()));
  };
  start = Clock::now();
  const v1::JobResult result = ValueOrExit(RunJob(job, nullptr, callbacks));
  const double job_seconds = std::chrono::duration<double>(Clock::now() - start).count();

  // Resuming from the last one
  Clock::time_point t0 = Clock::now();
  const v1::SearchCheckpoint parsed = ValueOrExit(ParseSearchCheckpoint(last));
  const double parse_us = MicrosecondsSince(t0);
  t0 = Clock::now();
  const std::string hash = JobContentHash(job);
  const double hash_us = MicrosecondsSince(t0);
  const OutdoorMatrix outdoor = ValueOrExit(ComputeOutdoorMatrix(job.scene, job.job.sampling()));
  t0 = Clock::now();
  const v1::JobResult resumed = ValueOrExit(RunJob(job, &outdoor, {}, &parsed));
  const double resume_s = std::chrono::duration<double>(Clock::now() - t0).count();

  // The replay alone: a search of as many steps over the job's variables, on an analytic
  // objective
  std::vector<DesignVariable> variables;
  for (const v1::DesignVariable& v : spec.variables()) {
    variables.push_back({v.name(), v.lower(), v.upper(), v.start(), v.fixed(), v.step()});
  }
  VnsOptions options;
  options.max_evaluations = spec.budget().max_evaluations();
  options.failed_cycles_to_stop = 0;
  const auto bowl = [&](const std::vector<double>& x) -> absl::StatusOr<Evaluation> {
    double sum = 0;
    for (size_t i = 0; i < x.size(); ++i) {
      const double u = (x[i] - variables[i].lower) / (variables[i].upper - variables[i].lower);
      sum += (u - 0.4) * (u - 0.4);
    }
    return Evaluation{-sum, 0.01, false, {}};
  };
  const VnsResult search = ValueOrExit(RunVns(variables, bowl, options));
  t0 = Clock::now();
  const absl::Status replayed = CheckVnsResume(variables, options, search);
  const double replay_us = MicrosecondsSince(t0);
  if (!replayed.ok()) return ValueOrExit(absl::StatusOr<int>(replayed));

  const Summary build = Summarize(build_us), serialize = Summarize(serialize_us);
  std::printf("%s: %d evaluations, %d steps, stop %s, job %.1f s\n", spec.name().c_str(),
              result.evaluations(), result.history_size(), result.stop_reason().c_str(),
              job_seconds);
  std::printf("checkpoint size: %.0f bytes after the last step (%.1f bytes per step)\n",
              sizes.back(), sizes.back() / static_cast<double>(sizes.size()));
  std::printf("build (step end to hand-out): median %.1f us, max %.1f us, last %.1f us\n",
              build.median, build.max, build.last);
  std::printf("serialize: median %.1f us, max %.1f us, last %.1f us\n", serialize.median,
              serialize.max, serialize.last);
  std::printf("parse the last: %.1f us; job content hash: %.1f us\n", parse_us, hash_us);
  std::printf(
      "resume after the last step (sky, indoor paths, replay; outdoor given): %.2f s, "
      "%d steps, same best: %s\n",
      resume_s, resumed.history_size(),
      resumed.best_value().value() == result.best_value().value() ? "yes" : "no");
  std::printf("replay of %zu steps (analytic objective): %.1f us\n", search.history.size(),
              replay_us);
  return 0;
}

}  // namespace
}  // namespace fenestra

int main() { return fenestra::Main(); }
