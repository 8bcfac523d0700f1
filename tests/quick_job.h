#pragma once

// A small tilt optimization of the city office (examples/city_office/alpha_max_quick.json
// with fewer paths and evaluations), run in this process, for tests of what reads results.
#include <gtest/gtest.h>

#include "core/optimize/job.h"

namespace fenestra {

// The job: `evaluations` designs, 2000 indoor paths per sensor, 40000 outdoor paths, the
// window in one part: 288 + 292 columns of I and rows of O instead of the 12 parts' 3748.
inline v1::Job QuickJob(int evaluations = 4) {
  absl::StatusOr<v1::Job> job =
      ReadJobFile(FENESTRA_SOURCE_DIR "/examples/city_office/alpha_max_quick.json");
  EXPECT_TRUE(job.ok()) << job.status();
  if (!job.ok()) return {};
  job->mutable_budget()->set_max_evaluations(evaluations);
  job->mutable_sampling()->set_indoor_paths_per_sensor(2000);
  job->mutable_sampling()->set_outdoor_paths(40000);
  job->mutable_sampling()->set_backend("cpu");
  job->mutable_sampling()->set_window_columns(1);
  job->mutable_sampling()->set_window_rows(1);
  return *job;
}

// The result of running `job` (relative files taken from examples/city_office/).
inline absl::StatusOr<v1::JobResult> RunQuickJob(const v1::Job& job) {
  absl::StatusOr<PreparedJob> prepared =
      PrepareJob(job, FENESTRA_SOURCE_DIR "/examples/city_office");
  if (!prepared.ok()) return prepared.status();
  return RunJob(*prepared, nullptr);
}

// The result of QuickJob(), run once per process.
inline const v1::JobResult& QuickJobResult() {
  static const v1::JobResult* result = [] {
    absl::StatusOr<v1::JobResult> run = RunQuickJob(QuickJob());
    EXPECT_TRUE(run.ok()) << run.status();
    return new v1::JobResult(run.ok() ? *run : v1::JobResult());
  }();
  return *result;
}

}  // namespace fenestra
