// Every way a window or a sensor can miss the room is refused, naming the field and saying
// why; the example scenes and rooms of other shapes pass.
#include "core/trace/room_check.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <string>
#include <vector>

namespace fenestra {
namespace {

using ::testing::AllOf;
using ::testing::HasSubstr;

v1::Scene Example(const std::string& name) {
  absl::StatusOr<v1::Scene> scene =
      ReadSceneProto(FENESTRA_SOURCE_DIR "/examples/" + name + "/scene.json");
  EXPECT_TRUE(scene.ok()) << scene.status();
  return scene.ok() ? *scene : v1::Scene();
}

v1::Vec3 V(double x, double y, double z) {
  v1::Vec3 v;
  v.set_x(x);
  v.set_y(y);
  v.set_z(z);
  return v;
}

v1::Sensor& AddSensor(v1::Scene& scene, const std::string& name, double x, double y, double z) {
  v1::Sensor& s = *scene.add_sensors();
  s.set_name(name);
  *s.mutable_position() = V(x, y, z);
  *s.mutable_direction() = V(0, 0, 1);
  return s;
}

void AddPolygon(v1::Scene& scene, const std::string& name, std::vector<v1::Vec3> vertices) {
  v1::Surface& s = *scene.add_surfaces();
  s.set_name(name);
  s.set_material("wall");
  s.set_side(v1::SIDE_INDOOR);
  for (const v1::Vec3& v : vertices) *s.mutable_polygon()->add_vertices() = v;
}

void AddBox(v1::Scene& scene, const std::string& name, v1::Vec3 min, v1::Vec3 max) {
  v1::Surface& s = *scene.add_surfaces();
  s.set_name(name);
  s.set_material("wall");
  s.set_side(v1::SIDE_INDOOR);
  *s.mutable_box()->mutable_min() = min;
  *s.mutable_box()->mutable_max() = max;
}

// A 4 m x 4 m x 3 m room whose north wall (y = 4) is glass from floor to ceiling and wall
// to wall: the window has no reveals (depth 0) and its edges meet floor, ceiling and walls.
v1::Scene GlassFrontRoom() {
  v1::Scene scene;
  scene.set_name("glass front");
  v1::Material& wall = *scene.add_materials();
  wall.set_name("wall");
  wall.set_reflectance(0.5);
  AddPolygon(scene, "floor", {V(0, 0, 0), V(4, 0, 0), V(4, 4, 0), V(0, 4, 0)});
  AddPolygon(scene, "ceiling", {V(0, 0, 3), V(4, 0, 3), V(4, 4, 3), V(0, 4, 3)});
  AddPolygon(scene, "south", {V(0, 0, 0), V(4, 0, 0), V(4, 0, 3), V(0, 0, 3)});
  AddPolygon(scene, "west", {V(0, 0, 0), V(0, 4, 0), V(0, 4, 3), V(0, 0, 3)});
  AddPolygon(scene, "east", {V(4, 0, 0), V(4, 4, 0), V(4, 4, 3), V(4, 0, 3)});
  v1::Window& w = *scene.mutable_window();
  *w.mutable_center() = V(2, 4, 1.5);
  *w.mutable_outward_normal() = V(0, 1, 0);
  *w.mutable_up() = V(0, 0, 1);
  w.set_width_m(4);
  w.set_height_m(3);
  AddSensor(scene, "middle", 2, 2, 0.8);
  return scene;
}

std::string ErrorOf(const v1::Scene& scene) {
  absl::StatusOr<Scene> built = ValidateScene(scene, "scene");
  EXPECT_FALSE(built.ok()) << "accepted";
  if (built.ok()) return "";
  EXPECT_EQ(built.status().code(), absl::StatusCode::kInvalidArgument);
  return std::string(built.status().message());
}

TEST(RoomCheckTest, ExampleScenesPass) {
  for (const std::string name : {"lightwell", "city_office", "corner_office", "skylight_room"}) {
    absl::StatusOr<Scene> scene =
        LoadValidScene(FENESTRA_SOURCE_DIR "/examples/" + name + "/scene.json");
    EXPECT_TRUE(scene.ok()) << name << ": " << scene.status();
  }
}

TEST(RoomCheckTest, OtherRoomShapesPass) {
  // Full-height glazing without reveals
  absl::StatusOr<Scene> glass = ValidateScene(GlassFrontRoom(), "scene");
  EXPECT_TRUE(glass.ok()) << glass.status();
  // Thick walls as boxes around a 2 m x 1.5 m opening, a desk box, a sensor above the desk
  v1::Scene boxes = GlassFrontRoom();
  boxes.clear_surfaces();
  AddBox(boxes, "floor", V(-1, -1, -1), V(5, 5, 0));
  AddBox(boxes, "ceiling", V(-1, -1, 3), V(5, 5, 4));
  AddBox(boxes, "south", V(-1, -1, 0), V(5, 0, 3));
  AddBox(boxes, "west", V(-1, 0, 0), V(0, 4.3, 3));
  AddBox(boxes, "east", V(4, 0, 0), V(5, 4.3, 3));
  AddBox(boxes, "north below", V(0, 4, 0), V(4, 4.3, 0.75));
  AddBox(boxes, "north above", V(0, 4, 2.25), V(4, 4.3, 3));
  AddBox(boxes, "north west", V(0, 4, 0.75), V(1, 4.3, 2.25));
  AddBox(boxes, "north east", V(3, 4, 0.75), V(4, 4.3, 2.25));
  AddBox(boxes, "desk", V(1, 1, 0), V(3, 2, 0.75));
  v1::Window& w = *boxes.mutable_window();
  *w.mutable_center() = V(2, 4.3, 1.5);
  w.set_width_m(2);
  w.set_height_m(1.5);
  w.set_depth_m(0.3);
  AddSensor(boxes, "on the desk", 2, 1.5, 0.8);
  absl::StatusOr<Scene> thick = ValidateScene(boxes, "scene");
  EXPECT_TRUE(thick.ok()) << thick.status();

  AddSensor(boxes, "in the desk", 2, 1.5, 0.5);
  EXPECT_THAT(ErrorOf(boxes), HasSubstr("scene: sensors[2] (\"in the desk\") at (2, 1.5, 0.5) is "
                                        "inside the solid box of surface 'desk'"));
  boxes.mutable_sensors()->RemoveLast();
  AddSensor(boxes, "in the wall", 2, -0.5, 1.5);
  EXPECT_THAT(ErrorOf(boxes), HasSubstr("sensors[2] (\"in the wall\") at (2, -0.5, 1.5) is "
                                        "inside the solid box of surface 'south'"));
}

TEST(RoomCheckTest, SensorsOutsideTheRoom) {
  v1::Scene office = Example("city_office");
  AddSensor(office, "desk 2", 1, -50, 6.7);
  EXPECT_THAT(
      ErrorOf(office),
      AllOf(HasSubstr("scene: sensors[9] (\"desk 2\") at (1, -50, 6.7) is outside the room: "
                      "a ray towards "),
            HasSubstr(" leaves without meeting an indoor surface or the window")));
  // In the neighbouring office, in the wall's cavity, far away, below the floor
  for (const auto& [x, y, z] : std::vector<std::array<double, 3>>{
           {-5, -3, 7.5}, {-1.3, 0.1, 7.5}, {1e4, 1e4, 1e4}, {0, -3, 5.5}}) {
    office = Example("city_office");
    AddSensor(office, "x", x, y, z);
    EXPECT_THAT(ErrorOf(office), HasSubstr("is outside the room")) << x << " " << y << " " << z;
  }
  // A grid's sensors are named after the grid
  office = Example("city_office");
  v1::SensorGrid& grid = *office.add_sensor_grids();
  grid.set_name("g");
  grid.set_z_m(6.7);
  grid.set_x_min_m(-1.5);
  grid.set_x_max_m(4.5);
  grid.set_y_min_m(-2);
  grid.set_y_max_m(-1);
  grid.set_spacing_m(1);
  EXPECT_THAT(ErrorOf(office),
              HasSubstr("sensor_grids[0] (\"g_12\") at (2, -1.5, 6.7) is outside the room"));
}

TEST(RoomCheckTest, SensorsOnSurfacesOrInTheBlindsSpace) {
  v1::Scene office = Example("city_office");
  AddSensor(office, "on the floor", 0, -3, 6.0);
  EXPECT_THAT(ErrorOf(office), HasSubstr("sensors[9] (\"on the floor\") at (0, -3, 6) lies on "
                                         "surface 'room floor' (within 0.001 m)"));
  office = Example("city_office");
  AddSensor(office, "in the window", 0, 0.25, 7.65);
  EXPECT_THAT(ErrorOf(office), HasSubstr("lies on the window"));
  // 5 cm behind the wall, in front of the opening: where slats up to 15 cm wide turn
  office = Example("city_office");
  AddSensor(office, "behind the blind", 0, -0.05, 7.65);
  EXPECT_THAT(ErrorOf(office),
              HasSubstr("sensors[9] (\"behind the blind\") at (0, -0.05, 7.65) lies in the space "
                        "the blind's slats take at some design within the ranges"));
}

TEST(RoomCheckTest, WindowsOffTheRoomsBoundary) {
  // In the middle of the room, floating in the street, flipped, too large, too small
  v1::Scene office = Example("city_office");
  *office.mutable_window()->mutable_center() = V(0, -3, 7.65);
  EXPECT_THAT(ErrorOf(office), AllOf(HasSubstr("scene: window: it does not lie at an opening of "
                                               "the indoor surfaces: 0.02 m outside its edge"),
                                     HasSubstr("no indoor surface closes the gap")));
  office = Example("city_office");
  *office.mutable_window()->mutable_center() = V(0, 1.25, 7.65);
  EXPECT_THAT(ErrorOf(office), HasSubstr("window: it does not lie at an opening"));
  office = Example("city_office");
  *office.mutable_window()->mutable_outward_normal() = V(0, -1, 0);
  EXPECT_THAT(ErrorOf(office), HasSubstr("window: no indoor surface lies behind its point"));
  office = Example("city_office");
  office.mutable_window()->set_width_m(3);
  EXPECT_THAT(ErrorOf(office),
              AllOf(HasSubstr("window: the opening is closed at (1.48, 0.25, 6.92): "),
                    HasSubstr("surface 'window wall room face east' lies 0.25 m behind")));
  office = Example("city_office");
  office.mutable_window()->set_width_m(1.8);
  EXPECT_THAT(ErrorOf(office), HasSubstr("window: it does not lie at an opening"));
  // A window in a wall without an opening
  office = Example("city_office");
  AddPolygon(office, "glass pane", {V(-1, 0, 6.9), V(1, 0, 6.9), V(1, 0, 8.4), V(-1, 0, 8.4)});
  office.mutable_surfaces()->rbegin()->set_material("office");
  EXPECT_THAT(ErrorOf(office), HasSubstr("window: the opening is closed"));
  // Glazing in the opening does not close it: a pane of glass 1 mm inside the outer face
  office = Example("city_office");
  v1::Material& pane = *office.add_materials();
  pane.set_name("pane");
  pane.mutable_glass()->set_transmittance(0.8);
  AddPolygon(office, "glazing",
             {V(-1, 0.249, 6.9), V(1, 0.249, 6.9), V(1, 0.249, 8.4), V(-1, 0.249, 8.4)});
  office.mutable_surfaces()->rbegin()->set_material("pane");
  const absl::StatusOr<Scene> glazed = ValidateScene(office, "scene");
  EXPECT_TRUE(glazed.ok()) << glazed.status();
  // The lightwell's outdoor walls, moved indoors: in front of the window
  v1::Scene well = Example("lightwell");
  for (v1::Surface& s : *well.mutable_surfaces()) {
    if (s.name() == "lightwell north wall") s.set_side(v1::SIDE_INDOOR);
  }
  EXPECT_THAT(ErrorOf(well), HasSubstr("window: surface 'lightwell north wall' lies 3 m in front"));
}

TEST(RoomCheckTest, NoIndoorSurfaces) {
  v1::Scene office = Example("city_office");
  for (v1::Surface& s : *office.mutable_surfaces()) s.set_side(v1::SIDE_OUTDOOR);
  EXPECT_THAT(ErrorOf(office), HasSubstr("scene: surfaces: no surface is SIDE_INDOOR"));
}

}  // namespace
}  // namespace fenestra
