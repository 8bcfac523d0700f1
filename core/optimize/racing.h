// Racing (after Maron & Moore, "Hoeffding races", NIPS 1993): a candidate design is traced
// in rounds, and after each round but the last its paired difference to the incumbent is
// tested; a candidate clearly worse is rejected there, with only part of its paths traced.
//
// Round r traces the first rounds[r] of kDesignParts parts of every batch's paths (dc_backend.h),
// so every round keeps the B paired, independent batches, and the jackknife over them
// (metric_errors.h) gives the standard error of the difference: version 0 of each design is
// the mean of its batches, version 1 + b the mean without batch b; the difference of the
// designs' scores per version is a jackknife sample of the difference. All designs use the
// same random numbers (common random numbers), so most of the noise cancels in the
// difference and a small share of the paths decides most candidates. A candidate that is not
// rejected is traced to the end: every value the search may accept has full precision.
//
// With constraints (VnsOptions::constraints) a round rejects only where the incumbent is
// feasible: by the paired difference (a worse objective loses to a feasible incumbent
// whatever the candidate's feasibility), or where the candidate breaks a constraint by more
// than RacingSettings::standard_errors of its standard errors at that round (it would be
// infeasible). Against an infeasible incumbent no round rejects (RoundRejects).
#pragma once

#include <cstdint>
#include <memory>
#include <optional>
#include <span>
#include <vector>

#include "absl/status/statusor.h"
#include "core/common/thread_pool.h"
#include "core/dc/dc_backend.h"
#include "core/metrics/annual_metrics.h"
#include "core/optimize/comfort.h"
#include "core/optimize/vns.h"

namespace fenestra {

// The rounds and the test (bench/README.md, "Racing", for how they were chosen).
struct RacingSettings {
  // Parts of kDesignParts traced by the end of each round but the last (increasing, each
  // below kDesignParts); the last round traces all.
  std::vector<int> rounds = {1, 2};
  // A candidate is rejected after a round when its paired difference to the incumbent is
  // below -standard_errors times the difference's standard error.
  double standard_errors = 4;
};

// The limits of RacingSettings::standard_errors.
inline constexpr double kMinRacingStandardErrors = 2;
inline constexpr double kMaxRacingStandardErrors = 100;

// The paired difference of a candidate's and the incumbent's scores after one round: the
// difference of version 0, and the jackknife standard error of the versions' differences.
struct PairedDifference {
  double difference = 0;
  double standard_error = 0;
};

// From the scores of each version of two designs (equal sizes, >= 3).
PairedDifference Paired(std::span<const double> candidate, std::span<const double> incumbent);

// Whether `difference` (candidate - incumbent, in scores) rejects the candidate.
bool Rejects(const PairedDifference& difference, const RacingSettings& settings);

// Whether a round rejects a candidate whose scores per version are `candidate` and whose
// constraints' values at the round are `constraints` (Evaluation::constraints), against an
// incumbent with `incumbent` scores at the same round: never where the incumbent is
// infeasible; else by the paired difference (Rejects), or where the candidate breaks one of
// `bounds` by more than settings.standard_errors of its standard errors.
bool RoundRejects(std::span<const double> candidate, std::span<const Estimated> constraints,
                  std::span<const double> incumbent, bool incumbent_feasible,
                  std::span<const Constraint> bounds, const RacingSettings& settings);

// A design's scores per version after each round but the last: rounds[r][v].
using RoundScores = std::vector<std::vector<double>>;

// What racing did over a search.
struct RacingStats {
  int candidates = 0;         // designs evaluated in rounds against an incumbent
  std::vector<int> rejected;  // per round but the last: candidates rejected there
  // Over every evaluation, an incumbent's rounds traced again after a resume included, the
  // audit's tracing not
  int64_t parts_traced = 0;
  int64_t parts_in_full = 0;       // what tracing each evaluation in full would have cost
  uint64_t rays_traced = 0;        // closest-hit queries, as parts_traced
  int rejected_audited = 0;        // rejected candidates also traced in full (audit)
  int rejected_would_improve = 0;  // of them, those a full evaluation would have accepted
  // Of them, those a full evaluation finds better than the incumbent by more than the
  // standard error of the paired difference
  int rejected_better_beyond_error = 0;
};

// The objective of a search in rounds over one or more DesignTallies of the same job (lanes:
// each on its own GPU, say). Evaluate traces a design in rounds, rejecting it after a round
// where it is clearly worse than the incumbent (set by SetIncumbent from the search's
// steps); without an incumbent, or with racing off, it is traced in full (its round scores
// still kept, so it can serve as the incumbent). EvaluateBatch evaluates several designs at
// once, spread over the lanes, each as Evaluate would against the same incumbent; without
// racing a lane traces its designs DesignTallies::DesignsAtOnce() at a time.
class Racer {
 public:
  struct Setting {
    std::vector<DesignTallies*> lanes;  // at least one
    MetricOptions options;
    int analysed_hours = 0;
    SceneMetric metric = SceneMetric::kUdiMean;
    Objective objective;
    // The search's constraints (VnsOptions::constraints), and the metric of each bound.
    Constraints constraints = {};
    std::vector<SceneMetric> constraint_metrics = {};
    RacingSettings racing;
    bool enabled = true;  // false: every design in one round
    // Trace rejected candidates to the end too, and count those a full evaluation would
    // have accepted (RacingStats::rejected_would_improve); their result stays the rejection.
    bool audit = false;
    // Per lane, the comfort metrics of its designs (core/optimize/comfort.h), or empty for
    // none; where set, racing must be off (the rounds do not give them). `comfort_beside`:
    // taken while the lane traces the designs (on a GPU, whose host thread waits), else after.
    std::vector<DesignComfort*> comfort = {};
    bool comfort_beside = false;
  };
  explicit Racer(Setting setting);
  ~Racer();

  // The evaluation of `design` (payload: AnnualMetricsEstimate); `partial` when rejected.
  absl::StatusOr<Evaluation> Evaluate(const BlindDesign& design);
  // The evaluations of `designs` in their order, the lanes tracing at once.
  std::vector<absl::StatusOr<Evaluation>> EvaluateBatch(const std::vector<BlindDesign>& designs);
  // The search's incumbent changed to `design`, `feasible` or not (vns.h, Feasible): one of
  // the last batch's (its round scores are kept) or, after a resume, unknown here (then
  // traced again when the next candidate needs them).
  void SetIncumbent(const BlindDesign& design, bool feasible);

  // Whether candidates are traced in rounds (enabled, and the tallies trace in parts).
  bool Races() const {
    return s_.enabled && !s_.racing.rounds.empty() && s_.lanes.front()->TracesInParts();
  }
  // Share of its paths the evaluation of `design` in the last batch traced (0: not there).
  double PathsFraction(const BlindDesign& design) const;
  const RacingStats& stats() const { return stats_; }
  const RacingSettings& settings() const { return s_.racing; }

 private:
  // A tally's evaluation (partial: of a round) and each version's score, from one pass of
  // the metrics over the versions.
  struct Scored {
    Evaluation evaluation;
    std::vector<double> scores;
  };
  // One design's evaluation on one lane, with what the racer keeps of it.
  struct Candidate {
    BlindDesign design;
    absl::StatusOr<Evaluation> evaluation = absl::UnknownError("not evaluated");
    RoundScores rounds;         // its scores after each round but the last
    std::vector<double> full;   // its full version scores, when traced in full (audit)
    double paths_fraction = 0;  // of its paths traced
    RacingStats stats;          // what racing did for it
  };
  absl::StatusOr<Scored> ScoreTallies(const std::vector<HourTally>& versions, bool partial,
                                      const ComfortEstimate* comfort = nullptr) const;
  absl::Status PrepareIncumbent();
  absl::StatusOr<Scored> FullScores(DesignTallies& lane, const BlindDesign& design) const;
  absl::Status Race(DesignTallies& lane, Candidate& c) const;
  void StartStats(Candidate& c) const;
  absl::Status TakeFull(const std::vector<HourTally>& versions, uint64_t rays, Candidate& c,
                        const ComfortEstimate* comfort = nullptr) const;
  void TraceTogether(DesignTallies& lane, DesignComfort* comfort,
                     const std::vector<Candidate*>& candidates) const;
  absl::Status Audit(DesignTallies& lane, Candidate& c) const;
  void AddStats(const RacingStats& s);

  Setting s_;
  std::unique_ptr<StandingThreads> threads_;  // one per lane: lane l always on thread l
  RacingStats stats_;
  std::vector<Candidate> last_batch_;
  BlindDesign incumbent_;
  bool incumbent_set_ = false;
  bool incumbent_feasible_ = true;
  std::optional<RoundScores> incumbent_rounds_;
  std::optional<std::vector<double>> incumbent_full_;  // (audit)
};

}  // namespace fenestra
