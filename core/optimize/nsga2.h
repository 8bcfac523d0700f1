#pragma once

// NSGA-II (Deb, Pratap, Agarwal & Meyarivan 2002), the population method of multi-objective
// search: a population of designs, each generation's offspring made by binary tournament on
// (front rank, crowding distance), simulated binary crossover and polynomial mutation, and the
// next population the best of parents and offspring by non-dominated sorting and crowding.
// Every objective is minimized. Objectives may carry standard errors: a design dominates
// another only when it is no worse in every objective and better in one beyond `z` combined
// standard errors (the error bars of a front of Monte Carlo estimates); with errors 0 this is
// the usual dominance.
//
// Ask/tell: Ask() gives the designs to evaluate next (the initial population, then each
// generation's offspring), Tell() takes their objectives. The whole state is plain data
// (Nsga2State): a search saved between Ask and Tell and restored goes on as the same search.
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "absl/status/statusor.h"

namespace fenestra {

struct Nsga2Options {
  int population = 40;  // even, at least 4
  double crossover_probability = 0.9;
  double crossover_eta = 15;  // SBX distribution index
  double mutation_eta = 20;   // polynomial mutation's
  // Each variable mutates with this probability; 0 = 1 / variables.
  double mutation_probability = 0;
  double dominance_z = 0;  // standard errors a difference must exceed to dominate
  uint64_t seed = 1;
};

struct Nsga2Member {
  std::vector<double> x;
  std::vector<double> objectives, standard_errors;
  int rank = 0;  // 0 = the first front
  double crowding = 0;
  // How far the design breaks its constraints (0: feasible); a smaller violation dominates
  // (Deb's constrained dominance), objectives decide between feasible designs.
  double violation = 0;
};

// Everything a search is, to save and restore.
struct Nsga2State {
  std::vector<double> lower, upper;
  int objectives = 0;
  Nsga2Options options;
  std::vector<Nsga2Member> population;     // evaluated
  std::vector<std::vector<double>> asked;  // awaiting Tell
  int generation = 0;                      // generations of offspring told
  std::string random;                      // the generator's state
};

class Nsga2 {
 public:
  // A search over the box [lower, upper] with `objectives` objectives (at least 2).
  // InvalidArgument for bounds that are not finite, not ordered or of different lengths, an odd
  // or too small population, or probabilities outside [0, 1].
  static absl::StatusOr<Nsga2> Make(std::vector<double> lower, std::vector<double> upper,
                                    int objectives, const Nsga2Options& options);
  static absl::StatusOr<Nsga2> Restore(const Nsga2State& state);

  // The designs to evaluate next (the same ones again until Tell).
  const std::vector<std::vector<double>>& Ask();
  // Their objectives (and standard errors, or none; constraint violations, or none), in Ask's
  // order. InvalidArgument for counts that do not match or values that are not finite.
  absl::Status Tell(const std::vector<std::vector<double>>& objectives,
                    const std::vector<std::vector<double>>& standard_errors = {},
                    const std::vector<double>& violations = {});

  // The population's first front (rank 0), by its first objective.
  std::vector<Nsga2Member> Front() const;
  const std::vector<Nsga2Member>& Population() const { return state_.population; }
  int Generation() const { return state_.generation; }
  Nsga2State Save() const;

 private:
  explicit Nsga2(Nsga2State state) : state_(std::move(state)) {}
  Nsga2State state_;
};

// Whether `a` dominates `b` (minimizing), beyond `z` combined standard errors.
bool Dominates(const Nsga2Member& a, const Nsga2Member& b, double z);

// Sets each member's rank and crowding distance (fast non-dominated sort, then crowding within
// each front).
void RankAndCrowd(std::vector<Nsga2Member>& members, double z);

// The hypervolume a two-objective front (minimizing) dominates below `reference`; members
// beyond the reference in either objective count for nothing.
double Hypervolume2d(const std::vector<Nsga2Member>& front, double reference_0, double reference_1);

// The hypervolume of a front of two or three objectives below `reference` (one value per
// objective; 0 for another count).
double Hypervolume(const std::vector<Nsga2Member>& front, const std::vector<double>& reference);

}  // namespace fenestra
