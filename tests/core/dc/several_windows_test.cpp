// Rooms as they are drawn: the corner office (examples/corner_office: windows on two walls,
// one blind design for both) is a room, its blinds move together, the one-stage method
// traces both windows, and a window that no light can reach changes nothing; the skylight
// room (examples/skylight_room: a roof light with a blind under it) gives the two-stage
// method the one-stage sums. Tolerances are in standard errors; seeds are fixed.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <memory>
#include <string>

#include "core/dc/indoor_replay.h"
#include "core/dc/one_stage.h"
#include "core/dc/two_stage.h"
#include "core/geometry/scene.h"
#include "core/geometry/scene_proto.h"
#include "core/trace/room_check.h"
#include "tests/core/dc/replay_checks.h"
#include "tests/core/dc/two_stage_checks.h"

namespace fenestra {
namespace {

const std::string kCornerOffice =
    std::string(FENESTRA_SOURCE_DIR) + "/examples/corner_office/scene.json";

v1::Scene CornerOfficeProto() {
  absl::StatusOr<v1::Scene> proto = ReadSceneProto(kCornerOffice);
  EXPECT_TRUE(proto.ok()) << proto.status();
  return *std::move(proto);
}

Scene Valid(const v1::Scene& proto) {
  absl::StatusOr<Scene> scene = ValidateScene(proto, kCornerOffice);
  EXPECT_TRUE(scene.ok()) << scene.status();
  return *std::move(scene);
}

OneStageResult OneStage(const Scene& scene, const BlindDesign& design) {
  OneStageOptions options;
  options.paths_per_sensor = 20000;
  options.seed = 5;
  absl::StatusOr<OneStageResult> r = ComputeOneStage(scene, design, options);
  EXPECT_TRUE(r.ok()) << r.status();
  return *std::move(r);
}

TEST(SeveralWindowsTest, CornerOfficeIsARoomWithTwoBlindsOfOneDesign) {
  const Scene scene = Valid(CornerOfficeProto());
  ASSERT_EQ(scene.windows.size(), 2u);
  EXPECT_EQ(scene.windows[0].name, "north");
  EXPECT_EQ(scene.windows[1].name, "east");
  const BlindDesign design = DefaultDesign(scene);
  ASSERT_TRUE(design.has_blind);
  const TriangleMesh mesh = AssembleMesh(scene, design);
  // Each window's slats lie in its own opening's plane band, both at the design's tilt
  size_t north = 0, east = 0;
  for (size_t t = scene.fixed.TriangleCount(); t < mesh.TriangleCount(); ++t) {
    const std::string& part = mesh.part_names[mesh.part[t]];
    const Vec3d& v = mesh.vertices[3 * t];
    if (part == "blind north") {
      ++north;
      EXPECT_GT(v.y, 4.6);
      EXPECT_LT(v.x, 3.8);
    } else if (part == "blind east") {
      ++east;
      EXPECT_GT(v.x, 3.6);
      EXPECT_LT(v.y, 4.8);
    } else {
      ADD_FAILURE() << "triangle of part " << part;
    }
  }
  EXPECT_GT(north, 0u);
  EXPECT_EQ(north, east);  // the same design on windows of the same height

  // A shared design variable moves both blinds
  absl::StatusOr<BlindDesign> tilted = DesignWithOverrides(scene, {{"alpha", 1.0}});
  ASSERT_TRUE(tilted.ok()) << tilted.status();
  const TriangleMesh turned = AssembleMesh(scene, *tilted);
  size_t moved_north = 0, moved_east = 0;
  for (size_t t = scene.fixed.TriangleCount(); t < mesh.TriangleCount(); ++t) {
    const bool moved = Length(turned.vertices[3 * t] - mesh.vertices[3 * t]) > 1e-3;
    (mesh.part_names[mesh.part[t]] == "blind north" ? moved_north : moved_east) += moved;
  }
  EXPECT_GT(moved_north, north / 2);
  EXPECT_GT(moved_east, east / 2);
}

TEST(SeveralWindowsTest, SelfContainedSceneKeepsTheWindowsAndTheirBlinds) {
  const Scene scene = Valid(CornerOfficeProto());
  const v1::Scene written = SelfContainedSceneProto(scene);
  ASSERT_EQ(written.windows_size(), 2);
  EXPECT_FALSE(written.has_window());
  EXPECT_EQ(written.windows(1).name(), "east");
  EXPECT_EQ(written.windows(1).blind().group(), "facades");
  absl::StatusOr<Scene> rebuilt = BuildScene(written, "rebuilt");
  ASSERT_TRUE(rebuilt.ok()) << rebuilt.status();
  const TriangleMesh a = AssembleMesh(scene, DefaultDesign(scene));
  const TriangleMesh b = AssembleMesh(*rebuilt, DefaultDesign(*rebuilt));
  ASSERT_EQ(a.vertices.size(), b.vertices.size());
  for (size_t v = 0; v < a.vertices.size(); ++v) {
    EXPECT_LT(Length(a.vertices[v] - b.vertices[v]), 1e-12) << "vertex " << v;
  }
}

TEST(SeveralWindowsTest, BlindsOfDifferentGroupsOrRangesAreRefusedForNow) {
  v1::Scene proto = CornerOfficeProto();
  proto.mutable_windows(1)->mutable_blind()->set_group("east only");
  absl::StatusOr<Scene> scene = BuildScene(proto, kCornerOffice);
  EXPECT_EQ(scene.status().code(), absl::StatusCode::kInvalidArgument);  // the group's name
  proto.mutable_windows(1)->mutable_blind()->set_group("east");
  scene = BuildScene(proto, kCornerOffice);
  EXPECT_EQ(scene.status().code(), absl::StatusCode::kUnimplemented) << scene.status();
  EXPECT_NE(scene.status().message().find("windows[1].blind.group"), std::string::npos);

  proto = CornerOfficeProto();
  proto.mutable_windows(1)->mutable_blind()->mutable_tilt_rad()->set_max(1.0);
  scene = BuildScene(proto, kCornerOffice);
  EXPECT_EQ(scene.status().code(), absl::StatusCode::kInvalidArgument);
  EXPECT_NE(scene.status().message().find("share their design"), std::string::npos)
      << scene.status();

  proto = CornerOfficeProto();
  proto.mutable_windows(1)->set_name("north");
  scene = BuildScene(proto, kCornerOffice);
  EXPECT_NE(scene.status().message().find("duplicate window 'north'"), std::string::npos)
      << scene.status();
}

TEST(SeveralWindowsTest, OverlappingWindowsAreRefused) {
  v1::Scene proto = CornerOfficeProto();
  *proto.add_windows() = proto.windows(0);
  proto.mutable_windows(2)->set_name("north_again");
  proto.mutable_windows(2)->clear_blind();
  absl::StatusOr<Scene> scene = ValidateScene(proto, kCornerOffice);
  ASSERT_FALSE(scene.ok());
  EXPECT_NE(scene.status().message().find("windows[2] ('north_again'): overlaps windows[0] "
                                          "('north')"),
            std::string::npos)
      << scene.status();
  // Blinds whose slats may meet: slats 0.4 m longer at each end reach the room's corner
  proto = CornerOfficeProto();
  for (v1::Window& w : *proto.mutable_windows()) w.mutable_blind()->set_side_margin_m(0.4);
  scene = ValidateScene(proto, kCornerOffice);
  ASSERT_FALSE(scene.ok());
  EXPECT_NE(scene.status().message().find("its slats may reach into the space of the blind of"),
            std::string::npos)
      << scene.status();
}

// The replay follows both blinds: for designs across the ranges, I equals the indoor stage
// traced in full with the same seed, up to the order of the sums. A replay that left either
// blind out, or tested a record against the other blind's slats, would differ by far more.
TEST(SeveralWindowsTest, TheReplayOfBothBlindsIsTheIndoorStage) {
  const Scene scene = Valid(CornerOfficeProto());
  ASSERT_TRUE(ReplayFollows(scene));
  IndoorOptions options;
  options.paths_per_sensor = 10'000;
  absl::StatusOr<std::unique_ptr<IndoorReplay>> replay = IndoorReplay::Record(scene, options);
  ASSERT_TRUE(replay.ok()) << replay.status();
  std::printf("paths resumed per design: %.1f%%\n", 100 * (*replay)->ResumedFraction());
  ExpectReplayIsTheTrace(scene, options, **replay);
}

// The east window opens onto a closed black box: no light comes in through it and all that
// leaves through it is lost, as on a black surface in its place. The one-stage sums with that
// window equal those of the room where a black polygon closes the opening instead.
TEST(SeveralWindowsTest, AWindowNoLightReachesChangesNothing) {
  v1::Scene with = CornerOfficeProto();
  with.mutable_windows(1)->clear_blind();
  v1::Material& black = *with.add_materials();
  black.set_name("black");
  black.set_reflectance(0);
  const v1::Window& east = with.windows(1);
  const double x = east.center().x(), y = east.center().y(), z = east.center().z();
  const double w = east.width_m(), h = east.height_m();
  v1::Surface& box = *with.add_surfaces();
  box.set_name("black box outside the east window");
  box.set_material("black");
  box.set_side(v1::SIDE_OUTDOOR);
  box.mutable_box()->mutable_min()->set_x(x);
  box.mutable_box()->mutable_min()->set_y(y - w / 2);
  box.mutable_box()->mutable_min()->set_z(z - h / 2);
  box.mutable_box()->mutable_max()->set_x(x + 1);
  box.mutable_box()->mutable_max()->set_y(y + w / 2);
  box.mutable_box()->mutable_max()->set_z(z + h / 2);

  v1::Scene closed = with;
  closed.mutable_windows()->DeleteSubrange(1, 1);
  v1::Surface& lid = *closed.add_surfaces();
  lid.set_name("black lid in the east opening");
  lid.set_material("black");
  lid.set_side(v1::SIDE_INDOOR);
  const int corners[4][2] = {{-1, -1}, {1, -1}, {1, 1}, {-1, 1}};
  for (const auto& corner : corners) {
    v1::Vec3& v = *lid.mutable_polygon()->add_vertices();
    v.set_x(x - 1e-4);
    v.set_y(y + corner[0] * w / 2);
    v.set_z(z + corner[1] * h / 2);
  }
  // The closed room is not a room of that window any more: build it without the room check
  const Scene a = Valid(with);
  absl::StatusOr<Scene> b = BuildScene(closed, kCornerOffice);
  ASSERT_TRUE(b.ok()) << b.status();
  ASSERT_EQ(a.windows.size(), 2u);
  ASSERT_EQ(b->windows.size(), 1u);
  const OneStageResult ra = OneStage(a, DefaultDesign(a));
  const OneStageResult rb = OneStage(*b, DefaultDesign(*b));
  for (Eigen::Index s = 0; s < ra.sky_sum.size(); ++s) {
    EXPECT_GT(ra.sky_sum(s), 0.0);
    EXPECT_NEAR(ra.sky_sum(s), rb.sky_sum(s),
                3 * std::hypot(ra.sky_sum_standard_error(s), rb.sky_sum_standard_error(s)))
        << "sensor " << s;
  }

  // And the open east window does let light in: the sensors beside it get more
  const OneStageResult open = OneStage(Valid(CornerOfficeProto()), DefaultDesign(a));
  for (const int s : {15, 19}) {  // S16 (3.5, 3.5) and S20 (3.5, 4.5), beside the east window
    EXPECT_GT(open.sky_sum(s) - ra.sky_sum(s),
              5 * std::hypot(open.sky_sum_standard_error(s), ra.sky_sum_standard_error(s)))
        << "sensor " << s;
  }
}

TEST(SeveralWindowsTest, SkylightTwoStageMatchesOneStageOverADesignGrid) {
  absl::StatusOr<Scene> scene =
      LoadValidScene(std::string(FENESTRA_SOURCE_DIR) + "/examples/skylight_room/scene.json");
  ASSERT_TRUE(scene.ok()) << scene.status();
  ASSERT_EQ(scene->window().normal.z, 1.0);
  ExpectTwoStageMatchesOneStage(*scene, 9);
}

// Two windows on two walls, one blind design for both: the outdoor matrix holds both windows'
// cells, the indoor stage draws its window points over both.
TEST(SeveralWindowsTest, CornerOfficeTwoStageMatchesOneStageOverADesignGrid) {
  const Scene scene = Valid(CornerOfficeProto());
  ASSERT_EQ(scene.windows.size(), 2u);
  ExpectTwoStageMatchesOneStage(scene, static_cast<int>(scene.sensors.size()));
}

}  // namespace
}  // namespace fenestra
