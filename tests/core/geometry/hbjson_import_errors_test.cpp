// Honeybee models refused with the JSON path of what is wrong, and public sample models built
// and checked as rooms.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_join.h"
#include "core/geometry/hbjson_import.h"
#include "core/geometry/scene.h"
#include "core/trace/room_check.h"
#include "tests/core/geometry/hbjson_test_models.h"

namespace fenestra::hbjson_test {
namespace {

using ::testing::HasSubstr;

// ---------------------------------------------------------------------------------------
// Refusals
// ---------------------------------------------------------------------------------------

TEST(HbjsonImportTest, RefusesBadJsonAndWrongTypes) {
  EXPECT_THAT(ErrorOf("{\"rooms\": ["), HasSubstr("model.hbjson: malformed JSON"));
  EXPECT_THAT(ErrorOf("[1, 2]"), HasSubstr("model.hbjson: a Honeybee model is a JSON object"));
  EXPECT_THAT(ErrorOf(R"({"type": "Room"})"), HasSubstr("type is 'Room', not a Honeybee Model"));
  EXPECT_THAT(ErrorOf(Edited(R"("face_type": "Wall")", R"("face_type": 3)")),
              HasSubstr("rooms[0].faces[2].face_type: must be a string, got a number"));
  EXPECT_THAT(ErrorOf(Edited(R"("face_type": "Wall")", R"("face_type": "Window")")),
              HasSubstr("rooms[0].faces[2].face_type: must be Wall, Floor, RoofCeiling or "
                        "AirBoundary, got 'Window'"));
  EXPECT_THAT(ErrorOf(Edited(R"("faces": [)", R"("faces": {"a": 1}, "x": [)")),
              HasSubstr("rooms[0].faces: must be an array, got an object"));
  EXPECT_THAT(ErrorOf(Edited("[0, 0, 0]", "[0, 0]")),
              HasSubstr("rooms[0].faces[0].geometry.boundary[0]: must be a point: an array of 3 "
                        "numbers"));
  EXPECT_THAT(ErrorOf(Edited("[0, 0, 0]", R"([0, "0", 0])")),
              HasSubstr("rooms[0].faces[0].geometry.boundary[0]: must be a point"));
  EXPECT_THAT(ErrorOf(Edited(R"("identifier": "office")", R"("identifier": "")")),
              HasSubstr("rooms[0].identifier: must not be empty"));
  EXPECT_THAT(ErrorOf(Edited(R"("identifier": "office")", "\"identifier\": \"a\\nb\"")),
              HasSubstr("rooms[0].identifier: "));
  EXPECT_THAT(ErrorOf(Edited(R"("boundary_condition": {"type": "Outdoors"})",
                             R"("boundary_condition": {"type": "Sky"})", "office_window")),
              HasSubstr("rooms[0].faces[2].apertures[0].boundary_condition: type must be "
                        "Outdoors or Surface, got 'Sky'"));
  EXPECT_THAT(ErrorOf(Edited(R"("dir": [0, 0, 1])", R"("dir": [0, 0, 0])")),
              HasSubstr("properties.radiance.sensor_grids[0].sensors[0].dir: must not be zero"));
  EXPECT_THAT(ErrorOf(Edited(R"("tolerance": 0.001)", R"("tolerance": -1)")),
              HasSubstr("model.hbjson: tolerance: must be at least 0"));
}

TEST(HbjsonImportTest, RefusesNonRectangularWindowsNamingThem) {
  const std::string trapezoid = "[[1, 0, 0.9], [3, 0, 0.9], [2.8, 0, 2.4], [1.2, 0, 2.4]]";
  const std::string office = Office();
  const std::string rectangle = "[[1, 0, 0.9], [3, 0, 0.9], [3, 0, 2.4], [1, 0, 2.4]]";
  ASSERT_NE(office.find(rectangle), std::string::npos);
  EXPECT_THAT(ErrorOf(Edited(rectangle, trapezoid)),
              HasSubstr("model.hbjson: rooms[0].faces[2].apertures[0].geometry: a window must be "
                        "a rectangle (4 vertices, right angles); its corner"));
  EXPECT_THAT(ErrorOf(Edited(rectangle,
                             "[[1, 0, 0.9], [3, 0, 0.9], [3, 0, 2.4], [2, 0, 2.6], [1, 0, 2.4]]")),
              HasSubstr("rooms[0].faces[2].apertures[0].geometry: a window must be a rectangle "
                        "(4 vertices, right angles); this one has 5 vertices"));
  // Off its face's plane
  EXPECT_THAT(
      ErrorOf(Edited(rectangle, "[[1, 0.5, 0.9], [3, 0.5, 0.9], [3, 0.5, 2.4], [1, 0.5, 2.4]]")),
      HasSubstr("rooms[0].faces[2].apertures[0].geometry: lies 0.5 m off its face's plane"));
  // Beyond its face
  EXPECT_THAT(ErrorOf(Edited(rectangle, "[[3, 0, 0.9], [5, 0, 0.9], [5, 0, 2.4], [3, 0, 2.4]]")),
              HasSubstr("rooms[0].faces[2].geometry: hole 0 lies outside the outline"));
}

TEST(HbjsonImportTest, RefusesAirBoundariesFacesIntoTheRoomAndRoomsWithoutWindows) {
  EXPECT_THAT(
      ErrorOf(Edited(R"("face_type": "Wall")", R"("face_type": "AirBoundary")", "office_north")),
      HasSubstr("rooms[0].faces[3]: an AirBoundary face (an opening into another room) "
                "is not supported"));
  // Every face turned inside out
  std::string inward = Office();
  for (const auto& [from, to] : {std::pair{"[[0, 0, 0], [0, 6, 0], [4, 6, 0], [4, 0, 0]]",
                                           "[[4, 0, 0], [4, 6, 0], [0, 6, 0], [0, 0, 0]]"},
                                 std::pair{"[[0, 0, 3], [4, 0, 3], [4, 6, 3], [0, 6, 3]]",
                                           "[[0, 6, 3], [4, 6, 3], [4, 0, 3], [0, 0, 3]]"},
                                 std::pair{"[[4, 6, 0], [0, 6, 0], [0, 6, 3], [4, 6, 3]]",
                                           "[[4, 6, 3], [0, 6, 3], [0, 6, 0], [4, 6, 0]]"},
                                 std::pair{"[[0, 6, 0], [0, 0, 0], [0, 0, 3], [0, 6, 3]]",
                                           "[[0, 6, 3], [0, 0, 3], [0, 0, 0], [0, 6, 0]]"},
                                 std::pair{"[[4, 0, 0], [4, 6, 0], [4, 6, 3], [4, 0, 3]]",
                                           "[[4, 0, 3], [4, 6, 3], [4, 6, 0], [4, 0, 0]]"},
                                 std::pair{"[[0, 0, 0], [4, 0, 0], [4, 0, 3], [0, 0, 3]]",
                                           "[[0, 0, 3], [4, 0, 3], [4, 0, 0], [0, 0, 0]]"}}) {
    const size_t at = inward.find(from);
    ASSERT_NE(at, std::string::npos) << from;
    inward.replace(at, std::string(from).size(), to);
  }
  EXPECT_THAT(ErrorOf(inward), HasSubstr("rooms[0]: its faces' normals enclose a volume of -72 "
                                         "m^3 about the room's centre: they must point out"));
  const std::string no_window =
      Edited(R"("boundary_condition": {"type": "Outdoors"})",
             R"("boundary_condition": {"type": "Surface"})", "office_window");
  EXPECT_THAT(ErrorOf(no_window), HasSubstr("rooms[0]: the room has no aperture in a face to the "
                                            "outdoors: a scene needs a window"));
}

TEST(HbjsonImportTest, RefusesMissingGridsAndBadFaces) {
  EXPECT_THAT(ErrorOf(Edited(R"("sensor_grids": [)", R"("sensor_grids": [], "x": [)")),
              HasSubstr("model.hbjson: the model has no sensor grid"));
  const std::string empty = Edited(R"("sensors": [)", R"("sensors": [], "x": [)");
  EXPECT_THAT(ErrorOf(empty), HasSubstr("model.hbjson: no sensor grid lies in room 'office'"));
  HoneybeeImportOptions desks;
  desks.sensor_grid = "desks";
  EXPECT_THAT(ErrorOf(empty, desks),
              HasSubstr("model.hbjson: the sensor grid 'desks' has no sensor"));
  // Not planar beyond the tolerance (1 mm)
  const std::string bent = ErrorOf(Edited("[4, 6, 3], [0, 6, 3]]", "[4, 6, 3.01], [0, 6, 3]]"));
  EXPECT_THAT(bent, HasSubstr("rooms[0].faces[1].geometry.boundary["));
  EXPECT_THAT(bent,
              HasSubstr("off its polygon's plane, more than the model's tolerance of 0.001 m"));
  // No area
  EXPECT_THAT(ErrorOf(Edited("[[4, 6, 0], [0, 6, 0], [0, 6, 3], [4, 6, 3]]",
                             "[[4, 6, 0], [0, 6, 0], [2, 6, 0], [3, 6, 0]]")),
              HasSubstr("rooms[0].faces[3].geometry: the polygon has no area"));
  // Beyond the scene's bounds
  EXPECT_THAT(ErrorOf(Edited("[4, 6, 3], [0, 6, 3]]", "[4, 6, 3], [0, 6, 3e6]]")),
              HasSubstr("rooms[0].faces[1].geometry.boundary[3]: lies beyond 100000 m"));
}

TEST(HbjsonImportTest, RefusesNonFiniteHugeDeepAndOversizedInput) {
  // JSON has no infinity: a number beyond a double's range does not parse
  EXPECT_THAT(ErrorOf(Edited("[0, 0, 0]", "[0, 1e999, 0]")),
              HasSubstr("model.hbjson: malformed JSON: 'Number exceeds the range of double.'"));
  EXPECT_THAT(ErrorOf(Edited("[0, 0, 0]", R"([0, "NaN", 0])")), HasSubstr("must be a point"));
  // Too many vertices in one face
  std::vector<std::string> circle;
  for (int k = 0; k < 3000; ++k) {
    const double a = 2 * 3.14159265358979 * k / 3000;
    circle.push_back(P(2 + std::cos(a), 3 + std::sin(a), 3));
  }
  EXPECT_THAT(
      ErrorOf(Edited("[[0, 0, 3], [4, 0, 3], [4, 6, 3], [0, 6, 3]]",
                     absl::StrCat("[", absl::StrJoin(circle, ", "), "]"))),
      HasSubstr("rooms[0].faces[1].geometry.boundary: holds 3000 points, more than the 2048"));
  // Nested too deep
  const std::string deep =
      absl::StrCat(R"({"type": "Model", "x": )", std::string(100, '['), std::string(100, ']'), "}");
  EXPECT_THAT(ErrorOf(deep),
              HasSubstr("model.hbjson: arrays and objects nest deeper than 64 levels"));
  // Larger than the caller takes
  HoneybeeImportOptions small;
  small.max_bytes = 1000;
  EXPECT_THAT(ErrorOf(Office(), small), HasSubstr("bytes, more than the 1000 taken"));
  // Too many sensors: bounded before they are read
  std::vector<std::pair<double, double>> many(1000, {2, 3});
  const absl::StatusOr<v1::Scene> thousand = Import(
      Edited(Grid("desks", {{1, 2}, {3, 2}, {1, 4}, {3, 4}}, 0.8), Grid("desks", many, 0.8)));
  EXPECT_TRUE(thousand.ok()) << thousand.status();
}

// ---------------------------------------------------------------------------------------
// The public samples (tests/data/models/*/README.md says where they come from)
// ---------------------------------------------------------------------------------------

TEST(HbjsonImportTest, HallOfOneRoomAndThreeGrids) {
  const std::string json = ReadSample("end_windows_hall/end_windows_hall.hbjson");
  // Its grids "perimeter" (twice: 300 and 220 sensors) and "core" (640) have no room
  // identifier; all lie in the room's bounding box, and two share an identifier
  EXPECT_THAT(ErrorOf(json), HasSubstr("more than one of the sensor grids taken is named "
                                       "'perimeter'"));
  HoneybeeImportOptions core;
  core.sensor_grid = "core";
  HoneybeeImportSummary summary;
  const absl::StatusOr<v1::Scene> scene =
      ImportHoneybee(json, "end_windows_hall.hbjson", core, &summary);
  ASSERT_TRUE(scene.ok()) << scene.status();
  // The file's room: 6 faces (4 walls, floor, roof), 2 apertures in the end walls, no shade
  EXPECT_EQ(summary.room, "Hall");
  EXPECT_EQ(summary.rooms, 1u);
  EXPECT_EQ(summary.faces, 6u);
  EXPECT_EQ(summary.apertures, 2u);
  EXPECT_EQ(summary.windows, 2u);
  EXPECT_EQ(summary.shades, 0u);
  EXPECT_EQ(summary.sensors, 640u);
  ASSERT_EQ(scene->windows_size(), 2);
  for (const v1::Window& w : scene->windows()) {
    EXPECT_NEAR(w.width_m(), 9.8, 1e-9);
    EXPECT_NEAR(w.height_m(), 3.0 - 0.8, 1e-9);
    EXPECT_NEAR(std::abs(w.outward_normal().y()), 1, 1e-12);
  }
  // The end walls less their windows
  EXPECT_NEAR(PartsArea(*scene, "Hall..South"),
              10 * 3.6 - 9.8 * (3.0 - 0.8), 1e-9);
  // Each window's pane: its rectangle, 1 mm into the room, of the generic window glass
  for (const v1::Window& w : scene->windows()) {
    const std::vector<const v1::Surface*> pane = Parts(*scene, w.name() + "#pane");
    ASSERT_EQ(pane.size(), 1u) << w.name();
    EXPECT_EQ(pane[0]->side(), v1::SIDE_INDOOR);
    EXPECT_NEAR(PolygonArea(pane[0]->polygon()), w.width_m() * w.height_m(), 1e-9);
    EXPECT_NEAR(std::abs(pane[0]->polygon().vertices(0).y()), 14.5 - kGlazingInsetM, 1e-12);
    EXPECT_EQ(MaterialOf(*scene, w.name() + "#pane")->name(), "generic_exterior_window_vis_0.64");
  }
  // The scene builds and is a room: its two windows face each other across it, and the room
  // check's probe from one window into the room may leave through the other
  const absl::StatusOr<Scene> built = BuildScene(*scene, "end_windows_hall.hbjson");
  ASSERT_TRUE(built.ok()) << built.status();
  EXPECT_EQ(built->windows.size(), 2u);
  const absl::StatusOr<Scene> room = ValidateScene(*scene, "end_windows_hall.hbjson");
  EXPECT_TRUE(room.ok()) << room.status();
}

TEST(HbjsonImportTest, HoneybeeSchemaSampleOfAPatientRoomWithAnOverhang) {
  const std::string json = ReadSample("patient_room/model_complete_patient_room.hbjson");
  // It has no sensor grid
  EXPECT_THAT(ErrorOf(json), HasSubstr("the model has no sensor grid"));
  // With a grid over its 5 m x 10 m floor, 0.8 m up (given here; the file is as published)
  std::vector<std::pair<double, double>> desks;
  for (double x : {1.0, 2.5, 4.0}) {
    for (double y : {1.0, 5.0, 9.0}) desks.push_back({x, y});
  }
  std::string with_grid = json;
  const std::string none = R"("modifiers": [])";
  const size_t at = with_grid.find(none);
  ASSERT_NE(at, std::string::npos);
  with_grid.replace(at, none.size(),
                    absl::StrCat(none, R"(, "sensor_grids": [)", Grid("beds", desks, 0.8), "]"));
  HoneybeeImportSummary summary;
  const absl::StatusOr<v1::Scene> scene =
      ImportHoneybee(with_grid, "patient_room.hbjson", {}, &summary);
  ASSERT_TRUE(scene.ok()) << scene.status();
  // The file's room: 6 faces, one aperture with one overhang
  EXPECT_EQ(summary.room, "Hospital_Patient_Room");
  EXPECT_EQ(summary.faces, 6u);
  EXPECT_EQ(summary.apertures, 1u);
  EXPECT_EQ(summary.shades, 1u);
  EXPECT_EQ(summary.sensors, 9u);
  ASSERT_EQ(scene->windows_size(), 1);
  const v1::Window& w = scene->windows(0);
  EXPECT_NEAR(w.width_m(), 4.08113883008419 - 0.9188611699158102, 1e-9);
  EXPECT_NEAR(w.height_m(), 2.448683298050514 - 0.5513167019494862, 1e-9);
  EXPECT_NEAR(w.outward_normal().y(), -1, 1e-12);
  EXPECT_EQ(Parts(*scene, "Hospital_Patient_Room_Back_Glz0_OutOverhang0")[0]->side(),
            v1::SIDE_OUTDOOR);
  const absl::StatusOr<Scene> built = BuildScene(*scene, "patient_room.hbjson");
  ASSERT_TRUE(built.ok()) << built.status();
  const absl::StatusOr<Scene> room = ValidateScene(*scene, "patient_room.hbjson");
  EXPECT_TRUE(room.ok()) << room.status();
}

}  // namespace
}  // namespace fenestra::hbjson_test
