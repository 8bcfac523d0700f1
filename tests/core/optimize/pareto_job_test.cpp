// A job's Pareto search (core/optimize/job_pareto.h, pareto_search.h): the front of the sunny
// office's sDA against hours of glare, its members non-dominated beyond their errors, the
// hypervolume growing, a resume mid-generation giving the same search, the comfort metrics
// of a design against the one-stage glare of its views, and what the door refuses. Seeds are
// fixed; tolerances in standard errors.
#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

#include "core/geometry/scene_proto.h"
#include "core/optimize/job.h"
#include "core/optimize/nsga2.h"
#include "core/optimize/pareto_search.h"
#include "core/optimize/view_glare.h"
#include "core/sky/epw.h"

namespace fenestra {
namespace {

const std::string kOfficeDir = FENESTRA_SOURCE_DIR "/examples/sunny_office";

// examples/sunny_office/pareto_sda_glare.json on the CPU with few paths: `population` designs
// over `generations` generations.
v1::Job QuickParetoJob(int population, int generations) {
  absl::StatusOr<v1::Job> job = ReadJobFile(kOfficeDir + "/pareto_sda_glare.json");
  EXPECT_TRUE(job.ok()) << job.status();
  job->mutable_pareto()->set_population(population);
  job->mutable_budget()->set_max_evaluations(population * generations);
  v1::Sampling& s = *job->mutable_sampling();
  s.set_indoor_paths_per_sensor(1024);
  s.set_outdoor_paths(40000);
  s.set_backend("cpu");
  s.set_window_columns(1);
  s.set_window_rows(1);
  s.set_final_check(false);
  return *job;
}

absl::StatusOr<v1::JobResult> RunOffice(const v1::Job& job, const JobCallbacks& callbacks = {},
                                  const v1::SearchCheckpoint* resume = nullptr) {
  absl::StatusOr<PreparedJob> prepared = PrepareJob(job, kOfficeDir);
  if (!prepared.ok()) return prepared.status();
  return RunJob(*prepared, nullptr, callbacks, resume);
}

Nsga2Member Member(const v1::FrontMember& m) {
  // Both minimized: -sDA, glare hours
  return {{},
          {-m.objectives(0).value(), m.objectives(1).value()},
          {m.objectives(0).standard_error(), m.objectives(1).standard_error()}};
}

TEST(ParetoJobTest, FrontOfDaylightAgainstGlareResumesMidGeneration) {
  const v1::Job job = QuickParetoJob(8, 3);
  // The whole run, and its checkpoint after the fourth step of the second generation
  v1::SearchCheckpoint middle;
  JobCallbacks callbacks;
  callbacks.checkpoint = [&](const v1::SearchCheckpoint& c) {
    if (c.history_size() == 12) middle = c;
  };
  absl::StatusOr<v1::JobResult> whole = RunOffice(job, callbacks);
  ASSERT_TRUE(whole.ok()) << whole.status();
  ASSERT_EQ(whole->history_size(), 24);
  ASSERT_TRUE(whole->has_pareto());
  const v1::ParetoResult& p = whole->pareto();
  EXPECT_EQ(p.generations(), 3);
  ASSERT_EQ(p.hypervolume_size(), 3);
  for (int g = 1; g < 3; ++g) EXPECT_GE(p.hypervolume(g), p.hypervolume(g - 1));
  EXPECT_GT(p.hypervolume(2), 0.0);
  ASSERT_GE(p.front_size(), 2);
  // No member dominates another beyond one standard error (the job's default), and each
  // member's objectives are its step's
  for (int a = 0; a < p.front_size(); ++a) {
    const v1::Evaluation& step = whole->history(p.front(a).evaluation());
    EXPECT_FALSE(step.cached());
    EXPECT_EQ(step.objectives(0).value(), p.front(a).objectives(0).value());
    EXPECT_TRUE(p.front(a).metrics().has_glare_hours());
    EXPECT_EQ(p.front(a).metrics().glare_hours().value(), p.front(a).objectives(1).value());
    EXPECT_GT(p.front(a).metrics().glare_hours().standard_error(), 0.0);
    for (int b = 0; b < p.front_size(); ++b) {
      EXPECT_FALSE(a != b && Dominates(Member(p.front(a)), Member(p.front(b)), 1.0));
    }
  }
  // The steps' generations and the best design: the front's best sDA
  EXPECT_EQ(whole->history(0).generation(), 0);
  EXPECT_EQ(whole->history(23).generation(), 2);
  EXPECT_EQ(whole->best_value().value(), p.front(0).objectives(0).value());  // best first
  for (int a = 1; a < p.front_size(); ++a) {
    EXPECT_LE(p.front(a).objectives(0).value(), p.front(a - 1).objectives(0).value());
  }

  ASSERT_EQ(middle.history_size(), 12);
  absl::StatusOr<v1::JobResult> resumed = RunOffice(job, {}, &middle);
  ASSERT_TRUE(resumed.ok()) << resumed.status();
  ASSERT_EQ(resumed->history_size(), 24);
  for (int s = 0; s < 24; ++s) {
    for (const char* v : {"alpha", "spacing"}) {
      EXPECT_EQ(resumed->history(s).design().at(v), whole->history(s).design().at(v)) << s;
    }
    EXPECT_EQ(resumed->history(s).objectives(1).value(), whole->history(s).objectives(1).value());
  }
  ASSERT_EQ(resumed->pareto().front_size(), p.front_size());
  for (int a = 0; a < p.front_size(); ++a) {
    EXPECT_EQ(resumed->pareto().front(a).evaluation(), p.front(a).evaluation());
  }
  // A checkpoint whose history this search does not make is refused
  v1::SearchCheckpoint wrong = middle;
  (*wrong.mutable_history(9)->mutable_design())["alpha"] += 0.1;
  EXPECT_EQ(RunOffice(job, {}, &wrong).status().code(), absl::StatusCode::kInvalidArgument);
}

// The comfort metrics of the two-stage search at a design against the one-stage glare of its
// views (view_glare.h): the mean glare autonomy within 3 combined standard errors and 1
// point, and the hours of glare between the worst view's and the sum of the views'.
TEST(ParetoJobTest, GlareOfTheSearchIsTheViewsGlare) {
  v1::Job job = QuickParetoJob(4, 1);
  job.mutable_sampling()->set_indoor_paths_per_sensor(16000);
  job.mutable_variables(0)->set_start(1.2);
  job.mutable_variables(0)->set_fixed(true);
  job.mutable_variables(1)->set_fixed(true);
  absl::StatusOr<v1::JobResult> result = RunOffice(job);
  ASSERT_TRUE(result.ok()) << result.status();
  const v1::Metrics& m = result->best_metrics();
  ASSERT_TRUE(m.has_glare_autonomy());
  ASSERT_EQ(result->best_glare_size(), 2);  // the one-stage glare at the end
  double autonomy = 0, autonomy_variance = 0, worst = 0, sum = 0;
  for (const v1::ViewGlare& g : result->best_glare()) {
    autonomy += g.autonomy().value() / 2;
    autonomy_variance += std::pow(g.autonomy().standard_error() / 2, 2);
    worst = std::max(worst, 100 - g.autonomy().value());
    sum += 100 - g.autonomy().value();
  }
  const double combined =
      std::sqrt(autonomy_variance + std::pow(m.glare_autonomy().standard_error(), 2));
  EXPECT_NEAR(m.glare_autonomy().value(), autonomy, 3 * combined + 1.0);
  EXPECT_GT(m.glare_hours().value(), worst - 3 * combined - 1.0);
  EXPECT_LT(m.glare_hours().value(), sum + 3 * combined + 1.0);
  EXPECT_GT(m.glare_hours().value(), 1.0);  // slats at 1.2 rad let the sun reach the desk
}

TEST(ParetoJobTest, TheDoorRefusesBadParetoAndComfortSettings) {
  const auto refused = [](const v1::Job& job, const std::string& field) {
    absl::StatusOr<PreparedJob> prepared = PrepareJob(job, kOfficeDir);
    EXPECT_EQ(prepared.status().code(), absl::StatusCode::kInvalidArgument) << field;
    EXPECT_NE(prepared.status().message().find(field), std::string::npos)
        << prepared.status().message();
  };
  v1::Job one = QuickParetoJob(8, 2);
  one.mutable_pareto()->mutable_objectives()->RemoveLast();
  refused(one, "pareto.objectives");
  v1::Job odd = QuickParetoJob(8, 2);
  odd.mutable_pareto()->set_population(7);
  refused(odd, "pareto.population");
  v1::Job twice = QuickParetoJob(8, 2);
  twice.mutable_pareto()->mutable_objectives(1)->set_metric(v1::METRIC_SDA);
  refused(twice, "pareto.objectives[1].metric");
  v1::Job target = QuickParetoJob(8, 2);
  target.mutable_pareto()->mutable_objectives(0)->set_goal(v1::GOAL_TARGET);
  refused(target, "pareto.objectives[0].goal");
  v1::Job both = QuickParetoJob(8, 2);
  both.mutable_objective()->set_metric(v1::METRIC_DA);
  refused(both, "objective");
  v1::Job small = QuickParetoJob(8, 2);
  small.mutable_budget()->set_max_evaluations(6);
  refused(small, "budget.max_evaluations");
  v1::Job threshold = QuickParetoJob(8, 2);
  threshold.mutable_metrics()->set_glare_threshold(1.5);
  refused(threshold, "metrics.glare_threshold");
  v1::Job month = QuickParetoJob(8, 2);
  month.mutable_metrics()->set_cooling_start_month(13);
  refused(month, "metrics.cooling_start_month");
  // Glare without views
  v1::Job blind_eyes = QuickParetoJob(8, 2);
  absl::StatusOr<v1::Scene> scene = ReadSceneProto(kOfficeDir + "/scene.json");
  ASSERT_TRUE(scene.ok());
  scene->clear_views();
  scene->mutable_site()->set_weather_file(
      FENESTRA_SOURCE_DIR "/examples/weather/USA_AZ_Phoenix-Sky.Harbor.Intl.AP.722780_TMY3.epw");
  blind_eyes.clear_scene_file();
  *blind_eyes.mutable_scene() = *scene;
  refused(blind_eyes, "glare metrics need view points");
  // A gain bound in kWh is no share
  v1::Job gain = QuickParetoJob(8, 2);
  v1::Constraint& c = *gain.mutable_objective()->add_constraints();
  c.set_metric(v1::METRIC_COOLING_SOLAR_GAIN);
  c.set_bound(v1::Constraint::AT_MOST);
  c.set_value(500);
  EXPECT_TRUE(PrepareJob(gain, kOfficeDir).ok());
  c.set_value(-1);
  refused(gain, "objective.constraints[0].value");
}

}  // namespace
}  // namespace fenestra
