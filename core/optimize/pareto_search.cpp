#include "core/optimize/pareto_search.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <map>
#include <utility>

#include "absl/strings/str_cat.h"
#include "core/common/seconds.h"
#include "core/common/status_macros.h"
#include "core/metrics/metric_errors.h"
#include "core/optimize/nsga2.h"

namespace fenestra {
namespace {

// `x` on the variables' grid and within their bounds; a fixed variable at its start.
std::vector<double> Snapped(const std::vector<double>& x, std::span<const DesignVariable> vars) {
  std::vector<double> out(x.size());
  for (size_t i = 0; i < x.size(); ++i) {
    const DesignVariable& v = vars[i];
    if (v.fixed) {
      out[i] = v.start;
      continue;
    }
    double value = std::clamp(x[i], v.lower, v.upper);
    if (v.step > 0) {
      value =
          std::clamp(v.lower + std::round((value - v.lower) / v.step) * v.step, v.lower, v.upper);
    }
    out[i] = value;
  }
  return out;
}

// An objective in the form NSGA-II minimizes.
double Minimized(const ParetoObjective& o, double value) { return o.maximize ? -value : value; }

Nsga2Member MemberOf(const ParetoOutcome& out, size_t step,
                     std::span<const ParetoObjective> objectives) {
  Nsga2Member m;
  m.x = out.search.history[step].x;
  for (size_t k = 0; k < objectives.size(); ++k) {
    m.objectives.push_back(Minimized(objectives[k], out.objectives[step][k].value));
    m.standard_errors.push_back(out.objectives[step][k].standard_error);
  }
  const VnsRecord& r = out.search.history[step];
  m.violation = r.feasible ? 0 : std::max(r.violation, 1e-12);
  return m;
}

// Whether step `a` is a better best than step `b`: feasible first, then the smaller violation,
// then the first objective.
bool BetterBest(const ParetoOutcome& out, const ParetoObjective& first, size_t a, size_t b) {
  const VnsRecord &ra = out.search.history[a], &rb = out.search.history[b];
  if (ra.feasible != rb.feasible) return ra.feasible;
  if (!ra.feasible && ra.violation != rb.violation) return ra.violation < rb.violation;
  return Minimized(first, out.objectives[a][0].value) <
         Minimized(first, out.objectives[b][0].value);
}

bool SameDesign(const std::vector<double>& a, const std::vector<double>& b) {
  if (a.size() != b.size()) return false;
  for (size_t i = 0; i < a.size(); ++i) {
    if (!(std::abs(a[i] - b[i]) <= 1e-9 * (1 + std::abs(a[i])))) return false;
  }
  return true;
}

// The search's moving parts beside its outcome.
struct ParetoRun {
  std::span<const DesignVariable> variables;
  const ParetoOptions& options;
  ParetoOutcome out;
  std::map<std::vector<double>, int> cache;  // design -> its evaluated step
  std::vector<int> archive;                  // steps no evaluated design dominates
  std::vector<Nsga2Member> archive_members;

  // Adds step `s` to the archive unless a member dominates it, dropping those it dominates.
  void Archive(int s) {
    const Nsga2Member m = MemberOf(out, s, options.objectives);
    for (const Nsga2Member& a : archive_members) {
      if (Dominates(a, m, options.dominance_z)) return;
    }
    for (size_t i = archive.size(); i-- > 0;) {
      if (Dominates(m, archive_members[i], options.dominance_z)) {
        archive.erase(archive.begin() + static_cast<std::ptrdiff_t>(i));
        archive_members.erase(archive_members.begin() + static_cast<std::ptrdiff_t>(i));
      }
    }
    archive.push_back(s);
    archive_members.push_back(m);
  }

  // The hypervolume of the archive's feasible members below the reference.
  double Hypervolume() const {
    std::vector<Nsga2Member> feasible;
    for (const Nsga2Member& m : archive_members) {
      if (m.violation == 0) feasible.push_back(m);
    }
    std::vector<double> reference;
    for (size_t k = 0; k < options.objectives.size(); ++k) {
      reference.push_back(Minimized(options.objectives[k], out.reference[k]));
    }
    return fenestra::Hypervolume(feasible, reference);
  }

  // The reference: the worst of each objective over the initial population.
  void SetReference(size_t steps) {
    out.reference.assign(options.objectives.size(), 0);
    for (size_t k = 0; k < options.objectives.size(); ++k) {
      double worst = -std::numeric_limits<double>::infinity();
      for (size_t s = 0; s < steps; ++s) {
        worst = std::max(worst, Minimized(options.objectives[k], out.objectives[s][k].value));
      }
      out.reference[k] = Minimized(options.objectives[k], worst);  // back to its own sign
    }
  }

  // Appends step `x` with `evaluation` (its objectives `values`).
  void AddStep(std::vector<double> x, Evaluation evaluation, std::vector<Estimated> values,
               bool cached, double seconds, double elapsed, int generation) {
    VnsRecord r;
    r.index = static_cast<int>(out.search.history.size());
    r.x = std::move(x);
    r.cached = cached;
    r.evaluation_seconds = seconds;
    r.elapsed_seconds = elapsed;
    r.neighborhood = -1;
    r.feasible = Feasible(options.constraints, evaluation);
    r.violation = ConstraintViolation(options.constraints.bounds, evaluation.constraints);
    r.score = Minimized(options.objectives[0], -values[0].value);  // maximized form
    r.evaluation = std::move(evaluation);
    out.search.history.push_back(std::move(r));
    out.objectives.push_back(std::move(values));
    out.generation.push_back(generation);
    const size_t s = out.search.history.size() - 1;
    VnsResult& search = out.search;
    if (s == 0 || BetterBest(out, options.objectives[0], s, search.best_index)) {
      search.history[s].improved = true;
      search.best_index = static_cast<int>(s);
      search.best_x = search.history[s].x;
      search.best = search.history[s].evaluation;
      search.best_score = search.history[s].score;
      if (s > 0) ++search.improvements;
    }
    if (cached) {
      ++search.cache_hits;
    } else {
      ++search.evaluations;
      search.evaluation_seconds += seconds;
    }
  }
};

absl::Status CheckParetoOptions(const ParetoOptions& o) {
  if (o.objectives.size() < 2 || o.objectives.size() > 3) {
    return absl::InvalidArgumentError(
        absl::StrCat("Pareto search: two or three objectives, got ", o.objectives.size()));
  }
  if (o.max_evaluations < o.population) {
    return absl::InvalidArgumentError(
        absl::StrCat("Pareto search: the budget of ", o.max_evaluations,
                     " evaluations is below one generation of ", o.population));
  }
  return absl::OkStatus();
}

}  // namespace

std::vector<Estimated> ObjectiveValues(const Evaluation& evaluation,
                                       std::span<const ParetoObjective> objectives) {
  std::vector<Estimated> out;
  const auto* metrics = std::any_cast<AnnualMetricsEstimate>(&evaluation.payload);
  for (const ParetoObjective& o : objectives) {
    if (metrics == nullptr) {
      out.push_back({evaluation.value, evaluation.standard_error});
    } else {
      out.push_back({SceneMetricValue(metrics->value.scene, o.metric),
                     SceneMetricValue(metrics->standard_error.scene, o.metric)});
    }
  }
  return out;
}

absl::StatusOr<ParetoOutcome> RunPareto(std::span<const DesignVariable> variables,
                                        const BatchObjective& objective,
                                        const ParetoOptions& options,
                                        const ParetoCallbacks& callbacks,
                                        const ParetoOutcome* resume) {
  FENESTRA_RETURN_IF_ERROR(CheckParetoOptions(options));
  std::vector<double> lower, upper;
  for (const DesignVariable& v : variables) {
    lower.push_back(v.fixed ? v.start : v.lower);
    upper.push_back(v.fixed ? v.start : v.upper);
  }
  Nsga2Options nsga;
  nsga.population = options.population;
  nsga.dominance_z = options.dominance_z;
  nsga.seed = options.seed;
  FENESTRA_ASSIGN_OR_RETURN(
      search, Nsga2::Make(lower, upper, static_cast<int>(options.objectives.size()), nsga));
  ParetoRun run{variables, options, {}, {}, {}, {}};
  const size_t resumed = resume != nullptr ? resume->search.history.size() : 0;
  const double clock_offset = resume != nullptr ? resume->search.elapsed_seconds : 0;
  const auto start = std::chrono::steady_clock::now();
  const auto elapsed = [&] { return clock_offset + SecondsSince(start); };
  StopReason stop = StopReason::kEvaluationBudget;
  const size_t n = static_cast<size_t>(options.population);
  while (run.out.search.history.size() + n <= static_cast<size_t>(options.max_evaluations)) {
    const size_t first = run.out.search.history.size();
    const bool replaying = first < resumed;
    if (!replaying && callbacks.cancelled && callbacks.cancelled()) {
      stop = StopReason::kCancelled;
      break;
    }
    if (!replaying && options.max_seconds > 0 && elapsed() >= options.max_seconds) {
      stop = StopReason::kTimeBudget;
      break;
    }
    std::vector<std::vector<double>> designs;
    for (const std::vector<double>& x : search.Ask()) designs.push_back(Snapped(x, variables));
    // Each design: from the resumed history, the cache (or an earlier twin), or evaluated now
    std::vector<int> twin(n, -1);
    std::vector<std::vector<double>> to_evaluate;
    std::vector<int> slot(n, -1);
    std::map<std::vector<double>, int> fresh;    // design -> its index in to_evaluate
    std::map<std::vector<double>, int> earlier;  // design -> its resumed step, this generation
    for (size_t k = 0; k < n; ++k) {
      if (first + k < resumed) {
        const VnsRecord& r = resume->search.history[first + k];
        if (!SameDesign(r.x, designs[k])) {
          return absl::InvalidArgumentError(
              absl::StrCat("Pareto search: step ", first + k,
                           " of the history is not the design this search "
                           "proposes there"));
        }
        designs[k] = r.x;
        if (!r.cached) earlier.emplace(designs[k], static_cast<int>(first + k));
        continue;
      }
      if (const auto hit = run.cache.find(designs[k]); hit != run.cache.end()) {
        twin[k] = hit->second;
      } else if (const auto before = earlier.find(designs[k]); before != earlier.end()) {
        twin[k] = before->second;
      } else if (const auto again = fresh.find(designs[k]); again != fresh.end()) {
        slot[k] = again->second;
      } else {
        slot[k] = static_cast<int>(to_evaluate.size());
        fresh[designs[k]] = slot[k];
        to_evaluate.push_back(designs[k]);
      }
    }
    if (first + n > resumed && !objective) break;  // the replay's end
    std::vector<absl::StatusOr<Evaluation>> evaluated;
    double share = 0;
    if (!to_evaluate.empty()) {
      const auto batch_start = std::chrono::steady_clock::now();
      evaluated = objective(to_evaluate);
      share = SecondsSince(batch_start) / static_cast<double>(to_evaluate.size());
      for (size_t e = 0; e < evaluated.size(); ++e) {
        if (!evaluated[e].ok()) {
          return absl::Status(evaluated[e].status().code(),
                              absl::StrCat("design ", e, " of generation ", run.out.generations,
                                           ": ", evaluated[e].status().message()));
        }
      }
    }
    std::vector<bool> first_of_slot(to_evaluate.size(), true);
    for (size_t k = 0; k < n; ++k) {
      const size_t step = first + k;
      if (step < resumed) {
        const VnsRecord& r = resume->search.history[step];
        run.AddStep(r.x, r.evaluation, resume->objectives[step], r.cached, r.evaluation_seconds,
                    r.elapsed_seconds, run.out.generations);
      } else if (twin[k] >= 0 || !first_of_slot[slot[k]]) {
        const int of = twin[k] >= 0 ? twin[k] : run.cache.at(designs[k]);
        const VnsRecord r = run.out.search.history[of];
        run.AddStep(designs[k], r.evaluation, run.out.objectives[of], true, 0, elapsed(),
                    run.out.generations);
      } else {
        first_of_slot[slot[k]] = false;
        Evaluation e = *evaluated[slot[k]];
        std::vector<Estimated> values = ObjectiveValues(e, options.objectives);
        for (const Estimated& v : values) {
          if (!std::isfinite(v.value) || !std::isfinite(v.standard_error)) {
            return absl::InvalidArgumentError(
                absl::StrCat("Pareto search: step ", step, " has an objective that is not finite"));
          }
        }
        run.AddStep(designs[k], std::move(e), std::move(values), false, share, elapsed(),
                    run.out.generations);
      }
      if (!run.out.search.history.back().cached) run.cache.emplace(designs[k], step);
      if (step >= resumed && callbacks.step) {
        run.out.search.elapsed_seconds = run.out.search.history.back().elapsed_seconds;
        callbacks.step(run.out);
      }
    }
    // The generation told, archived and measured
    std::vector<std::vector<double>> told, errors;
    std::vector<double> violations;
    for (size_t k = 0; k < n; ++k) {
      const Nsga2Member m = MemberOf(run.out, first + k, options.objectives);
      told.push_back(m.objectives);
      errors.push_back(m.standard_errors);
      violations.push_back(m.violation);
      if (!run.out.search.history[first + k].cached) run.Archive(static_cast<int>(first + k));
    }
    FENESTRA_RETURN_IF_ERROR(search.Tell(told, errors, violations));
    if (run.out.generations == 0) run.SetReference(n);
    run.out.hypervolume.push_back(run.Hypervolume());
    ++run.out.generations;
  }
  if (run.out.search.history.empty() && stop != StopReason::kCancelled) {
    return absl::InvalidArgumentError("Pareto search: no generation fits the budget");
  }
  run.out.front = run.archive;
  std::sort(run.out.front.begin(), run.out.front.end(), [&](int a, int b) {
    return Minimized(options.objectives[0], run.out.objectives[a][0].value) <
           Minimized(options.objectives[0], run.out.objectives[b][0].value);
  });
  run.out.search.stop_reason = stop;
  run.out.search.elapsed_seconds = elapsed();
  return std::move(run.out);
}

}  // namespace fenestra
