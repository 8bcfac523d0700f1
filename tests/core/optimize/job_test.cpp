#include "core/optimize/job.h"

#include <gtest/gtest.h>

#include <climits>
#include <cmath>
#include <cstdio>
#include <functional>
#include <set>
#include <string>
#include <vector>

#include "absl/strings/str_cat.h"
#include "core/dc/dc_backend.h"
#include "core/optimize/final_check.h"
#include "google/protobuf/util/message_differencer.h"
#include "tests/example_scene.h"
#include "tests/quick_job.h"

namespace fenestra {
namespace {

// The quick tilt job (examples/city_office/alpha_max_quick.json: 10^4 indoor paths per
// sensor) with `evaluations`, on the CPU, with the jobs' reflection limits (none, as the
// final check traces); `source_limits`: at most 30 outdoor and 5 indoor reflections, the
// source publication's.
PreparedJob PrepareQuickJob(int evaluations, bool source_limits = false) {
  absl::StatusOr<v1::Job> job =
      ReadJobFile(FENESTRA_SOURCE_DIR "/examples/city_office/alpha_max_quick.json");
  EXPECT_TRUE(job.ok()) << job.status();
  job->mutable_budget()->set_max_evaluations(evaluations);
  job->mutable_sampling()->set_backend("cpu");
  if (source_limits) {
    job->mutable_sampling()->set_outdoor_bounces(30);
    job->mutable_sampling()->set_indoor_bounces(5);
  }
  absl::StatusOr<PreparedJob> prepared =
      PrepareJob(*job, FENESTRA_SOURCE_DIR "/examples/city_office");
  EXPECT_TRUE(prepared.ok()) << prepared.status();
  return *prepared;
}

// A job's result with what it reported on the way.
struct Reported {
  v1::JobResult result;
  std::vector<std::string> stages;
  std::vector<JobProgress> progress;
};

Reported RunReporting(const PreparedJob& job, std::function<bool()> cancelled = {}) {
  Reported r;
  JobCallbacks callbacks;
  callbacks.stage = [&](const std::string& stage) { r.stages.push_back(stage); };
  callbacks.progress = [&](const JobProgress& p) { r.progress.push_back(p); };
  callbacks.cancelled = std::move(cancelled);
  absl::StatusOr<v1::JobResult> result = RunJob(job, nullptr, callbacks);
  EXPECT_TRUE(result.ok()) << result.status();
  if (result.ok()) r.result = *std::move(result);
  return r;
}

void Print(const v1::FinalCheck& c) {
  std::printf(
      "two-stage %.3f ± %.3f, one-stage %.3f ± %.3f (%lld paths per sensor, pilot %lld, %.2f s), "
      "difference %+.3f ± %.3f\n",
      c.two_stage().value(), c.two_stage().standard_error(), c.one_stage().value(),
      c.one_stage().standard_error(), static_cast<long long>(c.paths_per_sensor()),
      static_cast<long long>(c.pilot_paths_per_sensor()), c.seconds(), c.difference().value(),
      c.difference().standard_error());
}

TEST(JobTest, WindowPartsAreResolvedAndChecked) {
  absl::StatusOr<v1::Sampling> automatic = ResolveSampling(v1::Sampling());
  ASSERT_TRUE(automatic.ok()) << automatic.status();
  const Scene scene = LoadExample("city_office");
  EXPECT_EQ(SamplingWindowParts(*automatic, scene.window()), (WindowParts{4, 3}));
  v1::Sampling columns_only = *automatic;
  columns_only.set_window_columns(2);
  EXPECT_EQ(SamplingWindowParts(columns_only, scene.window()), (WindowParts{2, 3}));
  for (const int bad : {-1, 17}) {
    v1::Sampling s;
    s.set_window_rows(bad);
    absl::StatusOr<v1::Sampling> resolved = ResolveSampling(s);
    ASSERT_FALSE(resolved.ok());
    EXPECT_NE(resolved.status().message().find("sampling.window_columns/window_rows"),
              std::string::npos)
        << resolved.status();
  }
  // Enough outdoor paths for every window cell
  v1::Sampling few;
  few.set_outdoor_paths(1000);
  few.set_window_columns(2);
  EXPECT_FALSE(ResolveSampling(few).ok());
}

// A job needs an outdoor path per window cell of its resolved parts and batch
TEST(JobTest, PrepareChecksOutdoorPathsAgainstTheWindowCells) {
  absl::StatusOr<v1::Job> job =
      ReadJobFile(FENESTRA_SOURCE_DIR "/examples/city_office/alpha_max_quick.json");
  ASSERT_TRUE(job.ok()) << job.status();
  job->mutable_sampling()->set_outdoor_paths(20000);  // 4 x 3 x 288 cells x 8 batches: 27648
  absl::StatusOr<PreparedJob> prepared =
      PrepareJob(*job, FENESTRA_SOURCE_DIR "/examples/city_office");
  ASSERT_FALSE(prepared.ok());
  EXPECT_NE(prepared.status().message().find("4x3 window parts"), std::string::npos)
      << prepared.status();
  job->mutable_sampling()->set_window_columns(1);
  job->mutable_sampling()->set_window_rows(1);
  prepared = PrepareJob(*job, FENESTRA_SOURCE_DIR "/examples/city_office");
  EXPECT_TRUE(prepared.ok()) << prepared.status();
}

// The outdoor matrix's key follows the window parts it was traced with, not how they
// were asked for.
TEST(JobTest, OutdoorKeyFollowsTheWindowParts) {
  const Scene scene = LoadExample("city_office");
  v1::Sampling automatic = *ResolveSampling(v1::Sampling());
  v1::Sampling explicit_parts = automatic;
  explicit_parts.set_window_columns(4);
  explicit_parts.set_window_rows(3);
  v1::Sampling whole = automatic;
  whole.set_window_columns(1);
  whole.set_window_rows(1);
  EXPECT_EQ(OutdoorMatrixKey(scene, automatic), OutdoorMatrixKey(scene, explicit_parts));
  EXPECT_NE(OutdoorMatrixKey(scene, automatic), OutdoorMatrixKey(scene, whole));
}

TEST(JobTest, FinalCheckIsOnUnlessTheSamplingSaysNo) {
  absl::StatusOr<v1::Sampling> automatic = ResolveSampling(v1::Sampling());
  ASSERT_TRUE(automatic.ok()) << automatic.status();
  EXPECT_TRUE(automatic->final_check());
  v1::Sampling off;
  off.set_final_check(false);
  absl::StatusOr<v1::Sampling> resolved = ResolveSampling(off);
  ASSERT_TRUE(resolved.ok()) << resolved.status();
  EXPECT_FALSE(resolved->final_check());
}

// Where both methods count the same light (no reflection limits), the one-stage check of the
// best design agrees with the two-stage value within the errors (seed 1).
TEST(JobTest, FinalCheckAgreesWhereBothMethodsCountTheSameLight) {
  const PreparedJob job = PrepareQuickJob(8);
  const Reported r = RunReporting(job);
  ASSERT_TRUE(r.result.has_final_check());
  const v1::FinalCheck& c = r.result.final_check();
  Print(c);
  EXPECT_EQ(c.two_stage().value(), r.result.best_value().value());
  EXPECT_EQ(c.two_stage().standard_error(), r.result.best_value().standard_error());
  EXPECT_GT(c.one_stage().value(), 0);
  EXPECT_GT(c.one_stage().standard_error(), 0);
  EXPECT_EQ(c.one_stage().value(), c.one_stage_metrics().udi().value());  // the objective: UDI
  EXPECT_EQ(c.one_stage_metrics().sensor_udi_size(), 9);
  EXPECT_DOUBLE_EQ(c.difference().value(), c.one_stage().value() - c.two_stage().value());
  EXPECT_DOUBLE_EQ(c.difference().standard_error(),
                   std::hypot(c.one_stage().standard_error(), c.two_stage().standard_error()));
  EXPECT_LT(std::abs(c.difference().value()), 4 * c.difference().standard_error());
  EXPECT_EQ(c.disagrees(), std::abs(c.difference().value()) > 3 * c.difference().standard_error());
  EXPECT_GE(c.paths_per_sensor(), c.pilot_paths_per_sensor());
  EXPECT_GT(c.seconds(), 0);

  // The check runs after the search, and the last report carries it
  ASSERT_GE(r.stages.size(), 2u);
  EXPECT_EQ(r.stages[r.stages.size() - 2], "search");
  EXPECT_EQ(r.stages.back(), "check");
  ASSERT_GE(r.progress.size(), 2u);
  for (size_t i = 0; i + 1 < r.progress.size(); ++i) EXPECT_FALSE(r.progress[i].final_check);
  const JobProgress& last = r.progress.back();
  ASSERT_TRUE(last.final_check);
  EXPECT_EQ(last.final_check->SerializeAsString(), c.SerializeAsString());
  EXPECT_EQ(last.evaluations, r.result.evaluations());
  EXPECT_EQ(last.best.value().value(), r.result.best_value().value());
  EXPECT_EQ(last.remaining_seconds, 0);
  EXPECT_GE(last.elapsed_seconds, r.progress[r.progress.size() - 2].elapsed_seconds);

  // The same check of the same design, outside the job: the same numbers
  absl::StatusOr<v1::FinalCheck> again =
      CheckJobDesign(job, r.result.best_design(), r.result.best_value());
  ASSERT_TRUE(again.ok()) << again.status();
  v1::FinalCheck timeless = c;
  timeless.clear_seconds();
  again->clear_seconds();
  EXPECT_EQ(again->SerializeAsString(), timeless.SerializeAsString());
}

// The quick job with the source publication's limits (at most 5 indoor reflections): the
// check, which traces without a limit, finds the light the limits leave out (seed 1).
TEST(JobTest, FinalCheckFindsTheLightTheReflectionLimitsLeaveOut) {
  const Reported r = RunReporting(PrepareQuickJob(8, /*source_limits=*/true));
  ASSERT_TRUE(r.result.has_final_check());
  const v1::FinalCheck& c = r.result.final_check();
  Print(c);
  EXPECT_TRUE(c.disagrees());
  EXPECT_GT(c.difference().value(), 3 * c.difference().standard_error());
}

// Error against time: each evaluation's value, error and time, and the best value's as the
// search went, one entry per move of the incumbent.
TEST(JobTest, BestOverTimeFollowsTheIncumbent) {
  PreparedJob job = PrepareQuickJob(12);
  job.job.mutable_sampling()->set_final_check(false);
  const Reported r = RunReporting(job);
  EXPECT_FALSE(r.result.has_final_check());
  EXPECT_EQ(r.stages.back(), "search");
  const auto& history = r.result.history();
  EXPECT_EQ(r.result.evaluations(), 12);
  ASSERT_GE(history.size(), 12);  // cached repeats included
  for (int i = 0; i < history.size(); ++i) {
    EXPECT_EQ(history[i].index(), i);
    EXPECT_GT(history[i].elapsed_seconds(), 0);
    if (i > 0) {
      EXPECT_GE(history[i].elapsed_seconds(), history[i - 1].elapsed_seconds());
    }
    if (!history[i].cached()) {
      EXPECT_GT(history[i].seconds(), 0);
      EXPECT_GT(history[i].value().standard_error(), 0);
    }
  }
  const auto& best = r.result.best_over_time();
  ASSERT_GE(best.size(), 2);  // the start and at least one move from it
  int improvements = 0;
  for (const v1::Evaluation& e : history) improvements += e.improved() ? 1 : 0;
  EXPECT_EQ(best.size(), improvements);
  EXPECT_EQ(best[0].evaluation(), 0);
  for (int k = 0; k < best.size(); ++k) {
    const v1::Evaluation& e = history[best[k].evaluation()];
    EXPECT_TRUE(e.improved());
    EXPECT_EQ(best[k].value().value(), e.value().value());
    EXPECT_EQ(best[k].value().standard_error(), e.value().standard_error());
    EXPECT_EQ(best[k].elapsed_seconds(), e.elapsed_seconds());
    if (k > 0) {
      EXPECT_GT(best[k].evaluation(), best[k - 1].evaluation());
      EXPECT_GE(best[k].elapsed_seconds(), best[k - 1].elapsed_seconds());
      EXPECT_GT(best[k].value().value(), best[k - 1].value().value());  // maximized
    }
  }
  EXPECT_EQ(best[best.size() - 1].value().value(), r.result.best_value().value());
  EXPECT_EQ(best[best.size() - 1].value().standard_error(), r.result.best_value().standard_error());
  // The progress reports, one per step, carry the same times
  ASSERT_EQ(r.progress.size(), static_cast<size_t>(history.size()));
  EXPECT_EQ(r.progress.back().current.elapsed_seconds(),
            history[history.size() - 1].elapsed_seconds());
}

// A cancelled job stops without its check.
TEST(JobTest, CancelledJobLeavesTheCheckOut) {
  int reports = 0;
  PreparedJob job = PrepareQuickJob(12);
  JobCallbacks callbacks;
  std::vector<std::string> stages;
  callbacks.stage = [&](const std::string& stage) { stages.push_back(stage); };
  callbacks.progress = [&](const JobProgress&) { ++reports; };
  callbacks.cancelled = [&] { return reports >= 3; };
  absl::StatusOr<v1::JobResult> result = RunJob(job, nullptr, callbacks);
  ASSERT_TRUE(result.ok()) << result.status();
  EXPECT_EQ(result->stop_reason(), "cancelled");
  EXPECT_FALSE(result->has_final_check());
  EXPECT_EQ(stages.back(), "search");
  EXPECT_EQ(reports, 3);
}

// Resuming: the quick tilt job (tests/quick_job.h) of 14 evaluations on the CPU, its outdoor
// matrix traced once, run through and interrupted.
class JobResumeTest : public ::testing::Test {
 protected:
  // What a run handed out and returned.
  struct Run {
    absl::StatusOr<v1::JobResult> result;
    std::vector<std::string> checkpoints;  // serialized, one per step
    std::vector<std::string> stages;
  };

  static void SetUpTestSuite() {
    absl::StatusOr<PreparedJob> job =
        PrepareJob(QuickJob(14), FENESTRA_SOURCE_DIR "/examples/city_office");
    ASSERT_TRUE(job.ok()) << job.status();
    job_ = new PreparedJob(*std::move(job));
    absl::StatusOr<OutdoorMatrix> outdoor = ComputeOutdoorMatrix(job_->scene, job_->job.sampling());
    ASSERT_TRUE(outdoor.ok()) << outdoor.status();
    outdoor_ = new OutdoorMatrix(*std::move(outdoor));
  }
  static void TearDownTestSuite() {
    delete outdoor_;
    delete job_;
  }

  // The checkpoint after 6 steps, serialized.
  static std::string AfterSixSteps() {
    const Run run = RunJobOf(*job_, nullptr, 6);
    EXPECT_EQ(run.checkpoints.size(), 6u);
    return run.checkpoints.empty() ? std::string() : run.checkpoints.back();
  }

  // Runs `job` from `resume`, cancelled once the search has made `stop_at` steps.
  static Run RunJobOf(const PreparedJob& job, const v1::SearchCheckpoint* resume = nullptr,
                      int stop_at = INT_MAX) {
    Run run;
    int steps = 0;
    JobCallbacks callbacks;
    callbacks.stage = [&](const std::string& stage) { run.stages.push_back(stage); };
    callbacks.checkpoint = [&](const v1::SearchCheckpoint& checkpoint) {
      run.checkpoints.push_back(checkpoint.SerializeAsString());
      steps = checkpoint.history_size();
    };
    callbacks.cancelled = [&] { return steps >= stop_at; };
    run.result = RunJob(job, outdoor_, callbacks, resume);
    return run;
  }

  static v1::SearchCheckpoint Parsed(const std::string& bytes) {
    absl::StatusOr<v1::SearchCheckpoint> checkpoint = ParseSearchCheckpoint(bytes);
    EXPECT_TRUE(checkpoint.ok()) << checkpoint.status();
    return checkpoint.ok() ? *std::move(checkpoint) : v1::SearchCheckpoint();
  }

  // `history` without its times.
  static void ClearTimes(google::protobuf::RepeatedPtrField<v1::Evaluation>& history) {
    for (v1::Evaluation& e : history) {
      e.clear_seconds();
      e.clear_elapsed_seconds();
    }
  }
  static v1::JobResult Timeless(v1::JobResult result) {
    ClearTimes(*result.mutable_history());
    for (v1::BestSoFar& best : *result.mutable_best_over_time()) best.clear_elapsed_seconds();
    result.clear_timings();
    result.mutable_final_check()->clear_seconds();
    // Racing's counts are this process's (the steps' raced_out flags stay compared)
    result.clear_racing();
    return result;
  }
  static v1::SearchCheckpoint Timeless(v1::SearchCheckpoint checkpoint) {
    ClearTimes(*checkpoint.mutable_history());
    checkpoint.clear_search_seconds();
    return checkpoint;
  }

  template <class Message>
  static void ExpectEqual(const Message& a, const Message& b) {
    google::protobuf::util::MessageDifferencer differencer;
    std::string differences;
    differencer.ReportDifferencesToString(&differences);
    EXPECT_TRUE(differencer.Compare(a, b)) << differences;
  }

  // The refusal of `checkpoint`, before any stage of the job.
  static std::string Refusal(const PreparedJob& job, const v1::SearchCheckpoint& checkpoint) {
    const Run run = RunJobOf(job, &checkpoint);
    EXPECT_EQ(run.result.status().code(), absl::StatusCode::kInvalidArgument);
    EXPECT_TRUE(run.stages.empty());
    return std::string(run.result.status().message());
  }

  static PreparedJob* job_;
  static OutdoorMatrix* outdoor_;
};

PreparedJob* JobResumeTest::job_ = nullptr;
OutdoorMatrix* JobResumeTest::outdoor_ = nullptr;

// Interrupted after 3 steps and after 9, resumed each time from the serialized checkpoint:
// the result of the uninterrupted run, times aside, with no step done twice.
TEST_F(JobResumeTest, ResumedJobEndsAsTheUninterruptedOne) {
  const Run uninterrupted = RunJobOf(*job_);
  ASSERT_TRUE(uninterrupted.result.ok()) << uninterrupted.result.status();
  const v1::JobResult& full = *uninterrupted.result;
  ASSERT_EQ(full.stop_reason(), "evaluation_budget");
  ASSERT_TRUE(full.has_final_check());
  ASSERT_GT(full.history_size(), 9);
  ASSERT_EQ(uninterrupted.checkpoints.size(), static_cast<size_t>(full.history_size()));
  int hits = 0;
  for (const v1::Evaluation& e : full.history()) hits += e.cached() ? 1 : 0;
  EXPECT_GT(hits, 0);  // the tilt's lower bound is proposed again
  EXPECT_GT(full.best_over_time_size(), 1);

  // Stopped after 3 steps: the checkpoint of the uninterrupted run's third step
  const Run first = RunJobOf(*job_, nullptr, 3);
  ASSERT_TRUE(first.result.ok()) << first.result.status();
  EXPECT_EQ(first.result->stop_reason(), "cancelled");
  ASSERT_EQ(first.checkpoints.size(), 3u);
  const v1::SearchCheckpoint after_3 = Parsed(first.checkpoints.back());
  EXPECT_EQ(after_3.format(), kSearchCheckpointFormat);
  EXPECT_EQ(after_3.job_hash(), JobContentHash(*job_));
  ExpectEqual(Timeless(after_3), Timeless(Parsed(uninterrupted.checkpoints[2])));

  // Resumed, stopped after 9: the stages before the search again, the steps after the third
  const Run second = RunJobOf(*job_, &after_3, 9);
  ASSERT_TRUE(second.result.ok()) << second.result.status();
  EXPECT_EQ(second.stages, (std::vector<std::string>{"sky", "indoor paths", "search"}));
  ASSERT_EQ(second.checkpoints.size(), 6u);
  EXPECT_EQ(Parsed(second.checkpoints.front()).history_size(), 4);
  const v1::SearchCheckpoint after_9 = Parsed(second.checkpoints.back());
  ExpectEqual(Timeless(after_9), Timeless(Parsed(uninterrupted.checkpoints[8])));
  for (int i = 0; i < 3; ++i) ExpectEqual(after_9.history(i), after_3.history(i));  // as kept

  // Resumed to the end: the uninterrupted result, the clock going on from the checkpoint's
  const Run third = RunJobOf(*job_, &after_9);
  ASSERT_TRUE(third.result.ok()) << third.result.status();
  ExpectEqual(Timeless(*third.result), Timeless(full));
  EXPECT_EQ(third.checkpoints.size(), uninterrupted.checkpoints.size() - 9);
  for (int i = 0; i < 9; ++i) ExpectEqual(third.result->history(i), after_9.history(i));
  const double stopped_at = after_9.history(8).elapsed_seconds();
  EXPECT_GE(third.result->history(9).elapsed_seconds(),
            stopped_at + third.result->timings().sky_seconds());
  EXPECT_GE(third.result->timings().total_seconds(), stopped_at);

  // Resumed after its last step: nothing is evaluated, the result is the same
  const v1::SearchCheckpoint at_end = Parsed(uninterrupted.checkpoints.back());
  const Run last = RunJobOf(*job_, &at_end);
  ASSERT_TRUE(last.result.ok()) << last.result.status();
  EXPECT_TRUE(last.checkpoints.empty());
  ExpectEqual(Timeless(*last.result), Timeless(full));
}

// Designs evaluated three at once, on three CPU lanes standing in for GPUs: the steps and
// the result of one at a time, with the evaluations made ahead and dropped counted; a
// checkpoint of one resumes with the other.
TEST_F(JobResumeTest, SeveralCandidatesAtOnceTakeTheSameSteps) {
  const Run one = RunJobOf(*job_);
  ASSERT_TRUE(one.result.ok()) << one.result.status();
  EXPECT_EQ(one.result->candidates_at_once(), 1);  // the CPU's default
  EXPECT_EQ(one.result->evaluations_discarded(), 0);
  ASSERT_GT(one.result->best_over_time_size(), 2);  // improvements after the start

  PreparedJob three_at_once = *job_;
  three_at_once.job.mutable_sampling()->set_candidates_at_once(3);
  EXPECT_EQ(JobContentHash(three_at_once), JobContentHash(*job_));
  const Run three = RunJobOf(three_at_once);
  ASSERT_TRUE(three.result.ok()) << three.result.status();
  EXPECT_EQ(three.result->candidates_at_once(), 3);
  EXPECT_GT(three.result->evaluations_discarded(), 0);
  v1::JobResult same = Timeless(*three.result);
  same.clear_candidates_at_once();
  same.clear_evaluations_discarded();
  same.mutable_job()->mutable_sampling()->clear_candidates_at_once();
  v1::JobResult one_same = Timeless(*one.result);
  one_same.clear_candidates_at_once();
  ExpectEqual(same, one_same);

  const v1::SearchCheckpoint after_5 = Parsed(one.checkpoints[4]);
  const Run resumed = RunJobOf(three_at_once, &after_5);
  ASSERT_TRUE(resumed.result.ok()) << resumed.result.status();
  for (int i = 0; i < one.result->history_size(); ++i) {
    v1::Evaluation a = one.result->history(i), b = resumed.result->history(i);
    a.clear_seconds(), a.clear_elapsed_seconds(), b.clear_seconds(), b.clear_elapsed_seconds();
    ExpectEqual(a, b);
  }
}

// The slats' finish alone, the tilt fixed with the slats half open (QuickFinishJob): white slats
// (reflectance 0.8) send more light into the room than black ones (0), so the search maximizing
// DA moves from black to white, and from white stays there. The best design's final check
// traces its finish too: the one-stage value agrees with the two-stage one.
TEST_F(JobResumeTest, SearchOverTheFinishPicksTheWhiteSlats) {
  for (const bool white_first : {false, true}) {
    SCOPED_TRACE(white_first ? "white first" : "black first");
    v1::Job job = QuickFinishJob(4, white_first ? std::vector<std::string>{"white", "black"}
                                                : std::vector<std::string>{"black", "white"});
    job.mutable_objective()->set_metric(v1::METRIC_DA);
    job.mutable_budget()->set_failed_cycles_to_stop(1);
    absl::StatusOr<PreparedJob> prepared =
        PrepareJob(job, FENESTRA_SOURCE_DIR "/examples/city_office");
    ASSERT_TRUE(prepared.ok()) << prepared.status();
    const Run run = RunJobOf(*prepared);
    ASSERT_TRUE(run.result.ok()) << run.result.status();
    const v1::JobResult& r = *run.result;
    EXPECT_EQ(r.stop_reason(), "all_neighborhoods_failed");
    EXPECT_EQ(r.evaluations(), 2);  // the two finishes, then cache hits
    const double white = white_first ? 0 : 1;
    EXPECT_EQ(r.best_design().at("finish"), white);
    EXPECT_EQ(r.best_design().at("alpha"), 0.8);
    ASSERT_GE(r.history_size(), 2);
    const v1::Estimate &first = r.history(0).value(), &second = r.history(1).value();
    const v1::Estimate& black_value = white_first ? second : first;
    const v1::Estimate& white_value = white_first ? first : second;
    std::printf("DA: black slats %.2f +- %.2f %%, white %.2f +- %.2f %%\n", black_value.value(),
                black_value.standard_error(), white_value.value(), white_value.standard_error());
    EXPECT_GT(white_value.value() - black_value.value(),
              3 * std::hypot(white_value.standard_error(), black_value.standard_error()));
    ASSERT_TRUE(r.has_final_check());
    EXPECT_FALSE(r.final_check().disagrees());
    EXPECT_EQ(r.final_check().two_stage().value(), r.best_value().value());
  }
}

// A search over the tilt and the finish, interrupted after 4 steps and resumed from the
// serialized checkpoint: the steps and result of the uninterrupted run, the finish restored at
// every step; three candidates at once take the same steps.
TEST_F(JobResumeTest, ResumedSearchOverTheFinishEndsAsTheUninterruptedOne) {
  absl::StatusOr<PreparedJob> job =
      PrepareJob(QuickFinishJob(10, {"black", "grey", "white"}, /*tilt_fixed=*/false),
                 FENESTRA_SOURCE_DIR "/examples/city_office");
  ASSERT_TRUE(job.ok()) << job.status();
  const Run uninterrupted = RunJobOf(*job);
  ASSERT_TRUE(uninterrupted.result.ok()) << uninterrupted.result.status();
  const v1::JobResult& full = *uninterrupted.result;
  ASSERT_EQ(full.stop_reason(), "evaluation_budget");
  std::set<double> finishes;
  for (const v1::Evaluation& e : full.history()) finishes.insert(e.design().at("finish"));
  EXPECT_GT(finishes.size(), 1u);  // the search moved across finishes

  const Run first = RunJobOf(*job, nullptr, 4);
  ASSERT_TRUE(first.result.ok()) << first.result.status();
  ASSERT_EQ(first.checkpoints.size(), 4u);
  const v1::SearchCheckpoint after_4 = Parsed(first.checkpoints.back());
  for (const v1::Evaluation& e : after_4.history()) EXPECT_TRUE(e.design().contains("finish"));
  const Run resumed = RunJobOf(*job, &after_4);
  ASSERT_TRUE(resumed.result.ok()) << resumed.result.status();
  EXPECT_EQ(resumed.checkpoints.size(), uninterrupted.checkpoints.size() - 4);
  ExpectEqual(Timeless(*resumed.result), Timeless(full));

  PreparedJob three_at_once = *job;
  three_at_once.job.mutable_sampling()->set_candidates_at_once(3);
  const Run three = RunJobOf(three_at_once, &after_4);
  ASSERT_TRUE(three.result.ok()) << three.result.status();
  ASSERT_EQ(three.result->history_size(), full.history_size());
  for (int i = 0; i < full.history_size(); ++i) {
    v1::Evaluation a = full.history(i), b = three.result->history(i);
    a.clear_seconds(), a.clear_elapsed_seconds(), b.clear_seconds(), b.clear_elapsed_seconds();
    ExpectEqual(a, b);
  }
}

// The four-variable job on the GPU with `evaluations` evaluations and no final check.
absl::StatusOr<v1::Job> GpuFourVariableJob(int evaluations) {
  absl::StatusOr<v1::Job> job =
      ReadJobFile(FENESTRA_SOURCE_DIR "/examples/city_office/four_variables.json");
  if (!job.ok()) return job;
  job->mutable_budget()->set_max_evaluations(evaluations);
  job->mutable_sampling()->set_backend("cuda");
  job->mutable_sampling()->set_final_check(false);
  return job;
}

// On the GPU (none in CI): the four-variable job (150 evaluations) on four lanes, tracers of
// their own on the visible GPUs in turn, takes the steps of one lane, with racing (a design
// at a time per lane) and without (two per lane's launch). The values agree to the GPU's
// summation order (its per-row sums add in the order the lanes finish), the designs and
// decisions exactly.
TEST(JobLanesTest, GpuLanesTakeTheStepsOfOneAtATime) {
  if (CudaDevices() == 0) GTEST_SKIP() << "no CUDA device";
  absl::StatusOr<v1::Job> job = GpuFourVariableJob(150);
  ASSERT_TRUE(job.ok()) << job.status();
  for (const bool racing : {false, true}) {
    job->mutable_sampling()->set_racing(racing);
    std::vector<v1::JobResult> results;
    for (const int lanes : {1, 4}) {
      job->mutable_sampling()->set_candidates_at_once(lanes);
      absl::StatusOr<PreparedJob> prepared =
          PrepareJob(*job, FENESTRA_SOURCE_DIR "/examples/city_office");
      ASSERT_TRUE(prepared.ok()) << prepared.status();
      absl::StatusOr<v1::JobResult> result = RunJob(*prepared, nullptr);
      ASSERT_TRUE(result.ok()) << result.status();
      // Without racing each lane's replay traces kReplayDesignsAtOnce designs in one launch
      EXPECT_EQ(result->candidates_at_once(), racing ? lanes : lanes * kReplayDesignsAtOnce);
      results.push_back(*std::move(result));
    }
    const v1::JobResult &one = results[0], &four = results[1];
    SCOPED_TRACE(racing ? "racing" : "no racing");
    EXPECT_GT(four.evaluations_discarded(), 0);
    EXPECT_GT(one.best_over_time_size(), 3);
    ASSERT_EQ(one.history_size(), four.history_size());
    int partial = 0;
    for (int i = 0; i < one.history_size(); ++i) {
      const v1::Evaluation &a = one.history(i), &b = four.history(i);
      SCOPED_TRACE(absl::StrCat("step ", i));
      ASSERT_EQ(a.design().size(), b.design().size());
      for (const auto& [name, value] : a.design()) EXPECT_EQ(b.design().at(name), value);
      EXPECT_EQ(a.improved(), b.improved());
      EXPECT_EQ(a.cached(), b.cached());
      EXPECT_EQ(a.raced_out(), b.raced_out());
      EXPECT_NEAR(a.value().value(), b.value().value(), 1e-9 * std::abs(a.value().value()));
      partial += a.raced_out() ? 1 : 0;
    }
    if (racing) {
      EXPECT_GT(partial, 0);
    }
    std::printf(
        "%s: %d evaluations, %d improvements, %d raced out; four at once: %d dropped, "
        "evaluations %.3f s against %.3f s\n",
        racing ? "racing" : "no racing", one.evaluations(), one.best_over_time_size() - 1, partial,
        four.evaluations_discarded(), four.timings().evaluation_seconds(),
        one.timings().evaluation_seconds());
  }
}

// On the GPU (none in CI): a job that traces its outdoor stage takes O_b for its annual
// product from the GPU that formed them; one given the same matrix from a cache (on the host
// alone: a matrix computed to be kept holds no GPU memory) uploads them. The steps and
// values are the same.
TEST(JobLanesTest, GpuOutdoorBatchesOnTheDeviceAreTheHostsCopy) {
  if (CudaDevices() == 0) GTEST_SKIP() << "no CUDA device";
  absl::StatusOr<v1::Job> job = GpuFourVariableJob(40);
  ASSERT_TRUE(job.ok()) << job.status();
  absl::StatusOr<PreparedJob> prepared =
      PrepareJob(*job, FENESTRA_SOURCE_DIR "/examples/city_office");
  ASSERT_TRUE(prepared.ok()) << prepared.status();
  absl::StatusOr<OutdoorMatrix> kept =
      ComputeOutdoorMatrix(prepared->scene, prepared->job.sampling(), {}, true);
  absl::StatusOr<OutdoorMatrix> cached =
      ComputeOutdoorMatrix(prepared->scene, prepared->job.sampling());
  ASSERT_TRUE(kept.ok() && cached.ok()) << kept.status() << cached.status();
  EXPECT_NE(kept->batches_on_device.data, nullptr);
  EXPECT_GE(kept->batches_on_device.device, 0);
  EXPECT_EQ(cached->batches_on_device.data, nullptr);

  absl::StatusOr<v1::JobResult> traced = RunJob(*prepared, nullptr);
  absl::StatusOr<v1::JobResult> from_cache = RunJob(*prepared, &*cached);
  ASSERT_TRUE(traced.ok() && from_cache.ok()) << traced.status() << from_cache.status();
  ASSERT_GE(traced->history_size(), 40);  // cached steps come on top
  ASSERT_EQ(traced->history_size(), from_cache->history_size());
  for (int i = 0; i < traced->history_size(); ++i) {
    const v1::Evaluation &a = traced->history(i), &b = from_cache->history(i);
    SCOPED_TRACE(absl::StrCat("step ", i));
    for (const auto& [name, value] : a.design()) EXPECT_EQ(b.design().at(name), value);
    EXPECT_EQ(a.improved(), b.improved());
    // E's sums differ in the order of the GPU's atomic additions only
    EXPECT_NEAR(a.value().value(), b.value().value(), 1e-9 * std::abs(a.value().value()));
    EXPECT_NEAR(a.value().standard_error(), b.value().standard_error(),
                1e-9 * std::abs(a.value().standard_error()) + 1e-12);
  }
}

// A checkpoint belongs to one job: any change of the job's content refuses it.
TEST_F(JobResumeTest, CheckpointOfAnotherJobIsRefused) {
  const v1::SearchCheckpoint checkpoint = Parsed(AfterSixSteps());
  absl::StatusOr<PreparedJob> same =
      PrepareJob(QuickJob(14), FENESTRA_SOURCE_DIR "/examples/city_office");
  ASSERT_TRUE(same.ok()) << same.status();
  EXPECT_EQ(JobContentHash(*same), JobContentHash(*job_));

  for (const auto& change : std::vector<std::function<void(v1::Job&)>>{
           [](v1::Job& j) { j.mutable_budget()->set_max_evaluations(15); },
           [](v1::Job& j) { j.mutable_sampling()->set_seed(2); },
           [](v1::Job& j) { j.mutable_metrics()->set_udi_upper_lux(2500); }}) {
    v1::Job job = QuickJob(14);
    change(job);
    absl::StatusOr<PreparedJob> other =
        PrepareJob(job, FENESTRA_SOURCE_DIR "/examples/city_office");
    ASSERT_TRUE(other.ok()) << other.status();
    EXPECT_NE(JobContentHash(*other), JobContentHash(*job_));
    EXPECT_EQ(Refusal(*other, checkpoint),
              "search checkpoint: it belongs to another job (its content hash differs)");
  }

  // The scene's and the weather's content count, not where they were read from
  PreparedJob moved = *job_;
  moved.job.set_scene_file("/elsewhere/scene.json");
  moved.weather_file = "/elsewhere/weather.epw";
  EXPECT_EQ(JobContentHash(moved), JobContentHash(*job_));
  PreparedJob other_scene = *job_;
  other_scene.scene.materials[0].reflectance *= 0.9;
  EXPECT_NE(JobContentHash(other_scene), JobContentHash(*job_));
  PreparedJob other_weather = *job_;
  other_weather.weather.records[4000].diffuse_horizontal_wm2 += 1;
  EXPECT_NE(JobContentHash(other_weather), JobContentHash(*job_));
  EXPECT_NE(Refusal(other_weather, checkpoint).find("another job"), std::string::npos);
}

// Bytes that are no checkpoint, a format this build does not read, and a history the job's
// search does not make are refused with what is wrong, before any stage.
TEST_F(JobResumeTest, CorruptedOrUnknownCheckpointIsRefused) {
  const std::string bytes = AfterSixSteps();

  for (const std::string& bad : {std::string("\x0f\x01", 2), bytes.substr(0, bytes.size() - 3)}) {
    absl::StatusOr<v1::SearchCheckpoint> parsed = ParseSearchCheckpoint(bad);
    EXPECT_EQ(parsed.status().code(), absl::StatusCode::kDataLoss);
    EXPECT_NE(parsed.status().message().find("not a serialized fenestra.v1.SearchCheckpoint"),
              std::string::npos)
        << parsed.status();
  }
  v1::SearchCheckpoint later = Parsed(bytes);
  later.set_format(2);
  const std::string expected = "search checkpoint: format 2, but this build reads format 1 only";
  EXPECT_EQ(ParseSearchCheckpoint(later.SerializeAsString()).status().message(), expected);
  EXPECT_EQ(Refusal(*job_, later), expected);
  EXPECT_EQ(ParseSearchCheckpoint("").status().message(),
            "search checkpoint: format 0, but this build reads format 1 only");

  v1::SearchCheckpoint moved = Parsed(bytes);
  (*moved.mutable_history(2)->mutable_design())["alpha"] += 0.01;
  EXPECT_NE(Refusal(*job_, moved)
                .find("search checkpoint: resume: step 2 differs from this "
                      "search's (design ("),
            std::string::npos);
  v1::SearchCheckpoint flipped = Parsed(bytes);
  flipped.mutable_history(4)->set_improved(!flipped.history(4).improved());
  EXPECT_NE(Refusal(*job_, flipped).find("step 4 differs from this search's (improvement)"),
            std::string::npos);
  v1::SearchCheckpoint missing = Parsed(bytes);
  missing.mutable_history(1)->mutable_design()->erase("alpha");
  EXPECT_EQ(Refusal(*job_, missing), "search checkpoint: step 1 has no value of variable 'alpha'");
  v1::SearchCheckpoint empty = Parsed(bytes);
  empty.clear_history();
  EXPECT_EQ(Refusal(*job_, empty), "search checkpoint: no steps");
}
}  // namespace
}  // namespace fenestra
