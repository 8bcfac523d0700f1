// The slats' finish as a design variable: indices, names, and the design a job's values make.
#include "core/optimize/design_variables.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <limits>
#include <map>
#include <string>

#include "core/optimize/job.h"
#include "core/optimize/job_proto.h"
#include "tests/quick_job.h"

namespace fenestra {
namespace {

using ::testing::HasSubstr;

TEST(DesignVariablesTest, FinishIndexIsAWholeNumberInRange) {
  EXPECT_EQ(FinishIndex(0, 3), 0u);
  EXPECT_EQ(FinishIndex(2, 3), 2u);
  for (const double bad : {-1.0, 3.0, 0.5, -1e-300, std::numeric_limits<double>::quiet_NaN(),
                           std::numeric_limits<double>::infinity()}) {
    EXPECT_FALSE(FinishIndex(bad, 3)) << bad;
  }
  EXPECT_FALSE(FinishIndex(0, 0));
}

TEST(DesignVariablesTest, FinishNamesItsMaterials) {
  v1::BlindFinish finish;
  finish.set_material("white");
  EXPECT_EQ(FinishName(finish), "white");
  finish.set_outer_material("white");
  EXPECT_EQ(FinishName(finish), "white");
  finish.set_outer_material("aluminium");
  EXPECT_EQ(FinishName(finish), "white / aluminium outer");

  v1::Job job = QuickFinishJob(4, {"black", "white"});
  job.mutable_variables(4)->mutable_finishes(1)->set_outer_material("grey");
  EXPECT_EQ(FinishNameAt(job, 0), "black");
  EXPECT_EQ(FinishNameAt(job, 1), "white / grey outer");
  EXPECT_EQ(FinishNameAt(job, 2), "");
  EXPECT_EQ(FinishNameAt(QuickJob(), 0), "");
}

// Two designs of a job that differ by their finish alone differ (the racer's and the tallies'
// keys are designs), and carry their finish's materials; the search's points differ too (its
// cache's keys).
TEST(DesignVariablesTest, DesignsOfTwoFinishesDiffer) {
  absl::StatusOr<PreparedJob> job = ValidateJob(QuickFinishJob(4, {"black", "grey", "white"}),
                                                FENESTRA_SOURCE_DIR "/examples/city_office");
  ASSERT_TRUE(job.ok()) << job.status();
  const std::vector<Material>& materials = job->scene.materials;
  std::vector<double> x = {0.8, 0.15, 0, 0.01, 0};
  const BlindDesign black = DesignAt(*job, x);
  x[4] = 2;
  const BlindDesign white = DesignAt(*job, x);
  EXPECT_NE(black, white);
  ASSERT_TRUE(black.finish && white.finish);
  EXPECT_EQ(materials[black.finish->material].name, "black");
  EXPECT_EQ(materials[white.finish->outer_material].name, "white");
  EXPECT_EQ(black.tilt_rad, white.tilt_rad);
  const SearchSettings settings = MakeSearchSettings(job->job);
  ASSERT_EQ(settings.variables.size(), 5u);
  EXPECT_TRUE(settings.variables[4].categorical);
  EXPECT_EQ(settings.variables[4].step, 1);
  EXPECT_EQ(settings.variables[4].upper, 2);
  EXPECT_FALSE(settings.variables[0].categorical);
  // Without a finish variable, the spec's finish: no finish in the design
  absl::StatusOr<PreparedJob> plain =
      ValidateJob(QuickJob(), FENESTRA_SOURCE_DIR "/examples/city_office");
  ASSERT_TRUE(plain.ok()) << plain.status();
  EXPECT_FALSE(DesignAt(*plain, {0.8, 0.15, 0, 0.01}).finish);
}

// The design of a result's values (its best design) with the job's finish.
TEST(DesignVariablesTest, JobDesignWithOverridesResolvesTheFinish) {
  const v1::Job job = QuickFinishJob(4, {"black", "white"});
  absl::StatusOr<Scene> scene =
      BuildScene(job.scene(), FENESTRA_SOURCE_DIR "/examples/city_office/job.scene");
  ASSERT_TRUE(scene.ok()) << scene.status();
  absl::StatusOr<BlindDesign> design =
      JobDesignWithOverrides(*scene, job, {{"alpha", 0.6}, {"finish", 1}});
  ASSERT_TRUE(design.ok()) << design.status();
  EXPECT_EQ(design->tilt_rad, 0.6);
  ASSERT_TRUE(design->finish);
  EXPECT_EQ(scene->materials[design->finish->material].name, "white");
  EXPECT_EQ(scene->materials[FinishOf(*scene->blind(), *design).outer_material].name, "white");
  // Without a finish value: the scene's own slats
  design = JobDesignWithOverrides(*scene, job, {{"alpha", 0.6}});
  ASSERT_TRUE(design.ok()) << design.status();
  EXPECT_FALSE(design->finish);
  EXPECT_THAT(std::string(JobDesignWithOverrides(*scene, job, {{"finish", 2}}).status().message()),
              HasSubstr("finish 2 is not an index of the 2 finishes"));
  EXPECT_THAT(
      std::string(JobDesignWithOverrides(*scene, QuickJob(), {{"finish", 0}}).status().message()),
      HasSubstr("the job has no finish variable"));
  EXPECT_THAT(std::string(DesignWithOverrides(*scene, {{"finish", 0}}).status().message()),
              HasSubstr("unknown design variable 'finish'"));
}

}  // namespace
}  // namespace fenestra
