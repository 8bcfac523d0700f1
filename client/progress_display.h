#pragma once

#include <string>

#include "core/optimize/job.h"
#include "fenestra/v1/service.pb.h"

namespace fenestra {

// One progress line: evaluations, best score ± error with its design, the current design,
// elapsed and estimated remaining time; after the final check, the check (both values, their
// difference with its standard error, and whether they disagree).
std::string FormatProgress(const JobProgress& progress);

// The design as "alpha=0.580 width=0.130".
std::string FormatDesign(const google::protobuf::Map<std::string, double>& design);

// What a stage ("sky", "outdoor", "search", "check", ...) does, for "...\n" lines; `cached`:
// the outdoor matrix comes from the cache.
std::string StageText(const std::string& stage, bool cached = false);

// A progress event from fenestrad as FormatProgress takes it.
JobProgress FromProto(const v1::JobProgress& progress);

// Prints the line: rewritten in place on a terminal, one line per update otherwise.
void ShowProgress(const JobProgress& progress);

// Ends a live progress line (a newline on a terminal).
void EndProgress();

// A summary of a finished job: best design, its metrics with errors, each constraint of the
// objective at it (whether it holds), timings, and the final check with a warning when it
// disagrees.
std::string FormatResult(const v1::JobResult& result);

}  // namespace fenestra
