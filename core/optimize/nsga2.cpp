#include "core/optimize/nsga2.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <sstream>

#include "absl/strings/str_cat.h"

namespace fenestra {
namespace {

using Engine = std::mt19937_64;

// U[0, 1) from the top 53 bits, by fixed bit arithmetic (no std:: distributions), so that a
// seed gives the same search on every standard library.
double Uniform(Engine& engine) { return static_cast<double>(engine() >> 11) * 0x1p-53; }

Engine EngineOf(const std::string& state) {
  Engine engine;
  std::istringstream in(state);
  in >> engine;
  return engine;
}

std::string StateOf(const Engine& engine) {
  std::ostringstream out;
  out << engine;
  return out.str();
}

// The spread factor of simulated binary crossover for a child `room` away from a bound, in
// units of the parents' distance.
double SbxBeta(double u, double room, double eta) {
  const double beta = 1 + 2 * room;
  const double alpha = 2 - std::pow(beta, -(eta + 1));
  return u <= 1 / alpha ? std::pow(u * alpha, 1 / (eta + 1))
                        : std::pow(1 / (2 - u * alpha), 1 / (eta + 1));
}

// Simulated binary crossover of `a` and `b` within [lower, upper], each variable with
// probability 1/2 (Deb & Agrawal's bounded form).
void Crossover(std::vector<double>& a, std::vector<double>& b, const Nsga2State& s,
               Engine& engine) {
  for (size_t i = 0; i < a.size(); ++i) {
    if (Uniform(engine) > 0.5 || std::abs(a[i] - b[i]) < 1e-14) continue;
    const double lo = s.lower[i], hi = s.upper[i];
    const double y1 = std::min(a[i], b[i]), y2 = std::max(a[i], b[i]);
    const double u = Uniform(engine);
    const double eta = s.options.crossover_eta;
    double c1 = 0.5 * ((y1 + y2) - SbxBeta(u, (y1 - lo) / (y2 - y1), eta) * (y2 - y1));
    double c2 = 0.5 * ((y1 + y2) + SbxBeta(u, (hi - y2) / (y2 - y1), eta) * (y2 - y1));
    c1 = std::clamp(c1, lo, hi);
    c2 = std::clamp(c2, lo, hi);
    if (Uniform(engine) <= 0.5) std::swap(c1, c2);
    a[i] = c1;
    b[i] = c2;
  }
}

// Polynomial mutation of `x` within [lower, upper] (Deb's bounded form).
void Mutate(std::vector<double>& x, const Nsga2State& s, Engine& engine) {
  const double p = s.options.mutation_probability > 0 ? s.options.mutation_probability
                                                      : 1.0 / static_cast<double>(x.size());
  const double eta = s.options.mutation_eta, power = 1 / (eta + 1);
  for (size_t i = 0; i < x.size(); ++i) {
    if (Uniform(engine) > p) continue;
    const double lo = s.lower[i], hi = s.upper[i];
    if (!(hi > lo)) continue;
    const double d1 = (x[i] - lo) / (hi - lo), d2 = (hi - x[i]) / (hi - lo);
    const double u = Uniform(engine);
    double dq;
    if (u < 0.5) {
      const double v = 2 * u + (1 - 2 * u) * std::pow(1 - d1, eta + 1);
      dq = std::pow(v, power) - 1;
    } else {
      const double v = 2 * (1 - u) + 2 * (u - 0.5) * std::pow(1 - d2, eta + 1);
      dq = 1 - std::pow(v, power);
    }
    x[i] = std::clamp(x[i] + dq * (hi - lo), lo, hi);
  }
}

// The better of two members by rank, then crowding; a tie is drawn.
const Nsga2Member& Tournament(const std::vector<Nsga2Member>& p, Engine& engine) {
  const auto pick = [&] {
    return std::min(p.size() - 1,
                    static_cast<size_t>(Uniform(engine) * static_cast<double>(p.size())));
  };
  const Nsga2Member& a = p[pick()];
  const Nsga2Member& b = p[pick()];
  if (a.rank != b.rank) return a.rank < b.rank ? a : b;
  if (a.crowding != b.crowding) return a.crowding > b.crowding ? a : b;
  return Uniform(engine) < 0.5 ? a : b;
}

// The next designs: offspring of the population, or the first population.
std::vector<std::vector<double>> NextDesigns(const Nsga2State& s, Engine& engine) {
  std::vector<std::vector<double>> designs;
  const int n = s.options.population;
  if (s.population.empty()) {
    for (int k = 0; k < n; ++k) {
      std::vector<double> x(s.lower.size());
      for (size_t i = 0; i < x.size(); ++i) {
        x[i] = s.lower[i] + Uniform(engine) * (s.upper[i] - s.lower[i]);
      }
      designs.push_back(std::move(x));
    }
    return designs;
  }
  while (static_cast<int>(designs.size()) < n) {
    std::vector<double> a = Tournament(s.population, engine).x;
    std::vector<double> b = Tournament(s.population, engine).x;
    if (Uniform(engine) <= s.options.crossover_probability) Crossover(a, b, s, engine);
    Mutate(a, s, engine);
    Mutate(b, s, engine);
    designs.push_back(std::move(a));
    designs.push_back(std::move(b));
  }
  return designs;
}

bool BetterForNext(const Nsga2Member& a, const Nsga2Member& b) {
  if (a.rank != b.rank) return a.rank < b.rank;
  return a.crowding > b.crowding;
}

}  // namespace

bool Dominates(const Nsga2Member& a, const Nsga2Member& b, double z) {
  // Deb's constrained dominance: the smaller violation first
  if (a.violation > 0 || b.violation > 0) return a.violation < b.violation;
  bool better = false;
  for (size_t k = 0; k < a.objectives.size(); ++k) {
    const double ea = a.standard_errors.empty() ? 0 : a.standard_errors[k];
    const double eb = b.standard_errors.empty() ? 0 : b.standard_errors[k];
    const double margin = z * std::hypot(ea, eb);
    const double d = b.objectives[k] - a.objectives[k];       // > 0: a is better
    if (d < -margin || (margin == 0 && d < 0)) return false;  // a worse beyond the error
    if (d > margin) better = true;
  }
  return better;
}

void RankAndCrowd(std::vector<Nsga2Member>& members, double z) {
  const size_t n = members.size();
  std::vector<std::vector<size_t>> dominated(n);
  std::vector<int> count(n, 0);
  std::vector<size_t> front;
  for (size_t i = 0; i < n; ++i) {
    for (size_t j = 0; j < n; ++j) {
      if (i == j) continue;
      if (Dominates(members[i], members[j], z)) {
        dominated[i].push_back(j);
      } else if (Dominates(members[j], members[i], z)) {
        ++count[i];
      }
    }
    if (count[i] == 0) front.push_back(i);
  }
  for (int rank = 0; !front.empty(); ++rank) {
    std::vector<size_t> next;
    for (const size_t i : front) {
      members[i].rank = rank;
      members[i].crowding = 0;
      for (const size_t j : dominated[i]) {
        if (--count[j] == 0) next.push_back(j);
      }
    }
    // Crowding within the front: boundary members infinite, the rest the normalized sides
    // of the cuboid their neighbours span
    const size_t objectives = members[front[0]].objectives.size();
    for (size_t k = 0; k < objectives; ++k) {
      std::sort(front.begin(), front.end(), [&](size_t a, size_t b) {
        return members[a].objectives[k] < members[b].objectives[k];
      });
      const double lo = members[front.front()].objectives[k];
      const double hi = members[front.back()].objectives[k];
      members[front.front()].crowding = members[front.back()].crowding =
          std::numeric_limits<double>::infinity();
      if (!(hi > lo)) continue;
      for (size_t m = 1; m + 1 < front.size(); ++m) {
        members[front[m]].crowding +=
            (members[front[m + 1]].objectives[k] - members[front[m - 1]].objectives[k]) / (hi - lo);
      }
    }
    front = std::move(next);
  }
}

absl::StatusOr<Nsga2> Nsga2::Make(std::vector<double> lower, std::vector<double> upper,
                                  int objectives, const Nsga2Options& options) {
  if (lower.empty() || lower.size() != upper.size()) {
    return absl::InvalidArgumentError(
        absl::StrCat("NSGA-II: ", lower.size(), " lower and ", upper.size(), " upper bounds"));
  }
  for (size_t i = 0; i < lower.size(); ++i) {
    if (!(std::isfinite(lower[i]) && std::isfinite(upper[i]) && lower[i] <= upper[i])) {
      return absl::InvalidArgumentError(
          absl::StrCat("NSGA-II: variable ", i, " has bounds [", lower[i], ", ", upper[i], "]"));
    }
  }
  if (objectives < 2) {
    return absl::InvalidArgumentError(
        absl::StrCat("NSGA-II needs at least 2 objectives, got ", objectives));
  }
  if (options.population < 4 || options.population % 2 != 0) {
    return absl::InvalidArgumentError(absl::StrCat(
        "NSGA-II: the population must be even and at least 4, got ", options.population));
  }
  for (const double p : {options.crossover_probability, options.mutation_probability}) {
    if (!(p >= 0 && p <= 1)) {
      return absl::InvalidArgumentError(absl::StrCat("NSGA-II: probability ", p));
    }
  }
  if (!(options.crossover_eta >= 0 && options.mutation_eta >= 0 && options.dominance_z >= 0)) {
    return absl::InvalidArgumentError("NSGA-II: distribution indices and z must be >= 0");
  }
  Nsga2State state;
  state.lower = std::move(lower);
  state.upper = std::move(upper);
  state.objectives = objectives;
  state.options = options;
  Engine engine(options.seed);
  state.asked = NextDesigns(state, engine);
  state.random = StateOf(engine);
  return Nsga2(std::move(state));
}

absl::StatusOr<Nsga2> Nsga2::Restore(const Nsga2State& state) {
  absl::StatusOr<Nsga2> made = Make(state.lower, state.upper, state.objectives, state.options);
  if (!made.ok()) return made.status();
  if (state.asked.size() != static_cast<size_t>(state.options.population)) {
    return absl::InvalidArgumentError("NSGA-II: a saved state must await a whole generation");
  }
  return Nsga2(state);
}

const std::vector<std::vector<double>>& Nsga2::Ask() { return state_.asked; }

absl::Status Nsga2::Tell(const std::vector<std::vector<double>>& objectives,
                         const std::vector<std::vector<double>>& standard_errors,
                         const std::vector<double>& violations) {
  if (objectives.size() != state_.asked.size() ||
      (!standard_errors.empty() && standard_errors.size() != objectives.size()) ||
      (!violations.empty() && violations.size() != objectives.size())) {
    return absl::InvalidArgumentError(absl::StrCat("NSGA-II: ", objectives.size(),
                                                   " objective vectors for ", state_.asked.size(),
                                                   " designs asked"));
  }
  std::vector<Nsga2Member> told;
  for (size_t d = 0; d < objectives.size(); ++d) {
    const std::vector<double> none;
    const std::vector<double>& errors = standard_errors.empty() ? none : standard_errors[d];
    if (objectives[d].size() != static_cast<size_t>(state_.objectives) ||
        (!errors.empty() && errors.size() != objectives[d].size())) {
      return absl::InvalidArgumentError(absl::StrCat("NSGA-II: design ", d, " has ",
                                                     objectives[d].size(), " objectives, not ",
                                                     state_.objectives));
    }
    for (size_t k = 0; k < objectives[d].size(); ++k) {
      if (!std::isfinite(objectives[d][k]) || (!errors.empty() && !(errors[k] >= 0))) {
        return absl::InvalidArgumentError(
            absl::StrCat("NSGA-II: design ", d, " objective ", k, " is ", objectives[d][k]));
      }
    }
    const double violation = violations.empty() ? 0 : violations[d];
    if (!(violation >= 0) || !std::isfinite(violation)) {
      return absl::InvalidArgumentError(
          absl::StrCat("NSGA-II: design ", d, " has the violation ", violation));
    }
    told.push_back({state_.asked[d], objectives[d], errors, 0, 0, violation});
  }
  const bool first = state_.population.empty();
  std::vector<Nsga2Member> all = std::move(state_.population);
  all.insert(all.end(), told.begin(), told.end());
  RankAndCrowd(all, state_.options.dominance_z);
  std::stable_sort(all.begin(), all.end(), BetterForNext);
  all.resize(state_.options.population);
  RankAndCrowd(all, state_.options.dominance_z);
  state_.population = std::move(all);
  if (!first) ++state_.generation;
  Engine engine = EngineOf(state_.random);
  state_.asked = NextDesigns(state_, engine);
  state_.random = StateOf(engine);
  return absl::OkStatus();
}

std::vector<Nsga2Member> Nsga2::Front() const {
  std::vector<Nsga2Member> front;
  for (const Nsga2Member& m : state_.population) {
    if (m.rank == 0) front.push_back(m);
  }
  std::sort(front.begin(), front.end(), [](const Nsga2Member& a, const Nsga2Member& b) {
    return a.objectives[0] < b.objectives[0];
  });
  return front;
}

Nsga2State Nsga2::Save() const { return state_; }

double Hypervolume2d(const std::vector<Nsga2Member>& front, double reference_0,
                     double reference_1) {
  std::vector<std::pair<double, double>> points;
  for (const Nsga2Member& m : front) {
    if (m.objectives[0] < reference_0 && m.objectives[1] < reference_1) {
      points.push_back({m.objectives[0], m.objectives[1]});
    }
  }
  std::sort(points.begin(), points.end());
  double volume = 0, lowest = reference_1;
  for (const auto& [f0, f1] : points) {
    if (f1 >= lowest) continue;
    volume += (reference_0 - f0) * (lowest - f1);
    lowest = f1;
  }
  return volume;
}

double Hypervolume(const std::vector<Nsga2Member>& front, const std::vector<double>& reference) {
  if (reference.size() == 2) return Hypervolume2d(front, reference[0], reference[1]);
  if (reference.size() != 3) return 0;
  // Slices along the third objective: between consecutive levels, the area the members at or
  // below the level dominate in the first two
  std::vector<const Nsga2Member*> inside;
  for (const Nsga2Member& m : front) {
    if (m.objectives[0] < reference[0] && m.objectives[1] < reference[1] &&
        m.objectives[2] < reference[2]) {
      inside.push_back(&m);
    }
  }
  std::sort(inside.begin(), inside.end(), [](const Nsga2Member* a, const Nsga2Member* b) {
    return a->objectives[2] < b->objectives[2];
  });
  double volume = 0;
  std::vector<Nsga2Member> below;
  for (size_t i = 0; i < inside.size(); ++i) {
    below.push_back(*inside[i]);
    const double next = i + 1 < inside.size() ? inside[i + 1]->objectives[2] : reference[2];
    const double thickness = next - inside[i]->objectives[2];
    if (thickness > 0) volume += thickness * Hypervolume2d(below, reference[0], reference[1]);
  }
  return volume;
}

}  // namespace fenestra
