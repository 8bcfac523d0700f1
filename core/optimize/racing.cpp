#include "core/optimize/racing.h"

#include <algorithm>
#include <future>
#include <utility>

#include "core/common/status_macros.h"
#include "core/common/thread_pool.h"
#include "core/metrics/metric_errors.h"
#include "core/optimize/metric_objective.h"

namespace fenestra {

PairedDifference Paired(std::span<const double> candidate, std::span<const double> incumbent) {
  std::vector<double> leave_one_out;
  for (size_t v = 1; v < candidate.size() && v < incumbent.size(); ++v) {
    leave_one_out.push_back(candidate[v] - incumbent[v]);
  }
  return {candidate[0] - incumbent[0], JackknifeStandardError(leave_one_out)};
}

bool Rejects(const PairedDifference& difference, const RacingSettings& settings) {
  return difference.difference < -settings.standard_errors * difference.standard_error;
}

bool RoundRejects(std::span<const double> candidate, std::span<const Estimated> constraints,
                  std::span<const double> incumbent, bool incumbent_feasible,
                  std::span<const Constraint> bounds, const RacingSettings& settings) {
  if (!incumbent_feasible) return false;
  return Rejects(Paired(candidate, incumbent), settings) ||
         ConstraintsBroken(bounds, constraints, settings.standard_errors);
}

Racer::Racer(Setting setting)
    : s_(std::move(setting)),
      threads_(std::make_unique<StandingThreads>(static_cast<int>(s_.lanes.size()))) {
  stats_.rejected.assign(s_.racing.rounds.size(), 0);
}

Racer::~Racer() = default;

absl::StatusOr<Racer::Scored> Racer::ScoreTallies(const std::vector<HourTally>& versions,
                                                  bool partial,
                                                  const ComfortEstimate* comfort) const {
  std::vector<AnnualMetrics> version_metrics;
  FENESTRA_ASSIGN_OR_RETURN(
      metrics, AnnualMetricsFromTallies(versions, s_.analysed_hours, s_.options, &version_metrics));
  // The comfort metrics have no versions here: their scores serve no round (racing is off)
  if (comfort != nullptr) AddComfort(*comfort, metrics);
  Scored scored;
  for (const AnnualMetrics& m : version_metrics) {
    scored.scores.push_back(Score(s_.objective, SceneMetricValue(m.scene, s_.metric)));
  }
  scored.evaluation = MetricEvaluation(std::move(metrics), s_.metric, s_.constraint_metrics);
  scored.evaluation.partial = partial;
  return scored;
}

// The incumbent's round scores (and full scores, under the audit) for the next batch: kept
// from its evaluation here, else traced again on the first lane (after a resume).
absl::Status Racer::PrepareIncumbent() {
  if (!incumbent_set_ || !Races()) return absl::OkStatus();
  DesignTallies& lane = *s_.lanes.front();
  if (!incumbent_rounds_) {
    RoundScores rounds;
    for (const int parts : s_.racing.rounds) {
      FENESTRA_ASSIGN_OR_RETURN(versions, lane.Tally(incumbent_, s_.options, parts));
      FENESTRA_ASSIGN_OR_RETURN(scored, ScoreTallies(versions, true));
      rounds.push_back(std::move(scored.scores));
    }
    stats_.parts_traced += s_.racing.rounds.back();
    incumbent_rounds_ = std::move(rounds);
  }
  if (s_.audit && !incumbent_full_) {
    FENESTRA_ASSIGN_OR_RETURN(full, FullScores(lane, incumbent_));
    incumbent_full_ = std::move(full.scores);
  }
  return absl::OkStatus();
}

// Evaluates c.design on `lane` in rounds (racing), against the incumbent where there is one,
// then in full unless a round rejects it.
absl::Status Racer::Race(DesignTallies& lane, Candidate& c) const {
  const uint64_t rays_before = lane.RaysTraced();
  const bool against = incumbent_set_;
  StartStats(c);
  if (against) c.stats.candidates = 1;
  for (size_t r = 0; r < s_.racing.rounds.size(); ++r) {
    FENESTRA_ASSIGN_OR_RETURN(versions, lane.Tally(c.design, s_.options, s_.racing.rounds[r]));
    FENESTRA_ASSIGN_OR_RETURN(scored, ScoreTallies(versions, true));
    c.rounds.push_back(std::move(scored.scores));
    if (against && RoundRejects(c.rounds[r], scored.evaluation.constraints, (*incumbent_rounds_)[r],
                                incumbent_feasible_, s_.constraints.bounds, s_.racing)) {
      c.stats.rejected[r] = 1;
      c.stats.parts_traced = s_.racing.rounds[r];
      c.paths_fraction = static_cast<double>(s_.racing.rounds[r]) / kDesignParts;
      c.stats.rays_traced = lane.RaysTraced() - rays_before;
      c.evaluation = std::move(scored.evaluation);
      return s_.audit ? Audit(lane, c) : absl::OkStatus();
    }
  }
  FENESTRA_ASSIGN_OR_RETURN(versions, lane.Tally(c.design, s_.options, kDesignParts));
  return TakeFull(versions, lane.RaysTraced() - rays_before, c);
}

// c's racing statistics before any of its paths: no round rejected it yet.
void Racer::StartStats(Candidate& c) const {
  c.stats.rejected.assign(s_.racing.rounds.size(), 0);
  c.stats.parts_in_full = kDesignParts;
}

// c's evaluation from the tallies of all its paths, which took `rays`.
absl::Status Racer::TakeFull(const std::vector<HourTally>& versions, uint64_t rays, Candidate& c,
                             const ComfortEstimate* comfort) const {
  c.stats.parts_traced = kDesignParts;
  c.stats.rays_traced = rays;
  c.paths_fraction = 1;
  FENESTRA_ASSIGN_OR_RETURN(scored, ScoreTallies(versions, false, comfort));
  if (s_.audit) c.full = std::move(scored.scores);
  c.evaluation = std::move(scored.evaluation);
  return absl::OkStatus();
}

// Without racing: the candidates in full, as many at a time as the lane traces together, with
// their comfort metrics where the lane has them.
void Racer::TraceTogether(DesignTallies& lane, DesignComfort* comfort,
                          const std::vector<Candidate*>& candidates) const {
  const size_t at_once = static_cast<size_t>(std::max(1, lane.DesignsAtOnce()));
  for (size_t first = 0; first < candidates.size(); first += at_once) {
    const size_t count = std::min(at_once, candidates.size() - first);
    std::vector<BlindDesign> designs;
    for (size_t k = 0; k < count; ++k) designs.push_back(candidates[first + k]->design);
    std::vector<absl::StatusOr<ComfortEstimate>> comforts;
    std::future<void> comfort_done;
    if (comfort != nullptr) {
      comfort_done = std::async(s_.comfort_beside ? std::launch::async : std::launch::deferred,
                                [&] { comforts = comfort->EvaluateDesigns(designs); });
    }
    const uint64_t rays_before = lane.RaysTraced();
    std::vector<absl::StatusOr<std::vector<HourTally>>> tallies =
        lane.TallyDesigns(designs, s_.options);
    if (comfort_done.valid()) comfort_done.get();
    // Each design's share of the pass's rays
    const uint64_t rays = (lane.RaysTraced() - rays_before) / count;
    for (size_t k = 0; k < count; ++k) {
      Candidate& c = *candidates[first + k];
      StartStats(c);
      absl::Status taken = tallies[k].status();
      if (taken.ok() && comfort != nullptr) taken = comforts[k].status();
      if (taken.ok()) {
        taken = TakeFull(*tallies[k], rays, c, comfort != nullptr ? &*comforts[k] : nullptr);
      }
      if (!taken.ok()) c.evaluation = taken;
    }
  }
}

absl::StatusOr<Racer::Scored> Racer::FullScores(DesignTallies& lane,
                                                const BlindDesign& design) const {
  FENESTRA_ASSIGN_OR_RETURN(versions, lane.Tally(design, s_.options, kDesignParts));
  return ScoreTallies(versions, false);
}

// Traces the rejected candidate to the end and counts whether a full evaluation would have
// accepted it; its result stays the rejection.
absl::Status Racer::Audit(DesignTallies& lane, Candidate& c) const {
  FENESTRA_ASSIGN_OR_RETURN(full, FullScores(lane, c.design));
  c.stats.rejected_audited = 1;
  // The search accepts any strict improvement of the score (the job's VnsOptions) of a
  // feasible design (a round rejects only against a feasible incumbent)
  if (!Feasible(s_.constraints, full.evaluation)) return absl::OkStatus();
  const PairedDifference difference = Paired(full.scores, *incumbent_full_);
  if (difference.difference > 0) c.stats.rejected_would_improve = 1;
  if (difference.difference > difference.standard_error) c.stats.rejected_better_beyond_error = 1;
  return absl::OkStatus();
}

void Racer::AddStats(const RacingStats& s) {
  stats_.candidates += s.candidates;
  for (size_t r = 0; r < s.rejected.size() && r < stats_.rejected.size(); ++r) {
    stats_.rejected[r] += s.rejected[r];
  }
  stats_.parts_traced += s.parts_traced;
  stats_.parts_in_full += s.parts_in_full;
  stats_.rays_traced += s.rays_traced;
  stats_.rejected_audited += s.rejected_audited;
  stats_.rejected_would_improve += s.rejected_would_improve;
  stats_.rejected_better_beyond_error += s.rejected_better_beyond_error;
}

absl::StatusOr<Evaluation> Racer::Evaluate(const BlindDesign& design) {
  return std::move(EvaluateBatch({design}).front());
}

std::vector<absl::StatusOr<Evaluation>> Racer::EvaluateBatch(
    const std::vector<BlindDesign>& designs) {
  last_batch_.clear();
  std::vector<absl::StatusOr<Evaluation>> out;
  if (const absl::Status ready = PrepareIncumbent(); !ready.ok()) {
    out.assign(designs.size(), ready);
    return out;
  }
  last_batch_.resize(designs.size());
  for (size_t i = 0; i < designs.size(); ++i) last_batch_[i].design = designs[i];
  // Lane l takes candidates l, l + lanes, ... on its own thread
  const size_t lanes = s_.lanes.size();
  const auto race = [&](int l) {
    DesignTallies& lane = *s_.lanes[l];
    std::vector<Candidate*> mine;
    for (size_t i = l; i < last_batch_.size(); i += lanes) mine.push_back(&last_batch_[i]);
    if (!Races()) return TraceTogether(lane, s_.comfort.empty() ? nullptr : s_.comfort[l], mine);
    for (Candidate* c : mine) {
      if (const absl::Status raced = Race(lane, *c); !raced.ok()) c->evaluation = raced;
    }
  };
  if (designs.size() == 1) {
    race(0);
  } else {
    threads_->Run(race);
  }
  for (Candidate& c : last_batch_) {
    AddStats(c.stats);
    out.push_back(c.evaluation);
  }
  return out;
}

double Racer::PathsFraction(const BlindDesign& design) const {
  for (const Candidate& c : last_batch_) {
    if (c.design == design) return c.paths_fraction;
  }
  return 0;
}

void Racer::SetIncumbent(const BlindDesign& design, bool feasible) {
  incumbent_ = design;
  incumbent_set_ = true;
  incumbent_feasible_ = feasible;
  incumbent_rounds_.reset();
  incumbent_full_.reset();
  for (const Candidate& c : last_batch_) {
    if (c.design != design || !c.evaluation.ok()) continue;
    if (c.rounds.size() == s_.racing.rounds.size()) incumbent_rounds_ = c.rounds;
    if (!c.full.empty()) incumbent_full_ = c.full;
  }
}

}  // namespace fenestra
