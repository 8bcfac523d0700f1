// A job's search checkpoints (job_checkpoint.h): the bytes a store kept parsed
// (ParseSearchCheckpoint, job.h), a checkpoint checked against the job it resumes, and its
// history turned back into the search so far.
#include "core/optimize/job_checkpoint.h"

#include <climits>
#include <cmath>
#include <span>
#include <string>
#include <utility>

#include "absl/strings/str_cat.h"
#include "core/common/status_macros.h"
#include "core/optimize/job_pareto.h"

namespace fenestra {
namespace {

absl::Status CheckCheckpointFormat(const v1::SearchCheckpoint& checkpoint) {
  if (checkpoint.format() == kSearchCheckpointFormat) return absl::OkStatus();
  return absl::InvalidArgumentError(absl::StrCat("search checkpoint: format ", checkpoint.format(),
                                                 ", but this build reads format ",
                                                 kSearchCheckpointFormat, " only"));
}

// Step `e` of a checkpoint's history as a step of the search over `variables`, on the
// search's clock (started at `search_start` on the job's). InvalidArgument where its design
// has not the job's variables.
absl::StatusOr<VnsRecord> ResumedStep(const v1::Evaluation& e,
                                      std::span<const DesignVariable> variables,
                                      double search_start) {
  VnsRecord record;
  record.index = e.index();
  for (const DesignVariable& v : variables) {
    const auto value = e.design().find(v.name);
    if (value == e.design().end()) {
      return absl::InvalidArgumentError(absl::StrCat("search checkpoint: step ", e.index(),
                                                     " has no value of variable '", v.name, "'"));
    }
    record.x.push_back(value->second);
  }
  if (e.design_size() != static_cast<int>(variables.size())) {
    return absl::InvalidArgumentError(absl::StrCat("search checkpoint: step ", e.index(),
                                                   " has variables the job does not have"));
  }
  record.evaluation.value = e.value().value();
  record.evaluation.standard_error = e.value().standard_error();
  record.evaluation.partial = e.raced_out();
  for (const v1::Estimate& c : e.constraints()) {
    record.evaluation.constraints.push_back({c.value(), c.standard_error()});
  }
  record.evaluation_seconds = e.seconds();
  record.elapsed_seconds = e.elapsed_seconds() - search_start;
  record.cached = e.cached();
  record.improved = e.improved();
  record.neighborhood = e.neighborhood();
  return record;
}

// The search so far that `checkpoint` holds, once it is known to be of this format, of the
// job whose content hash is `job_hash` and a history its search makes (CheckVnsResume).
absl::StatusOr<VnsResult> ResumedSearch(const std::string& job_hash, const SearchSettings& search,
                                        const v1::SearchCheckpoint& checkpoint, bool pareto) {
  FENESTRA_RETURN_IF_ERROR(CheckCheckpointFormat(checkpoint));
  if (checkpoint.job_hash() != job_hash) {
    return absl::InvalidArgumentError(
        "search checkpoint: it belongs to another job (its content hash differs)");
  }
  if (checkpoint.history_size() == 0) {
    return absl::InvalidArgumentError("search checkpoint: no steps");
  }
  const double job_seconds = checkpoint.history(checkpoint.history_size() - 1).elapsed_seconds();
  if (!(job_seconds >= 0) || !std::isfinite(job_seconds)) {
    return absl::InvalidArgumentError(absl::StrCat(
        "search checkpoint: the last step's elapsed_seconds ", job_seconds, " is not a time"));
  }
  // The history on the search's clock
  const double search_start = job_seconds - checkpoint.search_seconds();
  VnsResult so_far;
  so_far.elapsed_seconds = checkpoint.search_seconds();
  for (const v1::Evaluation& e : checkpoint.history()) {
    FENESTRA_ASSIGN_OR_RETURN(record, ResumedStep(e, search.variables, search_start));
    so_far.history.push_back(std::move(record));
  }
  if (pareto) return so_far;  // replayed by ResumedPareto
  if (absl::Status replay = CheckVnsResume(search.variables, search.options, so_far);
      !replay.ok()) {
    return absl::InvalidArgumentError(absl::StrCat("search checkpoint: ", replay.message()));
  }
  return so_far;
}

// The same for a Pareto search: the history with each step's objectives, checked by replaying
// the generations it holds.
absl::StatusOr<ParetoOutcome> ResumedPareto(const v1::Job& job, const SearchSettings& search,
                                            const v1::SearchCheckpoint& checkpoint,
                                            VnsResult so_far) {
  ParetoOutcome outcome;
  for (const v1::Evaluation& e : checkpoint.history()) {
    outcome.objectives.push_back(ParetoObjectivesOf(e));
    outcome.generation.push_back(e.generation());
  }
  outcome.search = std::move(so_far);
  const ParetoOptions options = MakeParetoOptions(job, search);
  for (size_t s = 0; s < outcome.objectives.size(); ++s) {
    if (outcome.objectives[s].size() != options.objectives.size()) {
      return absl::InvalidArgumentError(absl::StrCat("search checkpoint: step ", s, " has ",
                                                     outcome.objectives[s].size(), " objectives"));
    }
  }
  if (absl::StatusOr<ParetoOutcome> replay = RunPareto(search.variables, {}, options, {}, &outcome);
      !replay.ok()) {
    return absl::InvalidArgumentError(
        absl::StrCat("search checkpoint: ", replay.status().message()));
  }
  return outcome;
}

}  // namespace

absl::StatusOr<v1::SearchCheckpoint> ParseSearchCheckpoint(std::string_view bytes) {
  v1::SearchCheckpoint checkpoint;
  if (bytes.size() > static_cast<size_t>(INT_MAX) ||
      !checkpoint.ParseFromArray(bytes.data(), static_cast<int>(bytes.size()))) {
    return absl::DataLossError(
        absl::StrCat("search checkpoint: ", bytes.size(),
                     " bytes that are not a serialized fenestra.v1.SearchCheckpoint"));
  }
  FENESTRA_RETURN_IF_ERROR(CheckCheckpointFormat(checkpoint));
  return checkpoint;
}

absl::StatusOr<SearchStart> StartOfSearch(const PreparedJob& job, const SearchSettings& settings,
                                          const v1::SearchCheckpoint* resume) {
  SearchStart start;
  if (resume == nullptr) {
    start.checkpoint.set_format(kSearchCheckpointFormat);
    start.checkpoint.set_job_hash(JobContentHash(job));
    return start;
  }
  FENESTRA_ASSIGN_OR_RETURN(
      so_far, ResumedSearch(JobContentHash(job), settings, *resume, job.job.has_pareto()));
  start.checkpoint = *resume;
  // Each step's feasibility as this search takes it, from the constraints' values it holds
  for (int i = 0; i < start.checkpoint.history_size(); ++i) {
    start.checkpoint.mutable_history(i)->set_feasible(
        Feasible(settings.options.constraints, so_far.history[i].evaluation));
  }
  if (job.job.has_pareto()) {
    FENESTRA_ASSIGN_OR_RETURN(pareto, ResumedPareto(job.job, settings, *resume, std::move(so_far)));
    start.pareto_so_far = std::move(pareto);
  } else {
    start.so_far = std::move(so_far);
  }
  start.resumed_seconds = resume->history(resume->history_size() - 1).elapsed_seconds();
  return start;
}

}  // namespace fenestra
