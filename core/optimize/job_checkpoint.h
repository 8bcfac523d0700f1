#pragma once

// Where a job's search starts, for the job runner (job.cpp): from nothing, or from a search
// checkpoint, checked against the job (its format, content hash and history) and turned back
// into the search so far. ParseSearchCheckpoint (job.h) is implemented here too.
#include <optional>

#include "absl/status/statusor.h"
#include "core/optimize/job.h"
#include "core/optimize/job_proto.h"
#include "core/optimize/vns.h"
#include "fenestra/v1/job.pb.h"

namespace fenestra {

// Where a job's search starts: from nothing, or from a checkpoint.
struct SearchStart {
  v1::SearchCheckpoint checkpoint;             // kept up to date after each step
  std::optional<VnsResult> so_far;             // the search resumed
  std::optional<ParetoOutcome> pareto_so_far;  // the same of a Pareto search (so_far unset)
  double resumed_seconds = 0;                  // the job's clock at the checkpoint [s]
};

// The start of the job's search: from `resume` when given, else new (a checkpoint of this
// format and of the job's content hash, no steps). InvalidArgument for a checkpoint of another
// format or job, without steps, or whose history `settings`' search does not make
// (CheckVnsResume).
absl::StatusOr<SearchStart> StartOfSearch(const PreparedJob& job, const SearchSettings& settings,
                                          const v1::SearchCheckpoint* resume);

}  // namespace fenestra
