#include "server/limits.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cstdint>
#include <limits>
#include <string>

#include "server/config.h"

namespace fenestra {
namespace {

using ::testing::HasSubstr;

v1::Limits DefaultLimits() { return ResolveConfig(v1::DaemonConfig())->limits(); }

v1::Scene SceneWithBlind(double min_width_m) {
  v1::Scene scene;
  scene.mutable_window()->set_width_m(2);
  scene.mutable_window()->set_height_m(1.5);
  v1::Surface& floor = *scene.add_surfaces();
  for (int i = 0; i < 4; ++i) floor.mutable_polygon()->add_vertices();
  scene.add_surfaces()->mutable_box();
  scene.mutable_blind()->mutable_slat_width_m()->set_value(0.1);
  scene.mutable_blind()->mutable_slat_width_m()->set_min(min_width_m);
  return scene;
}

TEST(LimitsTest, TrianglesCountPolygonsBoxesAndTheBlindAtItsMostSlats) {
  v1::Limits limits = DefaultLimits();
  // 2 + 12 + 12 x (1.5 / 0.125 + 1) = 170 triangles
  limits.set_max_triangles(170);
  EXPECT_TRUE(CheckSceneLimits(SceneWithBlind(0.125), limits).ok());
  limits.set_max_triangles(169);
  const absl::Status status = CheckSceneLimits(SceneWithBlind(0.125), limits);
  EXPECT_EQ(status.code(), absl::StatusCode::kInvalidArgument);
  EXPECT_THAT(status.message(), HasSubstr("max_triangles = 169"));
  EXPECT_THAT(status.message(), HasSubstr("170"));
  // A job's narrower width range counts
  limits.set_max_triangles(2'000'000);
  EXPECT_THAT(CheckSceneLimits(SceneWithBlind(0.1), limits, 1e-6).message(),
              HasSubstr("max_triangles"));
}

TEST(LimitsTest, BlindsInTheWindowsListCountToo) {
  // The same window and blind as windows[0], twice: twice the slats
  v1::Scene one = SceneWithBlind(0.125);
  v1::Scene listed = one;
  listed.clear_window();
  listed.clear_blind();
  for (int k = 0; k < 2; ++k) {
    v1::Window& w = *listed.add_windows();
    w = one.window();
    *w.mutable_blind() = one.blind();
  }
  v1::Limits limits = DefaultLimits();
  // 2 + 12 + 2 x 12 x (1.5 / 0.125 + 1) = 326 triangles
  limits.set_max_triangles(326);
  EXPECT_TRUE(CheckSceneLimits(listed, limits).ok());
  limits.set_max_triangles(325);
  EXPECT_THAT(CheckSceneLimits(listed, limits).message(), HasSubstr("326"));
}

TEST(LimitsTest, SensorGridsAreExpanded) {
  v1::Scene scene;
  scene.add_sensors();
  v1::SensorGrid& grid = *scene.add_sensor_grids();
  grid.set_x_max_m(9.9);  // 10 x 5 cells
  grid.set_y_max_m(4.9);
  grid.set_spacing_m(1);
  v1::Limits limits = DefaultLimits();
  limits.set_max_sensors(51);
  EXPECT_TRUE(CheckSceneLimits(scene, limits).ok());
  limits.set_max_sensors(50);
  EXPECT_THAT(CheckSceneLimits(scene, limits).message(), HasSubstr("max_sensors = 50"));
  grid.set_spacing_m(1e-6);
  limits.set_max_sensors(10'000);
  EXPECT_THAT(CheckSceneLimits(scene, limits).message(), HasSubstr("max_sensors"));
  // View points count as the sensors they are traced as
  grid.set_spacing_m(1);
  limits.set_max_sensors(51);
  scene.add_views();
  EXPECT_THAT(CheckSceneLimits(scene, limits).message(), HasSubstr("max_sensors = 51"));
}

TEST(LimitsTest, PathsAndEvaluations) {
  const v1::Limits limits = DefaultLimits();
  v1::Sampling sampling;
  sampling.set_outdoor_paths(2'000'000'000);
  EXPECT_THAT(CheckSamplingLimits(sampling, limits, false).message(),
              HasSubstr("max_outdoor_paths = 1000000000"));
  sampling.set_outdoor_paths(1000);
  sampling.set_indoor_paths_per_sensor(20'000'000);
  EXPECT_TRUE(CheckSamplingLimits(sampling, limits, false).ok());
  EXPECT_THAT(CheckSamplingLimits(sampling, limits, true).message(),
              HasSubstr("max_indoor_paths_per_sensor"));
  // Designs at once: each holds its own copy of the indoor records
  sampling.set_indoor_paths_per_sensor(1000);
  for (const int n : {0, 1, 4}) {
    sampling.set_candidates_at_once(n);
    EXPECT_TRUE(CheckSamplingLimits(sampling, limits, true).ok()) << n;
  }
  for (const int n : {5, 16, std::numeric_limits<int32_t>::max()}) {
    sampling.set_candidates_at_once(n);
    EXPECT_THAT(CheckSamplingLimits(sampling, limits, true).message(),
                HasSubstr("sampling.candidates_at_once is " + std::to_string(n) +
                          ", above this server's limit max_candidates_at_once = 4"));
  }
  sampling.set_candidates_at_once(0);
  v1::Budget budget;
  EXPECT_TRUE(CheckBudgetLimits(budget, limits).ok());  // the default, 150
  budget.set_max_evaluations(10'001);
  EXPECT_THAT(CheckBudgetLimits(budget, limits).message(), HasSubstr("max_evaluations = 10000"));
}

TEST(LimitsTest, ObjMeshesMustBeInlined) {
  v1::Scene scene;
  v1::Surface& s = *scene.add_surfaces();
  s.set_name("city");
  s.mutable_obj()->set_path("city.obj");
  const absl::Status status = CheckInlineScene(scene);
  EXPECT_EQ(status.code(), absl::StatusCode::kInvalidArgument);
  EXPECT_THAT(status.message(), HasSubstr("city.obj"));
  EXPECT_THAT(status.message(), HasSubstr("inline"));
}

}  // namespace
}  // namespace fenestra
