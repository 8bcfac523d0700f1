// The final check of the city-office experiments: each job's best design, as stored in
// build/bench/experiment_<job>_cpu2.result.json (written by bench/experiments.sh), checked by
// the one-stage method as the job does after its search (CheckJobDesign), then the quick job
// end to end. Prints both values, their difference, the paths and the check's wall, CPU and
// charged time (min(wall, CPU / threads): the machine may be shared, bench/README.md).
//
//   final_check_bench [seeds] [cpu|cuda|auto]
//   final_check_bench split [cpu|cuda|auto] [OUTDOOR/INDOOR ...]
//
// `seeds` (default 1) repeats each check with the jobs' seed set to 1, 2, ... (other streams).
// `split` tells the reflection limits from the method: the tilt jobs' blind at three tilts,
// each a one-evaluation job (the tilt fixed) with the jobs' sampling, once per pair of
// reflection limits (outdoor/indoor, -1 = unlimited; default: the jobs' defaults, then
// 30/5, the source publication's); its final check gives the one-stage value.
#include <sys/resource.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <string>
#include <thread>
#include <vector>

#include "bench/bench_util.h"
#include "core/common/json_proto.h"
#include "core/optimize/job.h"

namespace fenestra {
namespace {

double CpuSeconds() {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  return static_cast<double>(usage.ru_utime.tv_sec + usage.ru_stime.tv_sec) +
         1e-6 * static_cast<double>(usage.ru_utime.tv_usec + usage.ru_stime.tv_usec);
}

std::string DesignText(const google::protobuf::Map<std::string, double>& design) {
  std::string out;
  for (const char* name : {"alpha", "width", "spacing", "thickness"}) {
    if (const auto it = design.find(name); it != design.end()) {
      out += (out.empty() ? "" : ", ") + std::string(name) + " = " + std::to_string(it->second);
    }
  }
  return out;
}

// The check's numbers and times; `cpu_seconds` < 0: its wall time only.
void PrintCheck(const v1::FinalCheck& c, double cpu_seconds) {
  const unsigned threads = std::max(1u, std::thread::hardware_concurrency());
  const v1::Estimate& d = c.difference();
  std::printf(
      "  two-stage %.2f ± %.2f %%, one-stage %.2f ± %.2f %%, difference %+.2f ± %.2f %% (%.1f "
      "SE)%s;"
      " %lld paths per sensor%s (pilot %lld); wall %.2f s",
      c.two_stage().value(), c.two_stage().standard_error(), c.one_stage().value(),
      c.one_stage().standard_error(), d.value(), d.standard_error(),
      d.standard_error() > 0 ? std::abs(d.value()) / d.standard_error() : 0.0,
      c.disagrees() ? " DISAGREES" : "", static_cast<long long>(c.paths_per_sensor()),
      c.paths_limited() ? " (the most)" : "", static_cast<long long>(c.pilot_paths_per_sensor()),
      c.seconds());
  if (cpu_seconds >= 0) {
    std::printf(", CPU %.2f s, charged %.2f s", cpu_seconds,
                std::min(c.seconds(), cpu_seconds / threads));
  }
  std::printf("\n");
}

PreparedJob Prepare(const std::string& name, const std::string& backend, uint64_t seed) {
  const std::string dir = FENESTRA_SOURCE_DIR "/examples/city_office";
  v1::Job job = ValueOrExit(ReadJobFile(dir + "/" + name + ".json"));
  job.mutable_sampling()->set_backend(backend);
  job.mutable_sampling()->set_seed(seed);
  return ValueOrExit(PrepareJob(job, dir));
}

// Reflection limits of the two stages; 0 = the jobs' default.
struct Limits {
  int outdoor = 0, indoor = 0;
};

std::string LimitsText(const Limits& limits) {
  const auto text = [](int bounces) {
    return bounces == 0  ? std::string("the default")
           : bounces < 0 ? std::string("unlimited")
                         : std::to_string(bounces);
  };
  return "outdoor reflections " + text(limits.outdoor) + ", indoor " + text(limits.indoor);
}

// The two-stage value of alpha_max.json's blind at `alpha` with each pair of reflection
// limits, each with its final check and its CPU time.
void Split(const std::string& backend, const std::vector<Limits>& limits) {
  for (const double alpha : {0.1136, 0.8, 1.5707963267948966}) {
    for (const Limits& l : limits) {
      PreparedJob job = Prepare("alpha_max", backend, 1);
      v1::DesignVariable& tilt = *job.job.mutable_variables(0);
      tilt.set_start(alpha);
      tilt.set_fixed(true);
      v1::Sampling& sampling = *job.job.mutable_sampling();
      v1::Sampling defaults = ValueOrExit(ResolveSampling(v1::Sampling()));
      sampling.set_outdoor_bounces(l.outdoor != 0 ? l.outdoor : defaults.outdoor_bounces());
      sampling.set_indoor_bounces(l.indoor != 0 ? l.indoor : defaults.indoor_bounces());
      const double cpu = CpuSeconds();
      const v1::JobResult result = ValueOrExit(RunJob(job, nullptr));
      std::printf("alpha = %.4f, %s (%d/%d): job CPU %.2f s (outdoor stage %.2f s wall)\n", alpha,
                  LimitsText(l).c_str(), sampling.outdoor_bounces(), sampling.indoor_bounces(),
                  CpuSeconds() - cpu, result.timings().outdoor_seconds());
      PrintCheck(result.final_check(), -1);
    }
  }
}

// "OUTDOOR/INDOOR" (e.g. "30/-1"), or exits.
Limits ParseLimits(const std::string& text) {
  const size_t slash = text.find('/');
  if (slash == std::string::npos) {
    std::fprintf(stderr, "error: reflection limits must read OUTDOOR/INDOOR, got '%s'\n",
                 text.c_str());
    std::exit(2);
  }
  return {std::stoi(text.substr(0, slash)), std::stoi(text.substr(slash + 1))};
}

}  // namespace
}  // namespace fenestra

int main(int argc, char** argv) {
  using namespace fenestra;
  if (argc > 1 && std::string(argv[1]) == "split") {
    std::vector<Limits> limits;
    for (int i = 3; i < argc; ++i) limits.push_back(ParseLimits(argv[i]));
    if (limits.empty()) limits = {Limits{}, Limits{30, 5}};
    Split(argc > 2 ? argv[2] : "auto", limits);
    return 0;
  }
  const int seeds = argc > 1 ? std::max(1, std::atoi(argv[1])) : 1;
  const std::string backend = argc > 2 ? argv[2] : "auto";
  for (const char* name : {"alpha_max", "alpha_target", "alpha_width_target", "four_variables"}) {
    v1::JobResult stored;
    const std::string path =
        std::string(FENESTRA_SOURCE_DIR "/build/bench/experiment_") + name + "_cpu2.result.json";
    if (absl::Status s = ReadJsonProtoFile(path, "result", &stored); !s.ok()) {
      std::fprintf(stderr, "error: %s\n", std::string(s.message()).c_str());
      return 1;
    }
    std::printf("%s: best design %s\n", name, DesignText(stored.best_design()).c_str());
    for (int seed = 1; seed <= seeds; ++seed) {
      const PreparedJob job = Prepare(name, backend, static_cast<uint64_t>(seed));
      const double cpu = CpuSeconds();
      const v1::FinalCheck check =
          ValueOrExit(CheckJobDesign(job, stored.best_design(), stored.best_value()));
      PrintCheck(check, CpuSeconds() - cpu);
    }
  }

  // The quick job end to end
  const PreparedJob quick = Prepare("alpha_max_quick", backend, 1);
  const double cpu = CpuSeconds();
  const v1::JobResult result = ValueOrExit(RunJob(quick, nullptr));
  std::printf(
      "alpha_max_quick end to end: best design %s, %d evaluations, job wall %.2f s, "
      "CPU %.2f s\n",
      DesignText(result.best_design()).c_str(), result.evaluations(),
      result.timings().total_seconds(), CpuSeconds() - cpu);
  PrintCheck(result.final_check(), -1);
  return 0;
}
