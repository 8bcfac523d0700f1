// Honeybee models as scenes: units, materials and their defaults, faces with their openings
// cut out, windows from apertures, shades, and the room chosen.
#include "core/geometry/hbjson_import.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <set>

#include "absl/strings/str_cat.h"
#include "core/geometry/scene.h"
#include "core/trace/glass.h"
#include "core/trace/room_check.h"
#include "tests/core/geometry/hbjson_test_models.h"

namespace fenestra::hbjson_test {
namespace {

using ::testing::HasSubstr;

// ---------------------------------------------------------------------------------------
// The office
// ---------------------------------------------------------------------------------------

TEST(HbjsonImportTest, OfficeBecomesAScene) {
  HoneybeeImportSummary summary;
  const absl::StatusOr<v1::Scene> scene = Import(Office(), {}, &summary);
  ASSERT_TRUE(scene.ok()) << scene.status();
  EXPECT_EQ(scene->name(), "office");
  EXPECT_EQ(summary.room, "office");
  EXPECT_EQ(summary.faces, 6u);
  EXPECT_EQ(summary.apertures, 1u);
  EXPECT_EQ(summary.windows, 1u);
  EXPECT_EQ(summary.sensors, 4u);
  EXPECT_EQ(summary.sensor_grids, std::vector<std::string>{"desks"});
  EXPECT_FALSE(scene->has_site());
  ASSERT_EQ(scene->windows_size(), 1);
  const v1::Window& w = scene->windows(0);
  EXPECT_EQ(w.name(), "office_window");
  EXPECT_NEAR(w.center().x(), 2, 1e-12);
  EXPECT_NEAR(w.center().y(), 0, 1e-12);
  EXPECT_NEAR(w.center().z(), 1.65, 1e-12);
  EXPECT_NEAR(w.outward_normal().y(), -1, 1e-12);
  EXPECT_NEAR(w.up().z(), 1, 1e-12);
  EXPECT_NEAR(w.width_m(), 2, 1e-12);
  EXPECT_NEAR(w.height_m(), 1.5, 1e-12);
  EXPECT_EQ(w.depth_m(), 0);
  for (const v1::Surface& s : scene->surfaces()) EXPECT_EQ(s.side(), v1::SIDE_INDOOR) << s.name();
  ASSERT_EQ(scene->sensors_size(), 4);
  EXPECT_EQ(scene->sensors(0).name(), "desks_0");
  EXPECT_EQ(scene->sensors(3).name(), "desks_3");
  EXPECT_NEAR(scene->sensors(3).position().y(), 4, 1e-12);
  EXPECT_NEAR(scene->sensors(3).direction().z(), 1, 1e-12);
  const absl::StatusOr<Scene> built = BuildScene(*scene, "model.hbjson");
  EXPECT_TRUE(built.ok()) << built.status();
  const absl::StatusOr<Scene> room = ValidateScene(*scene, "model.hbjson");
  EXPECT_TRUE(room.ok()) << room.status();
}

TEST(HbjsonImportTest, PunchedFaceIsTheFaceLessItsOpenings) {
  const absl::StatusOr<v1::Scene> scene = Import(Office());
  ASSERT_TRUE(scene.ok()) << scene.status();
  // The south wall less the window, in convex pieces
  const std::vector<const v1::Surface*> wall = Parts(*scene, "office_south");
  EXPECT_GT(wall.size(), 1u);
  EXPECT_NEAR(PartsArea(*scene, "office_south"), 4 * 3 - 2 * 1.5, 1e-9);
  // Walls without openings stay one polygon
  EXPECT_EQ(Parts(*scene, "office_north").size(), 1u);
  EXPECT_EQ(Parts(*scene, "office_north")[0]->name(), "office_north");
  EXPECT_NEAR(PartsArea(*scene, "office_north"), 12, 1e-12);
  // Two windows and a hole in one face
  const std::string left =
      Aperture("left", {P(0.5, 0, 1), P(1.5, 0, 1), P(1.5, 0, 2), P(0.5, 0, 2)});
  const std::string right =
      Aperture("right", {P(2.5, 0, 1), P(3.5, 0, 2 - 1), P(3.5, 0, 2.5), P(2.5, 0, 2.5)});
  const auto faces =
      BoxFaces("room", 0, 0, 0, 4, 6, 3,
               {{"south", absl::StrCat(R"(, "apertures": [)", left, ", ", right, "]")}});
  ModelSpec m;
  m.rooms = {Room("room", faces)};
  m.grids = {Grid("g", {{2, 3}}, 0.8)};
  const absl::StatusOr<v1::Scene> two = Import(Model(m));
  ASSERT_TRUE(two.ok()) << two.status();
  EXPECT_NEAR(PartsArea(*two, "room_south"), 12 - 1 - 1.5, 1e-9);
  EXPECT_EQ(two->windows_size(), 2);
  // Every piece is a convex polygon the scene takes
  const absl::StatusOr<Scene> built = BuildScene(*two, "model.hbjson");
  EXPECT_TRUE(built.ok()) << built.status();
}

TEST(HbjsonImportTest, FaceHolesAreCutToo) {
  // A floor with a 1 m x 1 m hole (a light well), under a floor of its own below
  FaceSpec floor{"floor", "Floor", "Ground", {P(0, 0, 0), P(0, 6, 0), P(4, 6, 0), P(4, 0, 0)}};
  auto faces = BoxFaces(
      "room", 0, 0, 0, 4, 6, 3,
      {{"south",
        absl::StrCat(R"(, "apertures": [)",
                     Aperture("w", {P(1, 0, 1), P(3, 0, 1), P(3, 0, 2), P(1, 0, 2)}), "]")}});
  std::string holed = Room("room", faces);
  const std::string hole =
      absl::StrCat("[[", P(1, 2, 0), ", ", P(2, 2, 0), ", ", P(2, 3, 0), ", ", P(1, 3, 0), "]]");
  const std::string floor_geometry = Geometry(faces[0].points);
  holed.replace(holed.find(floor_geometry), floor_geometry.size(), Geometry(faces[0].points, hole));
  ModelSpec m;
  m.rooms = {holed};
  m.grids = {Grid("g", {{3, 4}}, 0.8)};
  const absl::StatusOr<v1::Scene> scene = Import(Model(m));
  ASSERT_TRUE(scene.ok()) << scene.status();
  EXPECT_NEAR(PartsArea(*scene, "room_floor"), 24 - 1, 1e-9);
}

TEST(HbjsonImportTest, UnitsBecomeMetres) {
  const std::pair<const char*, double> units[] = {{"Meters", 1},
                                                  {"Millimeters", 1000},
                                                  {"Centimeters", 100},
                                                  {"Feet", 1 / 0.3048},
                                                  {"Inches", 1 / 0.0254}};
  for (const auto& [name, per_metre] : units) {
    const absl::StatusOr<v1::Scene> scene = Import(Office(per_metre, name));
    ASSERT_TRUE(scene.ok()) << name << ": " << scene.status();
    const v1::Window& w = scene->windows(0);
    EXPECT_NEAR(w.width_m(), 2, 1e-9) << name;
    EXPECT_NEAR(w.height_m(), 1.5, 1e-9) << name;
    EXPECT_NEAR(w.center().z(), 1.65, 1e-9) << name;
    EXPECT_NEAR(scene->sensors(3).position().y(), 4, 1e-9) << name;
    EXPECT_NEAR(PartsArea(*scene, "office_north"), 12, 1e-9) << name;
    // The pane lies 1 mm into the room whatever the units
    const std::vector<const v1::Surface*> pane = Parts(*scene, "office_window#pane");
    ASSERT_EQ(pane.size(), 1u) << name;
    EXPECT_NEAR(pane[0]->polygon().vertices(0).y(), kGlazingInsetM, 1e-12) << name;
  }
  EXPECT_THAT(ErrorOf(Office(1, "Furlongs")),
              HasSubstr("model.hbjson: units: must be Meters, Millimeters, Centimeters, Feet or "
                        "Inches, got 'Furlongs'"));
}

// ---------------------------------------------------------------------------------------
// Materials
// ---------------------------------------------------------------------------------------

TEST(HbjsonImportTest, GenericModifiersByFaceTypeAndBoundary) {
  const absl::StatusOr<v1::Scene> scene = Import(Office());
  ASSERT_TRUE(scene.ok()) << scene.status();
  const auto plastic = [&](const std::string& surface) {
    const v1::Material* m = MaterialOf(*scene, surface);
    EXPECT_NE(m, nullptr) << surface;
    EXPECT_TRUE(m != nullptr && m->has_plastic()) << surface;
    return m == nullptr ? std::pair<std::string, double>{}
                        : std::pair{m->name(), m->plastic().reflectance()};
  };
  EXPECT_EQ(plastic("office_south"), (std::pair<std::string, double>{"generic_wall_0.50", 0.5}));
  EXPECT_EQ(plastic("office_floor"), (std::pair<std::string, double>{"generic_floor_0.20", 0.2}));
  EXPECT_EQ(plastic("office_roof"), (std::pair<std::string, double>{"generic_ceiling_0.80", 0.8}));
  const v1::Material* glass = MaterialOf(*scene, "office_window#pane");
  ASSERT_NE(glass, nullptr);
  EXPECT_EQ(glass->name(), "generic_exterior_window_vis_0.64");
  ASSERT_TRUE(glass->has_glass());
  EXPECT_NEAR(glass->glass().transmittance(), 0.64, 0.005);
  EXPECT_NEAR(GlassPane::TransmissivityFor(static_cast<float>(glass->glass().transmittance())),
              0.6975761815384331, 1e-5);
  // The exterior visible set: walls to the outdoors reflect 0.35 outside
  const absl::StatusOr<v1::Scene> exterior = Import(Office(
      1, "Meters", "",
      R"(, "properties": {"radiance": {"modifier_set": "Generic_Exterior_Visible_Modifier_Set"}})"));
  ASSERT_TRUE(exterior.ok()) << exterior.status();
  EXPECT_EQ(MaterialOf(*exterior, "office_south")->name(), "generic_wall_exterior_side_0.35");
  EXPECT_EQ(MaterialOf(*exterior, "office_floor")->name(), "generic_floor_0.20");  // Ground
}

TEST(HbjsonImportTest, ModelModifiersAndModifierSets) {
  const std::string modifiers = R"(
    {"type": "Plastic", "identifier": "ochre", "r_reflectance": 0.8, "g_reflectance": 0.5,
     "b_reflectance": 0.2, "specularity": 0.02, "roughness": 0.1},
    {"type": "metal", "identifier": "steel", "r_reflectance": 0.6, "g_reflectance": 0.6,
     "b_reflectance": 0.6, "roughness": 0.05},
    {"type": "Trans", "identifier": "curtain", "r_reflectance": 0.7, "g_reflectance": 0.7,
     "b_reflectance": 0.7, "transmitted_diff": 0.3, "transmitted_spec": 0.1},
    {"type": "Glass", "identifier": "clear", "r_transmissivity": 0.9, "g_transmissivity": 0.9,
     "b_transmissivity": 0.9, "refraction_index": null},
    {"type": "Void", "identifier": "nothing"})";
  const std::string sets = R"(
    {"type": "ModifierSetAbridged", "identifier": "office_set",
     "wall_set": {"interior_modifier": "steel", "exterior_modifier": "ochre"},
     "aperture_set": {"window_modifier": "clear"}, "floor_set": {"interior_modifier": null}})";
  const std::string window =
      Aperture("w", {P(1, 0, 0.9), P(3, 0, 0.9), P(3, 0, 2.4), P(1, 0, 2.4)});
  auto faces = BoxFaces("office", 0, 0, 0, 4, 6, 3,
                        {{"south", absl::StrCat(R"(, "apertures": [)", window, "]")}});
  faces[3].boundary = "Adiabatic";  // north: an interior wall of the set
  ModelSpec m;
  m.rooms = {
      Room("office", faces, R"(, "properties": {"radiance": {"modifier_set": "office_set"}})")};
  m.grids = {Grid("g", {{2, 3}}, 0.8)};
  m.modifiers = modifiers;
  m.modifier_sets = sets;
  // The west wall has its own modifier, the east one is left out (Void)
  std::string json = Model(m);
  const auto own = [&](const std::string& face, const std::string& modifier) {
    const std::string id = absl::StrCat(R"("identifier": ")", face, "\"");
    const size_t at = json.find(R"("properties": )", json.find(id));
    const std::string old = absl::StrCat(R"("properties": )", Properties(""));
    ASSERT_EQ(json.compare(at, old.size(), old), 0);
    json.replace(at, old.size(), absl::StrCat(R"("properties": )", Properties(modifier)));
  };
  own("office_west", "curtain");
  own("office_east", "nothing");
  HoneybeeImportSummary summary;
  const absl::StatusOr<v1::Scene> scene = Import(json, {}, &summary);
  ASSERT_TRUE(scene.ok()) << scene.status();
  const v1::Material* ochre = MaterialOf(*scene, "office_south");  // Outdoors: exterior
  ASSERT_TRUE(ochre != nullptr && ochre->has_plastic());
  EXPECT_EQ(ochre->name(), "ochre");
  EXPECT_NEAR(ochre->plastic().reflectance(), 0.265 * 0.8 + 0.670 * 0.5 + 0.065 * 0.2, 1e-12);
  EXPECT_EQ(ochre->plastic().specularity(), 0.02);
  EXPECT_EQ(ochre->plastic().roughness(), 0.1);
  const v1::Material* steel = MaterialOf(*scene, "office_north");  // Adiabatic: interior
  ASSERT_TRUE(steel != nullptr && steel->has_metal());
  EXPECT_NEAR(steel->metal().reflectance(), 0.6, 1e-12);
  EXPECT_EQ(steel->metal().specularity(), 0.9);  // honeybee's default for a metal
  EXPECT_EQ(steel->metal().roughness(), 0.05);
  const v1::Material* curtain = MaterialOf(*scene, "office_west");
  ASSERT_TRUE(curtain != nullptr && curtain->has_trans());
  EXPECT_EQ(curtain->trans().transmissivity(), 0.3);
  EXPECT_EQ(curtain->trans().transmitted_specular(), 0.1);
  EXPECT_TRUE(Parts(*scene, "office_east").empty());
  EXPECT_EQ(summary.void_elements, 1u);
  const v1::Material* clear = MaterialOf(*scene, "w#pane");
  ASSERT_TRUE(clear != nullptr && clear->has_glass());
  EXPECT_NEAR(clear->glass().transmittance(), GlassPane{0.9f}.Transmittance(1.0f), 1e-7);
  // What the set leaves out is the generic modifier
  EXPECT_EQ(MaterialOf(*scene, "office_floor")->name(), "generic_floor_0.20");
  EXPECT_EQ(MaterialOf(*scene, "office_roof")->name(), "generic_ceiling_0.80");
  // Names are unique, and the scene takes every material
  std::set<std::string> names;
  for (const v1::Material& material : scene->materials())
    EXPECT_TRUE(names.insert(material.name()).second);
  const absl::StatusOr<Scene> built = BuildScene(*scene, "model.hbjson");
  EXPECT_TRUE(built.ok()) << built.status();
}

TEST(HbjsonImportTest, RefusesModifiersFenestraDoesNotHave) {
  const auto with_modifier = [](const std::string& modifier) {
    std::string json = Office();
    const std::string old = R"("modifiers": [])";
    json.replace(json.find(old), old.size(), absl::StrCat(R"("modifiers": [)", modifier, "]"));
    const std::string props = absl::StrCat(R"("properties": )", Properties(""));
    const size_t face = json.find(props, json.find(R"("office_north")"));
    json.replace(face, props.size(), absl::StrCat(R"("properties": )", Properties("m")));
    return json;
  };
  EXPECT_THAT(ErrorOf(with_modifier(R"({"type": "Mirror", "identifier": "m"})")),
              HasSubstr("properties.radiance.modifiers[0].type: modifier type 'Mirror' is not "
                        "supported"));
  EXPECT_THAT(ErrorOf(with_modifier(R"({"type": "Plastic", "identifier": "m", "specularity": 1})")),
              HasSubstr("properties.radiance.modifiers[0].specularity: must be in [0, 1), got 1"));
  EXPECT_THAT(
      ErrorOf(with_modifier(R"({"type": "Plastic", "identifier": "m", "r_reflectance": "0.5"})")),
      HasSubstr("modifiers[0].r_reflectance: must be a number, got a string"));
  EXPECT_THAT(ErrorOf(with_modifier(R"({"type": "Glass", "identifier": "m", "r_transmissivity": 1,
                                       "g_transmissivity": 1, "b_transmissivity": 1})")),
              HasSubstr("at most 0.9"));
  EXPECT_THAT(ErrorOf(with_modifier(R"({"type": "Plastic", "identifier": "other"})")),
              HasSubstr("rooms[0].faces[3].properties.radiance.modifier: unknown modifier 'm'"));
  EXPECT_THAT(
      ErrorOf(Office(1, "Meters", "", R"(, "properties": {"radiance": {"modifier_set": "x"}})")),
      HasSubstr("rooms[0].properties.radiance.modifier_set: unknown modifier set 'x'"));
}

// ---------------------------------------------------------------------------------------
// Windows and shades
// ---------------------------------------------------------------------------------------

TEST(HbjsonImportTest, WindowsFaceOutOfTheirWallsAndSkylightsPointUpNorth) {
  const std::string north = Aperture("n", {P(3, 6, 1), P(1, 6, 1), P(1, 6, 2), P(3, 6, 2)});
  const std::string east = Aperture("e.1", {P(4, 1, 1), P(4, 5, 1), P(4, 5, 2), P(4, 1, 2)});
  const std::string roof = Aperture("sky light", {P(1, 2, 3), P(3, 2, 3), P(3, 3, 3), P(1, 3, 3)});
  const auto faces = BoxFaces("r", 0, 0, 0, 4, 6, 3,
                              {{"north", absl::StrCat(R"(, "apertures": [)", north, "]")},
                               {"east", absl::StrCat(R"(, "apertures": [)", east, "]")},
                               {"roof", absl::StrCat(R"(, "apertures": [)", roof, "]")}});
  ModelSpec m;
  m.rooms = {Room("r", faces)};
  m.grids = {Grid("g", {{2, 3}}, 0.8)};
  const absl::StatusOr<v1::Scene> scene = Import(Model(m));
  ASSERT_TRUE(scene.ok()) << scene.status();
  ASSERT_EQ(scene->windows_size(), 3);
  std::map<std::string, const v1::Window*> windows;
  for (const v1::Window& w : scene->windows()) windows[w.name()] = &w;
  ASSERT_EQ(windows.count("sky_light"), 1u);  // "sky light", sanitized
  const v1::Window& n = *windows.at("n");
  EXPECT_NEAR(n.outward_normal().y(), 1, 1e-12);
  EXPECT_NEAR(n.up().z(), 1, 1e-12);
  EXPECT_NEAR(n.width_m(), 2, 1e-12);
  const v1::Window& e = *windows.at("e.1");
  EXPECT_NEAR(e.outward_normal().x(), 1, 1e-12);
  EXPECT_NEAR(e.up().z(), 1, 1e-12);
  EXPECT_NEAR(e.width_m(), 4, 1e-12);
  EXPECT_NEAR(e.height_m(), 1, 1e-12);
  const v1::Window& sky = *windows.at("sky_light");
  EXPECT_NEAR(sky.outward_normal().z(), 1, 1e-12);
  EXPECT_NEAR(sky.up().y(), 1, 1e-12);  // level: the side closest to +y
  EXPECT_NEAR(sky.width_m(), 2, 1e-12);
  EXPECT_NEAR(sky.height_m(), 1, 1e-12);
  EXPECT_NEAR(sky.center().z(), 3, 1e-12);
  // A tilted roof light: up runs up the slope
  const std::string slope_light = Aperture("s", {P(1, 1, 1), P(3, 1, 1), P(3, 2, 2), P(1, 2, 2)});
  std::vector<FaceSpec> wedge = {
      {"floor", "Floor", "Ground", {P(0, 0, 0), P(0, 3, 0), P(4, 3, 0), P(4, 0, 0)}},
      {"slope",
       "RoofCeiling",
       "Outdoors",
       {P(0, 0, 0), P(4, 0, 0), P(4, 3, 3), P(0, 3, 3)},
       absl::StrCat(R"(, "apertures": [)", slope_light, "]")},
      {"back", "Wall", "Outdoors", {P(4, 3, 0), P(0, 3, 0), P(0, 3, 3), P(4, 3, 3)}},
      {"west", "Wall", "Outdoors", {P(0, 3, 0), P(0, 0, 0), P(0, 3, 3)}},
      {"east", "Wall", "Outdoors", {P(4, 0, 0), P(4, 3, 0), P(4, 3, 3)}}};
  ModelSpec tilted;
  tilted.rooms = {Room("wedge", wedge)};
  tilted.grids = {Grid("g", {{2, 2.5}}, 0.5)};
  const absl::StatusOr<v1::Scene> slope = Import(Model(tilted));
  ASSERT_TRUE(slope.ok()) << slope.status();
  const v1::Window& s = slope->windows(0);
  EXPECT_NEAR(s.up().y(), std::sqrt(0.5), 1e-12);
  EXPECT_NEAR(s.up().z(), std::sqrt(0.5), 1e-12);
  EXPECT_NEAR(s.outward_normal().y(), -std::sqrt(0.5), 1e-12);
  EXPECT_NEAR(s.outward_normal().z(), std::sqrt(0.5), 1e-12);
  EXPECT_NEAR(s.height_m(), std::sqrt(2.0), 1e-12);
  EXPECT_NEAR(s.width_m(), 2, 1e-12);
}

TEST(HbjsonImportTest, ShadesAreOutdoorsUnlessIndoorsOfTheRoom) {
  const std::string overhang =
      Shade("overhang", {P(1, 0, 2.5), P(3, 0, 2.5), P(3, -0.5, 2.5), P(1, -0.5, 2.5)});
  const std::string shelf = Shade("shelf", {P(1, 0.5, 2), P(3, 0.5, 2), P(3, 0, 2), P(1, 0, 2)});
  const std::string fin =
      Shade("fin", {P(0.9, 0, 1), P(0.9, -0.3, 1), P(0.9, -0.3, 2.3), P(0.9, 0, 2.3)});
  const std::string partition =
      Shade("partition", {P(2, 5, 0), P(2, 6, 0), P(2, 6, 2), P(2, 5, 2)});
  const std::string tree = Shade("tree", {P(-5, -10, 0), P(5, -10, 0), P(5, -10, 8), P(-5, -10, 8)},
                                 R"(, "is_detached": true)");
  const std::string awning =
      Shade("awning", {P(-1, -2, 3), P(5, -2, 3), P(5, -3, 3), P(-1, -3, 3)});
  const std::string window = Aperture(
      "w", {P(1, 0, 0.9), P(3, 0, 0.9), P(3, 0, 2.4), P(1, 0, 2.4)},
      absl::StrCat(R"(, "outdoor_shades": [)", fin, R"(], "indoor_shades": [)", shelf, "]"));
  const auto faces = BoxFaces(
      "office", 0, 0, 0, 4, 6, 3,
      {{"south",
        absl::StrCat(R"(, "apertures": [)", window, R"(], "outdoor_shades": [)", overhang, "]")}});
  ModelSpec m;
  m.rooms = {Room("office", faces, absl::StrCat(R"(, "indoor_shades": [)", partition, "]"))};
  m.grids = {Grid("g", {{1, 3}}, 0.8)};
  m.extra = absl::StrCat(R"(, "orphaned_shades": [)", tree, ", ", awning,
                         R"(], "shade_meshes": [{"type": "ShadeMesh", "identifier": "hedge", )",
                         R"("geometry": {"type": "Mesh3D", "vertices": [)", P(-4, -6, 0), ", ",
                         P(8, -6, 0), ", ", P(8, -6, 1), ", ", P(-4, -6, 1), ", ", P(2, -6, 2),
                         R"(], "faces": [[0, 1, 2, 3], [3, 2, 4]]}, "properties": {}}])");
  HoneybeeImportSummary summary;
  const absl::StatusOr<v1::Scene> scene = Import(Model(m), {}, &summary);
  ASSERT_TRUE(scene.ok()) << scene.status();
  EXPECT_EQ(summary.shades, 7u);
  const auto side = [&](const std::string& name) {
    const std::vector<const v1::Surface*> parts = Parts(*scene, name);
    EXPECT_FALSE(parts.empty()) << name;
    return parts.empty() ? v1::SIDE_UNSPECIFIED : parts[0]->side();
  };
  EXPECT_EQ(side("overhang"), v1::SIDE_OUTDOOR);
  EXPECT_EQ(side("fin"), v1::SIDE_OUTDOOR);
  EXPECT_EQ(side("tree"), v1::SIDE_OUTDOOR);
  EXPECT_EQ(side("awning"), v1::SIDE_OUTDOOR);
  EXPECT_EQ(side("hedge"), v1::SIDE_OUTDOOR);
  EXPECT_EQ(side("shelf"), v1::SIDE_INDOOR);
  EXPECT_EQ(side("partition"), v1::SIDE_INDOOR);
  EXPECT_EQ(Parts(*scene, "hedge").size(), 2u);
  EXPECT_EQ(MaterialOf(*scene, "overhang")->name(), "generic_exterior_shade_0.35");
  EXPECT_EQ(MaterialOf(*scene, "shelf")->name(), "generic_interior_shade_0.50");
  EXPECT_EQ(MaterialOf(*scene, "tree")->name(), "generic_context_0.20");  // detached
  EXPECT_EQ(MaterialOf(*scene, "awning")->name(), "generic_exterior_shade_0.35");
  EXPECT_EQ(MaterialOf(*scene, "hedge")->name(), "generic_context_0.20");
  const absl::StatusOr<Scene> built = BuildScene(*scene, "model.hbjson");
  EXPECT_TRUE(built.ok()) << built.status();
}

TEST(HbjsonImportTest, DoorsAreOpaqueUnlessGlass) {
  const std::string door = R"({"type": "Door", "identifier": "door", "geometry": )" +
                           Geometry({P(3.2, 0, 0), P(3.9, 0, 0), P(3.9, 0, 2.1), P(3.2, 0, 2.1)}) +
                           R"(, "boundary_condition": {"type": "Outdoors"}, "properties": {}})";
  const std::string glass_door =
      R"({"type": "Door", "identifier": "french", "is_glass": true, "geometry": )" +
      Geometry({P(0.2, 0, 0), P(0.9, 0, 0), P(0.9, 0, 2.1), P(0.2, 0, 2.1)}) +
      R"(, "boundary_condition": {"type": "Outdoors"}, "properties": {}})";
  const auto faces =
      BoxFaces("r", 0, 0, 0, 4, 6, 3,
               {{"south", absl::StrCat(R"(, "doors": [)", door, ", ", glass_door, "]")}});
  ModelSpec m;
  m.rooms = {Room("r", faces)};
  m.grids = {Grid("g", {{2, 3}}, 0.8)};
  HoneybeeImportSummary summary;
  const absl::StatusOr<v1::Scene> scene = Import(Model(m), {}, &summary);
  ASSERT_TRUE(scene.ok()) << scene.status();
  EXPECT_EQ(summary.doors, 2u);
  ASSERT_EQ(scene->windows_size(), 1);  // the glass door
  EXPECT_EQ(scene->windows(0).name(), "french");
  EXPECT_EQ(MaterialOf(*scene, "door")->name(), "generic_opaque_door_0.50");
  EXPECT_EQ(Parts(*scene, "door")[0]->side(), v1::SIDE_INDOOR);
  EXPECT_EQ(MaterialOf(*scene, "french#pane")->name(), "generic_exterior_window_vis_0.64");
  EXPECT_NEAR(PartsArea(*scene, "r_south"), 12 - 2 * 0.7 * 2.1, 1e-9);
}

// ---------------------------------------------------------------------------------------
// The room
// ---------------------------------------------------------------------------------------

TEST(HbjsonImportTest, RoomOfTheSensorGrid) {
  // By the grid's room_identifier, by its bounding box, by the option
  const std::string by_name =
      TwoRooms({Grid("g", {{6, 3}}, 0.8, R"(, "room_identifier": "east")")});
  const std::string by_box = TwoRooms({Grid("g", {{6, 3}}, 0.8)});
  for (const std::string& json : {by_name, by_box}) {
    HoneybeeImportSummary summary;
    const absl::StatusOr<v1::Scene> scene = Import(json, {}, &summary);
    ASSERT_TRUE(scene.ok()) << scene.status();
    EXPECT_EQ(summary.room, "east");
    EXPECT_EQ(summary.rooms, 2u);
    ASSERT_EQ(scene->windows_size(), 1);
    EXPECT_EQ(scene->windows(0).name(), "east_window");
    // The other room's faces and window are outdoor; its wall against this room is left out
    EXPECT_EQ(Parts(*scene, "east_south")[0]->side(), v1::SIDE_INDOOR);
    EXPECT_EQ(Parts(*scene, "west_south")[0]->side(), v1::SIDE_OUTDOOR);
    EXPECT_EQ(Parts(*scene, "west_window")[0]->side(), v1::SIDE_OUTDOOR);
    EXPECT_TRUE(Parts(*scene, "west_east").empty());
    EXPECT_EQ(summary.hidden_faces, 1u);
    EXPECT_EQ(summary.context_faces, 5u);
    const absl::StatusOr<Scene> built = BuildScene(*scene, "model.hbjson");
    EXPECT_TRUE(built.ok()) << built.status();
  }
  HoneybeeImportOptions west;
  west.room = "west";
  west.sensor_grid = "w";
  const std::string both = TwoRooms({Grid("g", {{6, 3}}, 0.8), Grid("w", {{2, 3}, {2, 4}}, 0.8)});
  HoneybeeImportSummary summary;
  const absl::StatusOr<v1::Scene> scene = Import(both, west, &summary);
  ASSERT_TRUE(scene.ok()) << scene.status();
  EXPECT_EQ(summary.room, "west");
  EXPECT_EQ(scene->sensors_size(), 2);
  EXPECT_EQ(scene->sensors(1).name(), "w_1");
  // The grid alone picks its room
  HoneybeeImportOptions grid_w;
  grid_w.sensor_grid = "w";
  const absl::StatusOr<v1::Scene> by_grid = Import(both, grid_w, &summary);
  ASSERT_TRUE(by_grid.ok()) << by_grid.status();
  EXPECT_EQ(summary.room, "west");
}

TEST(HbjsonImportTest, RoomChoiceErrorsListTheRooms) {
  const std::string both = TwoRooms({Grid("g", {{6, 3}}, 0.8), Grid("w", {{2, 3}}, 0.8)});
  EXPECT_THAT(ErrorOf(both), HasSubstr("model.hbjson: cannot tell which of its 2 rooms to "
                                       "simulate: the sensor grids lie in 2 rooms; choose one "
                                       "of 'west', 'east'"));
  EXPECT_THAT(ErrorOf(TwoRooms({})), HasSubstr("the model has no sensor grid"));
  HoneybeeImportOptions unknown;
  unknown.room = "attic";
  EXPECT_THAT(ErrorOf(both, unknown),
              HasSubstr("no room 'attic'; the model's rooms are 'west', 'east'"));
  EXPECT_THAT(ErrorOf(TwoRooms({Grid("outside", {{20, 3}}, 0.8)})),
              HasSubstr("sensor grid 'outside' names no room of the model and lies in no single "
                        "room's bounding box"));
  HoneybeeImportOptions missing;
  missing.sensor_grid = "x";
  EXPECT_THAT(ErrorOf(Office(), missing),
              HasSubstr("no sensor grid 'x'; the model's grids are 'desks'"));
  HoneybeeImportOptions east;
  east.room = "east";
  EXPECT_THAT(ErrorOf(TwoRooms({Grid("w", {{2, 3}}, 0.8)}), east),
              HasSubstr("no sensor grid lies in room 'east'"));
}

}  // namespace
}  // namespace fenestra::hbjson_test
