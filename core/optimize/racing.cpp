#include "core/optimize/racing.h"

#include <utility>

#include "core/common/status_macros.h"
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

Racer::Racer(Setting setting) : s_(std::move(setting)) {
  stats_.rejected.assign(s_.racing.rounds.size(), 0);
}

absl::StatusOr<Racer::Scored> Racer::ScoreTallies(const std::vector<HourTally>& versions,
                                                  bool partial) const {
  std::vector<AnnualMetrics> version_metrics;
  FENESTRA_ASSIGN_OR_RETURN(
      metrics, AnnualMetricsFromTallies(versions, s_.analysed_hours, s_.options, &version_metrics));
  Scored scored;
  for (const AnnualMetrics& m : version_metrics) {
    scored.scores.push_back(Score(s_.objective, SceneMetricValue(m.scene, s_.metric)));
  }
  scored.evaluation = MetricEvaluation(std::move(metrics), s_.metric);
  scored.evaluation.partial = partial;
  return scored;
}

absl::StatusOr<RoundScores> Racer::IncumbentRounds() {
  if (!incumbent_rounds_) {
    RoundScores rounds;
    for (const int parts : s_.racing.rounds) {
      FENESTRA_ASSIGN_OR_RETURN(versions, s_.tallies->Tally(incumbent_, s_.options, parts));
      FENESTRA_ASSIGN_OR_RETURN(scored, ScoreTallies(versions, true));
      rounds.push_back(std::move(scored.scores));
    }
    stats_.parts_traced += s_.racing.rounds.back();
    incumbent_rounds_ = std::move(rounds);
  }
  return *incumbent_rounds_;
}

absl::StatusOr<Evaluation> Racer::Evaluate(const BlindDesign& design) {
  const uint64_t rays_before = s_.tallies->RaysTraced();
  const bool races = Races();
  last_rounds_.clear();
  last_full_.clear();
  stats_.parts_in_full += kDesignParts;
  // The incumbent's rounds first: they may need tracing (after a resume), which would
  // replace this design's sums on the device
  std::optional<RoundScores> against;
  if (races && incumbent_score_set_) {
    FENESTRA_ASSIGN_OR_RETURN(rounds, IncumbentRounds());
    against = std::move(rounds);
    ++stats_.candidates;
  }
  for (size_t r = 0; races && r < s_.racing.rounds.size(); ++r) {
    FENESTRA_ASSIGN_OR_RETURN(versions, s_.tallies->Tally(design, s_.options, s_.racing.rounds[r]));
    FENESTRA_ASSIGN_OR_RETURN(scored, ScoreTallies(versions, true));
    last_rounds_.push_back(std::move(scored.scores));
    if (against && Rejects(Paired(last_rounds_[r], (*against)[r]), s_.racing)) {
      ++stats_.rejected[r];
      stats_.parts_traced += s_.racing.rounds[r];
      last_paths_fraction_ = static_cast<double>(s_.racing.rounds[r]) / kDesignParts;
      stats_.rays_traced += s_.tallies->RaysTraced() - rays_before;
      if (s_.audit) FENESTRA_RETURN_IF_ERROR(Audit(design));
      return std::move(scored.evaluation);
    }
  }
  FENESTRA_ASSIGN_OR_RETURN(versions, s_.tallies->Tally(design, s_.options, kDesignParts));
  stats_.parts_traced += kDesignParts;
  stats_.rays_traced += s_.tallies->RaysTraced() - rays_before;
  last_paths_fraction_ = 1;
  FENESTRA_ASSIGN_OR_RETURN(scored, ScoreTallies(versions, false));
  if (s_.audit) last_full_ = std::move(scored.scores);
  return std::move(scored.evaluation);
}

absl::StatusOr<std::vector<double>> Racer::FullScores(const BlindDesign& design) {
  FENESTRA_ASSIGN_OR_RETURN(versions, s_.tallies->Tally(design, s_.options, kDesignParts));
  FENESTRA_ASSIGN_OR_RETURN(scored, ScoreTallies(versions, false));
  return std::move(scored.scores);
}

absl::Status Racer::Audit(const BlindDesign& design) {
  if (!incumbent_full_) {
    FENESTRA_ASSIGN_OR_RETURN(scores, FullScores(incumbent_));
    incumbent_full_ = std::move(scores);
  }
  FENESTRA_ASSIGN_OR_RETURN(full, FullScores(design));
  ++stats_.rejected_audited;
  // The search accepts any strict improvement of the score (the job's VnsOptions)
  const PairedDifference difference = Paired(full, *incumbent_full_);
  if (difference.difference > 0) ++stats_.rejected_would_improve;
  if (difference.difference > difference.standard_error) ++stats_.rejected_better_beyond_error;
  return absl::OkStatus();
}

void Racer::SetIncumbent(const BlindDesign& design, const Evaluation& evaluation,
                         bool last_evaluated) {
  incumbent_ = design;
  incumbent_score_ = Score(s_.objective, evaluation.value);
  incumbent_score_set_ = true;
  if (last_evaluated && last_rounds_.size() == s_.racing.rounds.size()) {
    incumbent_rounds_ = last_rounds_;
  } else {
    incumbent_rounds_.reset();
  }
  if (last_evaluated && !last_full_.empty()) {
    incumbent_full_ = last_full_;
  } else {
    incumbent_full_.reset();
  }
}

}  // namespace fenestra
