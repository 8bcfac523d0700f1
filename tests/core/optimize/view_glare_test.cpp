// View points and their glare (core/optimize/view_glare.h): views in scene files, checked at
// the door as sensors are; the sunny office's glare follows its blind and the view's direction.
// Tolerances are in standard errors; seeds are fixed.
#include "core/optimize/view_glare.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "core/geometry/scene_proto.h"
#include "core/metrics/occupancy.h"
#include "core/optimize/job.h"
#include "core/sky/epw.h"
#include "core/trace/room_check.h"
#include "tests/core/optimize/scene_year.h"
#include "tests/quick_job.h"

namespace fenestra {
namespace {

const std::string kSunnyOffice = FENESTRA_SOURCE_DIR "/examples/sunny_office/scene.json";

v1::ViewPoint View(const std::string& name, double x, double y, double z, double dx, double dy,
                   double dz) {
  v1::ViewPoint v;
  v.set_name(name);
  v.mutable_position()->set_x(x), v.mutable_position()->set_y(y), v.mutable_position()->set_z(z);
  v.mutable_direction()->set_x(dx), v.mutable_direction()->set_y(dy);
  v.mutable_direction()->set_z(dz);
  return v;
}

// The sunny office (its window in the wall y = 0, facing south) with its desk 2 m in: an eye
// looking at the window and one looking along the wall; the second left unnamed here.
v1::Scene SunnyOfficeWithViews() {
  absl::StatusOr<v1::Scene> proto = ReadSceneProto(kSunnyOffice);
  EXPECT_TRUE(proto.ok()) << proto.status();
  EXPECT_EQ(proto->views_size(), 2);
  proto->mutable_views(1)->clear_name();
  return *proto;
}

TEST(ViewGlareTest, ViewsBuildWithTheirDefaultsAndRoundTrip) {
  absl::StatusOr<Scene> scene = ValidateScene(SunnyOfficeWithViews(), kSunnyOffice);
  ASSERT_TRUE(scene.ok()) << scene.status();
  ASSERT_EQ(scene->views.size(), 2u);
  EXPECT_EQ(scene->views[0].name, "desk facing the window");
  EXPECT_EQ(scene->views[1].name, "v2");  // by its place in the list
  EXPECT_EQ(scene->views[1].up.z, 1.0);   // unset: +z
  EXPECT_EQ(scene->views[1].field, "views[1]");
  const Sensor eye = EyeSensor(scene->views[0]);
  EXPECT_EQ(eye.direction.y, -1.0);
  // The self-contained form keeps them
  absl::StatusOr<Scene> again = BuildScene(SelfContainedSceneProto(*scene), kSunnyOffice);
  ASSERT_TRUE(again.ok()) << again.status();
  ASSERT_EQ(again->views.size(), 2u);
  EXPECT_EQ(again->views[1].name, "v2");
  EXPECT_EQ(again->views[0].position.y, 2.0);
}

TEST(ViewGlareTest, BadViewsAreRefusedNamingTheirField) {
  const auto error = [](const v1::Scene& proto) {
    absl::StatusOr<Scene> scene = ValidateScene(proto, kSunnyOffice);
    EXPECT_EQ(scene.status().code(), absl::StatusCode::kInvalidArgument);
    return std::string(scene.status().message());
  };
  v1::Scene along = SunnyOfficeWithViews();
  along.mutable_views(1)->mutable_up()->set_x(2);
  EXPECT_NE(error(along).find("views[1].up: must not lie along the view direction"),
            std::string::npos);
  v1::Scene same = SunnyOfficeWithViews();
  same.mutable_views(1)->set_name("desk facing the window");
  EXPECT_NE(error(same).find("views[1].name"), std::string::npos);
  v1::Scene blind = SunnyOfficeWithViews();
  blind.mutable_views(0)->mutable_direction()->set_y(0);
  EXPECT_NE(error(blind).find("views[0].direction"), std::string::npos);
  v1::Scene outside = SunnyOfficeWithViews();
  outside.mutable_views(0)->mutable_position()->set_y(-3);  // beyond the window
  EXPECT_NE(error(outside).find("views[0]"), std::string::npos);
  v1::Scene many = SunnyOfficeWithViews();
  for (int i = 0; i < kMaxSceneViews; ++i) *many.add_views() = View("", 0, 2, 4.2, 0, -1, 0);
  EXPECT_NE(error(many).find("at most 1000 views"), std::string::npos);
}

using Year = SceneYear;
Year PhoenixYear(const Scene& scene) { return YearOf(scene); }

ViewGlareResult Glare(const Scene& scene, const Year& year, double alpha) {
  ViewGlareOptions options;
  options.tracing.paths_per_sensor = 8000;
  options.tracing.batches = 8;
  options.tracing.seed = 3;
  absl::StatusOr<BlindDesign> design = DesignWithOverrides(scene, {{"alpha", alpha}});
  EXPECT_TRUE(design.ok()) << design.status();
  absl::StatusOr<ViewGlareResult> r =
      ComputeViewGlare(scene, *design, year.sky, year.occupied, options);
  EXPECT_TRUE(r.ok()) << r.status();
  return *std::move(r);
}

// Closed slats (alpha 0, in the window plane) against open ones (alpha 1.2): the eye facing
// the window gets more glare with the slats open, beyond 5 standard errors, and more than the
// eye looking along the wall; every figure is finite, the hourly DGP without the sun is Ev's
// by hand, and an hour the sun's beam reaches the eye facing the window is intolerable.
TEST(ViewGlareTest, GlareFollowsTheBlindAndTheViewDirection) {
  absl::StatusOr<Scene> scene = ValidateScene(SunnyOfficeWithViews(), kSunnyOffice);
  ASSERT_TRUE(scene.ok()) << scene.status();
  const Year year = PhoenixYear(*scene);
  const ViewGlareResult closed = Glare(*scene, year, 0.0);
  const ViewGlareResult open = Glare(*scene, year, 1.2);
  ASSERT_EQ(open.views.size(), 2u);
  const auto apart = [](double a, double sa, double b, double sb) {
    return (a - b) / std::hypot(sa, sb);
  };
  EXPECT_GT(apart(open.views[0].mean_dgp, open.mean_dgp_standard_error[0], closed.views[0].mean_dgp,
                  closed.mean_dgp_standard_error[0]),
            5.0);
  EXPECT_GT(apart(closed.views[0].autonomy_percent, closed.autonomy_standard_error[0],
                  open.views[0].autonomy_percent, open.autonomy_standard_error[0]),
            5.0);
  EXPECT_GT(apart(open.views[0].mean_dgp, open.mean_dgp_standard_error[0], open.views[1].mean_dgp,
                  open.mean_dgp_standard_error[1]),
            5.0);
  EXPECT_EQ(open.views[0].occupied_hours, 3650);
  EXPECT_GT(open.views[0].class_hours[3], 0);  // intolerable hours with the slats open
  ASSERT_GT(open.views[0].sunlit_hours, 0);
  for (Eigen::Index s = 0; s < open.sun_lux.cols(); ++s) {
    if (open.sun_lux(0, s) > 0) {
      EXPECT_GT(open.dgp(0, s), 0.45) << "step " << s;
    }
  }
  for (const ViewGlareResult* r : {&closed, &open}) {
    EXPECT_TRUE(r->eye_lux.allFinite() && r->eye_lux_standard_error.allFinite());
    EXPECT_GE(r->eye_lux.minCoeff(), 0.0);
    EXPECT_GT(r->eye_lux.maxCoeff(), 1000.0);
    // The hours without the sun's beam at the eye have Ev's DGP alone, by hand; the mean
    // DGP is that of the hours
    double sum = 0;
    int sunless = 0;
    for (Eigen::Index s = 0; s < r->eye_lux.cols(); ++s) {
      if (r->sun_lux(0, s) == 0 && r->eye_lux(0, s) > 0) {
        EXPECT_NEAR(r->dgp(0, s), std::min(1.0, 5.87e-5 * r->eye_lux(0, s) + 0.159), 1e-12);
        ++sunless;
      }
      if (year.occupied[s]) sum += r->dgp(0, s);
    }
    EXPECT_GT(sunless, 1000);
    EXPECT_NEAR(r->views[0].mean_dgp, sum / 3650, 1e-9);
  }
}

TEST(ViewGlareTest, MissingViewsOrBadOptionsAreRefused) {
  absl::StatusOr<Scene> scene = ValidateScene(SunnyOfficeWithViews(), kSunnyOffice);
  ASSERT_TRUE(scene.ok()) << scene.status();
  const Year year = PhoenixYear(*scene);
  const BlindDesign design = DefaultDesign(*scene);
  ViewGlareOptions one_batch;
  one_batch.tracing.batches = 1;
  EXPECT_EQ(ComputeViewGlare(*scene, design, year.sky, year.occupied, one_batch).status().code(),
            absl::StatusCode::kInvalidArgument);
  EXPECT_EQ(ComputeViewGlare(*scene, design, year.sky, {true}, {}).status().code(),
            absl::StatusCode::kInvalidArgument);
  Scene none = *scene;
  none.views.clear();
  EXPECT_EQ(ComputeViewGlare(none, design, year.sky, year.occupied, {}).status().code(),
            absl::StatusCode::kInvalidArgument);
}

// A job on a scene with views reports the glare at each of them at its best design: the
// city office (a deep courtyard: little glare) with an eye looking at its window and one away.
TEST(ViewGlareTest, AJobReportsTheGlareOfItsBestDesign) {
  v1::Job job = QuickJob(3);
  absl::StatusOr<v1::Scene> scene =
      ReadSceneProto(FENESTRA_SOURCE_DIR "/examples/city_office/scene.json");
  ASSERT_TRUE(scene.ok()) << scene.status();
  *scene->add_views() = View("toward the window", 0, -2, 7.2, 0, 1, 0);
  *scene->add_views() = View("toward the back", 0, -2, 7.2, 0, -1, 0);
  job.clear_scene_file();
  *job.mutable_scene() = *std::move(scene);
  absl::StatusOr<v1::JobResult> result = RunQuickJob(job);
  ASSERT_TRUE(result.ok()) << result.status();
  ASSERT_EQ(result->best_glare_size(), 2);
  const v1::ViewGlare& window = result->best_glare(0);
  const v1::ViewGlare& back = result->best_glare(1);
  EXPECT_EQ(window.view(), "toward the window");
  EXPECT_EQ(window.analysed_hours(), 3650);
  EXPECT_EQ(window.class_hours_size(), 4);
  // 2000 paths per view: the eye facing the window above the other by 3.3 SE at this seed
  EXPECT_GT(window.mean_dgp().value(),
            back.mean_dgp().value() + 2 * std::hypot(window.mean_dgp().standard_error(),
                                                     back.mean_dgp().standard_error()));
  EXPECT_GE(window.autonomy().value(), 0);
  EXPECT_LE(window.autonomy().value(), 100);
  EXPECT_FALSE(window.en17037().empty());
  EXPECT_GT(result->timings().glare_seconds(), 0);
  // Without views, none
  absl::StatusOr<v1::JobResult> plain = RunQuickJob(QuickJob(3));
  ASSERT_TRUE(plain.ok()) << plain.status();
  EXPECT_EQ(plain->best_glare_size(), 0);
}

}  // namespace
}  // namespace fenestra
