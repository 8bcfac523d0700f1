#pragma once

#include <string>

#include "core/optimize/job.h"
#include "fenestra/v1/service.pb.h"

namespace fenestra {

// One progress line: evaluations, best score ± error with its design, the current design,
// elapsed and estimated remaining time.
std::string FormatProgress(const JobProgress& progress);

// The design as "alpha=0.580 width=0.130".
std::string FormatDesign(const google::protobuf::Map<std::string, double>& design);

// A progress event from fenestrad as FormatProgress takes it.
JobProgress FromProto(const v1::JobProgress& progress);

// Prints the line: rewritten in place on a terminal, one line per update otherwise.
void ShowProgress(const JobProgress& progress);

// Ends a live progress line (a newline on a terminal).
void EndProgress();

// A summary of a finished job: best design, its metrics with errors, timings.
std::string FormatResult(const v1::JobResult& result);

}  // namespace fenestra
