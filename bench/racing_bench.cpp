// Racing (core/optimize/racing.h) on the four city-office experiments: each run without
// racing, with racing's default settings, and with other rounds and thresholds under the
// audit (every candidate racing stops is traced to the end too, and compared with the
// incumbent it raced against). Prints per run: evaluations, the search's time and mean
// evaluation, the best design and value, and racing's counts.
//
//   racing_bench [BACKEND] [EXPERIMENTS] [quick]
// BACKEND: auto (default), cpu or cuda; EXPERIMENTS: comma-separated (default all four);
// quick: only without racing and with racing's defaults.
#include <chrono>
#include <cstdio>
#include <string>
#include <vector>

#include "absl/strings/str_split.h"
#include "bench/bench_util.h"
#include "core/common/seconds.h"
#include "core/optimize/job.h"

using namespace fenestra;

namespace {

const std::string kRoot = FENESTRA_SOURCE_DIR;

struct Variant {
  std::string name;
  bool racing = true;
  bool audit = false;
  std::vector<int> rounds;     // empty: the default
  double standard_errors = 0;  // 0: the default
};

void Run(const PreparedJob& base, const OutdoorMatrix& outdoor, const Variant& v) {
  PreparedJob job = base;
  v1::Sampling& s = *job.job.mutable_sampling();
  s.set_racing(v.racing);
  s.set_racing_audit(v.audit);
  if (!v.rounds.empty()) {
    s.clear_racing_rounds();
    for (const int r : v.rounds) s.add_racing_rounds(r);
  }
  if (v.standard_errors > 0) s.set_racing_standard_errors(v.standard_errors);
  const auto start = std::chrono::steady_clock::now();
  const v1::JobResult r = ValueOrExit(RunJob(job, &outdoor));
  const double wall = SecondsSince(start);
  std::printf(
      "  %-22s %3d evaluations, job %.2f s, evaluations %.3f s (mean %.2f ms); best %.2f ± %.2f %% "
      "at",
      v.name.c_str(), r.evaluations(), wall, r.timings().evaluation_seconds(),
      1e3 * r.timings().evaluation_seconds() / std::max(1, r.evaluations()), r.best_value().value(),
      r.best_value().standard_error());
  for (const v1::DesignVariable& variable : job.job.variables()) {
    std::printf(" %s=%.4f", variable.name().c_str(), r.best_design().at(variable.name()));
  }
  std::printf("\n");
  if (!r.has_racing()) return;
  const v1::Racing& racing = r.racing();
  std::printf("  %-22s rounds", "");
  for (const double f : racing.round_fractions()) std::printf(" %.3f", f);
  std::printf(", k %.1f: %d candidates, raced out", racing.standard_errors(), racing.candidates());
  for (const int n : racing.raced_out()) std::printf(" %d", n);
  std::printf("; paths traced %.1f%%, rays %.3g traced, %.3g saved", 100 * racing.paths_fraction(),
              static_cast<double>(racing.rays_traced()), static_cast<double>(racing.rays_saved()));
  if (v.audit) {
    std::printf("; audit: %d stopped, %d would have improved, %d by more than their error",
                racing.audited(), racing.audited_would_improve(),
                racing.audited_better_beyond_error());
  }
  std::printf("\n");
}

}  // namespace

int main(int argc, char** argv) {
  const std::string backend = argc > 1 ? argv[1] : "auto";
  std::vector<std::string> experiments = {"alpha_max", "alpha_target", "alpha_width_target",
                                          "four_variables"};
  if (argc > 2) experiments = absl::StrSplit(argv[2], ',');
  const bool quick = argc > 3 && std::string(argv[3]) == "quick";
  std::vector<Variant> variants = {
      {"no racing", false, false, {}, 0},
      {"racing", true, false, {}, 0},
      {"racing (audit)", true, true, {}, 0},
      {"rounds 1, k 3 (audit)", true, true, {1}, 3},
      {"rounds 1 2, k 3 (audit)", true, true, {1, 2}, 3},
      {"rounds 2, k 4 (audit)", true, true, {2}, 4},
      {"rounds 1 2 4, k 4 (audit)", true, true, {1, 2, 4}, 4},
  };
  if (quick) variants.resize(2);
  for (const std::string& name : experiments) {
    v1::Job job = ValueOrExit(ReadJobFile(kRoot + "/examples/city_office/" + name + ".json"));
    job.mutable_sampling()->set_backend(backend);
    job.mutable_sampling()->set_final_check(false);
    const PreparedJob prepared = ValueOrExit(PrepareJob(job, kRoot + "/examples/city_office"));
    const OutdoorMatrix outdoor =
        ValueOrExit(ComputeOutdoorMatrix(prepared.scene, prepared.job.sampling()));
    std::printf("%s (%s), outdoor matrix %.2f s on %s\n", name.c_str(), job.name().c_str(),
                outdoor.wall_seconds, outdoor.backend.c_str());
    for (const Variant& v : variants) Run(prepared, outdoor, v);
    std::fflush(stdout);
  }
  return 0;
}
