#pragma once

// A small tilt optimization of the city office (examples/city_office/alpha_max_quick.json
// with fewer paths and evaluations), run in this process, for tests of what reads results.
#include <gtest/gtest.h>

#include <string>
#include <utility>
#include <vector>

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

// QuickJob with its scene inline, slat materials added to choose from ("black", reflectance 0;
// "grey", 0.4; "white", 0.8), its blind's slats "black", and a finish variable over
// `finishes` (names of those materials), starting at the first; the tilt at 0.8 rad (slats
// half open, their faces seen from the room), free unless `tilt_fixed`.
inline v1::Job QuickFinishJob(int evaluations, const std::vector<std::string>& finishes,
                              bool tilt_fixed = true) {
  v1::Job job = QuickJob(evaluations);
  absl::StatusOr<v1::Scene> scene =
      ReadSceneProto(FENESTRA_SOURCE_DIR "/examples/city_office/scene.json");
  EXPECT_TRUE(scene.ok()) << scene.status();
  if (!scene.ok()) return {};
  for (const auto& [name, reflectance] :
       {std::pair{"black", 0.0}, std::pair{"grey", 0.4}, std::pair{"white", 0.8}}) {
    v1::Material& m = *scene->add_materials();
    m.set_name(name);
    m.set_reflectance(reflectance);
  }
  scene->mutable_blind()->set_material("black");
  job.clear_scene_file();
  *job.mutable_scene() = *std::move(scene);
  v1::DesignVariable& alpha = *job.mutable_variables(0);
  alpha.set_start(0.8);
  alpha.set_fixed(tilt_fixed);
  v1::DesignVariable& finish = *job.add_variables();
  finish.set_name("finish");
  for (const std::string& name : finishes) finish.add_finishes()->set_material(name);
  return job;
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

// The result of a search over the finish alone, black slats or white ones, maximizing DA
// (QuickFinishJob): white, finish 1. Run once per process.
inline const v1::JobResult& QuickFinishJobResult() {
  static const v1::JobResult* result = [] {
    v1::Job job = QuickFinishJob(4, {"black", "white"});
    job.mutable_objective()->set_metric(v1::METRIC_DA);
    job.mutable_budget()->set_failed_cycles_to_stop(1);
    absl::StatusOr<v1::JobResult> run = RunQuickJob(job);
    EXPECT_TRUE(run.ok()) << run.status();
    return new v1::JobResult(run.ok() ? *run : v1::JobResult());
  }();
  return *result;
}

}  // namespace fenestra
