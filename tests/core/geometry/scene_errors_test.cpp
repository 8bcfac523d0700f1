// Every kind of bad scene input gives an error naming the file, the field and the reason.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <utility>
#include <vector>

#include "core/geometry/material.h"
#include "core/geometry/scene.h"

namespace fenestra {
namespace {

namespace fs = std::filesystem;

class SceneErrorsTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("fenestra_scene_errors_" +
            std::to_string(::testing::UnitTest::GetInstance()->random_seed()) + "_" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }

  std::string Write(const std::string& name, const std::string& text) {
    const std::string path = (dir_ / name).string();
    std::ofstream(path) << text;
    return path;
  }

  // A valid scene with `replace` substituted for `find` (the first occurrence).
  std::string Scene(const std::string& find = "", const std::string& replace = "") {
    if (find.empty()) return Scene(std::vector<std::pair<std::string, std::string>>{});
    return Scene(std::vector<std::pair<std::string, std::string>>{{find, replace}});
  }

  // A valid scene with each of `edits` (find, replace) applied in turn.
  std::string Scene(const std::vector<std::pair<std::string, std::string>>& edits) {
    std::string text = R"({
      "name": "box",
      "materials": [{"name": "wall", "reflectance": 0.5}, {"name": "slat", "reflectance": 0.8}],
      "surfaces": [{"name": "floor", "material": "wall", "side": "SIDE_INDOOR",
                    "polygon": {"vertices": [{"x": 0, "y": 0, "z": 0}, {"x": 1, "y": 0, "z": 0},
                                             {"x": 1, "y": 1, "z": 0}]}}],
      "window": {"center": {"x": 0, "y": 1, "z": 1}, "outwardNormal": {"x": 0, "y": 1, "z": 0},
                 "up": {"x": 0, "y": 0, "z": 1}, "widthM": 1, "heightM": 1, "depthM": 0.2},
      "sensors": [{"name": "s", "position": {"x": 0.5, "y": 0.5, "z": 0.5},
                   "direction": {"x": 0, "y": 0, "z": 1}}],
      "blind": {"material": "slat", "tiltRad": {"value": 0, "min": 0, "max": 1.5},
                "slatWidthM": {"value": 0.1, "min": 0.05, "max": 0.15},
                "slatSpacingM": {"value": 0, "min": 0, "max": 0.1},
                "slatThicknessM": {"value": 0.01, "min": 0.01, "max": 0.02}}
    })";
    for (const auto& [find, replace] : edits) {
      const size_t at = text.find(find);
      EXPECT_NE(at, std::string::npos) << find;
      if (at != std::string::npos) text.replace(at, find.size(), replace);
    }
    return Write("scene.json", text);
  }

  // Loads `path` and expects an error containing each of `parts` (and the file name).
  void ExpectError(const std::string& path, std::initializer_list<std::string> parts) {
    absl::StatusOr<fenestra::Scene> scene = LoadScene(path);
    ASSERT_FALSE(scene.ok()) << "accepted a bad scene";
    const std::string message(scene.status().message());
    EXPECT_NE(message.find(path), std::string::npos) << message;
    for (const std::string& part : parts) {
      EXPECT_NE(message.find(part), std::string::npos) << "'" << part << "' not in: " << message;
    }
  }

  fs::path dir_;
};

TEST_F(SceneErrorsTest, ValidSceneLoads) {
  absl::StatusOr<fenestra::Scene> scene = LoadScene(Scene());
  ASSERT_TRUE(scene.ok()) << scene.status();
  EXPECT_EQ(scene->fixed.TriangleCount(), 1u);
}

TEST_F(SceneErrorsTest, MalformedJson) {
  ExpectError(Write("scene.json", R"({"name": "x", "materials": [)"), {"malformed scene"});
}

TEST_F(SceneErrorsTest, UnknownField) {
  ExpectError(Scene(R"("name": "box",)", R"("name": "box", "colour": "red",)"),
              {"malformed scene", "colour"});
}

TEST_F(SceneErrorsTest, ReflectanceOutsideRange) {
  ExpectError(Scene(R"("reflectance": 0.5)", R"("reflectance": 1.0)"),
              {"materials[0].reflectance", "must be in [0, 1)"});
  ExpectError(Scene(R"("reflectance": 0.5)", R"("reflectance": -0.1)"),
              {"materials[0].reflectance", "must be in [0, 1)"});
}

TEST_F(SceneErrorsTest, NonFiniteCoordinates) {
  ExpectError(Scene(R"({"x": 1, "y": 0, "z": 0})", R"({"x": "NaN", "y": 0, "z": 0})"),
              {"surfaces[0].polygon.vertices[1]", "finite"});
  ExpectError(Scene(R"("position": {"x": 0.5)", R"("position": {"x": "Infinity")"),
              {"sensors[0].position", "finite"});
}

TEST_F(SceneErrorsTest, DegenerateWindow) {
  ExpectError(Scene(R"("widthM": 1)", R"("widthM": 0)"),
              {"window.width_m", "must be at least 0.01 m, got 0"});
  ExpectError(Scene(R"("heightM": 1)", R"("heightM": 1e-300)"),
              {"window.height_m", "must be at least 0.01 m, got 1e-300"});
  ExpectError(Scene(R"("up": {"x": 0, "y": 0, "z": 1})", R"("up": {"x": 0, "y": 1, "z": 0})"),
              {"window.up", "perpendicular"});
  ExpectError(Scene(R"("outwardNormal": {"x": 0, "y": 1, "z": 0})",
                    R"("outwardNormal": {"x": 0, "y": 0, "z": 0})"),
              {"window.outward_normal", "zero"});
}

TEST_F(SceneErrorsTest, DegeneratePolygon) {
  ExpectError(Scene(R"({"x": 1, "y": 1, "z": 0})", R"({"x": 2, "y": 0, "z": 0})"),
              {"surfaces[0].polygon", "zero area"});
}

TEST_F(SceneErrorsTest, ZeroOrNegativeSlatSizes) {
  ExpectError(Scene(R"("slatWidthM": {"value": 0.1, "min": 0.05)",
                    R"("slatWidthM": {"value": 0.1, "min": 0)"),
              {"blind.slat_width_m", "[0, 0.15] must stay within [0.001, 1] m"});
  ExpectError(Scene(R"("slatThicknessM": {"value": 0.01, "min": 0.01)",
                    R"("slatThicknessM": {"value": 0.01, "min": -0.01)"),
              {"blind.slat_thickness_m", "[-0.01, 0.02] must stay within [0.0001, 0.1] m"});
  ExpectError(Scene(R"("slatSpacingM": {"value": 0, "min": 0)",
                    R"("slatSpacingM": {"value": 0, "min": -1)"),
              {"blind.slat_spacing_m", "[-1, 0.1] must stay within [0, 1] m"});
}

// Sizes that would take more memory than a scene may use are errors before any is taken.
TEST_F(SceneErrorsTest, TooManySensorsOrSlats) {
  const std::string sensors = R"("sensors": [)";
  ExpectError(Scene(sensors, R"("sensorGrids": [{"zM": 0.8, "xMinM": 0, "xMaxM": 1.8, "yMinM": 0,
                                                "yMaxM": 2.8, "spacingM": 1e-5}], )" +
                                 sensors),
              {"sensor_grids[0]", "the grid holds 5.04e+10 cells", "at most 1000000 sensors"});
  // The pitch is at least the width: a 10 km window over 5 cm slats needs 200001 of them
  ExpectError(Scene(R"("heightM": 1)", R"("heightM": 10000)"),
              {"blind:", "slats from 0.05 m wide need up to 200001 slats", "at most 100000"});
  // Far more slats than an int counts: the width's bounds refuse it first
  ExpectError(Scene(R"("slatWidthM": {"value": 0.1, "min": 0.05, "max": 0.15})",
                    R"("slatWidthM": {"value": 1e-300})"),
              {"blind.slat_width_m", "must stay within [0.001, 1] m"});
}

TEST_F(SceneErrorsTest, DesignValueOutsideItsRange) {
  ExpectError(Scene(R"("slatWidthM": {"value": 0.1)", R"("slatWidthM": {"value": 0.2)"),
              {"blind.slat_width_m", "value 0.2 is outside [0.05, 0.15]"});
}

TEST_F(SceneErrorsTest, UnknownMaterial) {
  ExpectError(Scene(R"("material": "wall")", R"("material": "brick")"),
              {"surfaces[0].material", "unknown material 'brick'"});
}

TEST_F(SceneErrorsTest, MissingObjFile) {
  ExpectError(Scene(R"("polygon": {"vertices": [{"x": 0, "y": 0, "z": 0}, {"x": 1, "y": 0, "z": 0},
                                             {"x": 1, "y": 1, "z": 0}]})",
                    R"("obj": {"path": "missing.obj"})"),
              {"surfaces[0].obj.path", "missing.obj", "not found"});
}

TEST_F(SceneErrorsTest, MalformedObjFile) {
  Write("bad.obj", "v 0 0 0\nv 1 0 0\nv 1 1 0\nf 1 2 7\n");
  ExpectError(Scene(R"("polygon": {"vertices": [{"x": 0, "y": 0, "z": 0}, {"x": 1, "y": 0, "z": 0},
                                             {"x": 1, "y": 1, "z": 0}]})",
                    R"("obj": {"path": "bad.obj"})"),
              {"surfaces[0].obj.path", "bad.obj", "malformed OBJ"});
  Write("empty.obj", "# nothing\n");
  ExpectError(Scene(R"("polygon": {"vertices": [{"x": 0, "y": 0, "z": 0}, {"x": 1, "y": 0, "z": 0},
                                             {"x": 1, "y": 1, "z": 0}]})",
                    R"("obj": {"path": "empty.obj"})"),
              {"surfaces[0].obj.path", "no faces"});
}

TEST_F(SceneErrorsTest, ObjGroupsGetMaterialsAndDegenerateTrianglesAreLeftOut) {
  Write("mesh.obj",
        "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 2 0 0\n"
        "g slats\nf 1 2 3\ng rest\nf 1 2 3\nf 1 2 4\n");  // the last face has zero area
  absl::StatusOr<fenestra::Scene> scene = LoadScene(
      Scene(R"("polygon": {"vertices": [{"x": 0, "y": 0, "z": 0}, {"x": 1, "y": 0, "z": 0},
                                             {"x": 1, "y": 1, "z": 0}]})",
            R"("obj": {"path": "mesh.obj", "groupMaterials": {"slats": "slat"}})"));
  ASSERT_TRUE(scene.ok()) << scene.status();
  ASSERT_EQ(scene->fixed.TriangleCount(), 2u);
  EXPECT_EQ(scene->dropped_degenerate, 1u);
  EXPECT_EQ(scene->materials[scene->fixed.material[0]].name, "slat");
  EXPECT_EQ(scene->materials[scene->fixed.material[1]].name, "wall");
}

TEST_F(SceneErrorsTest, UnknownEnumValues) {
  ExpectError(Scene(R"("side": "SIDE_INDOOR")", R"("side": 99)"),
              {"surfaces[0].side", "must be SIDE_INDOOR or SIDE_OUTDOOR, got 99"});
  ExpectError(Scene(R"("material": "slat",)", R"("material": "slat", "orientation": 7,)"),
              {"blind.orientation", "must be HORIZONTAL or VERTICAL, got 7"});
  ExpectError(Scene(R"("material": "slat",)", R"("material": "slat", "operation": 42,)"),
              {"blind.operation", "unknown operation 42 (STATIC or AUTOMATED_SUN)"});
}

TEST_F(SceneErrorsTest, BadNames) {
  ExpectError(Scene(R"("name": "floor")", R"("name": "floor\nINFO forged")"),
              {"surfaces[0].name", "control character U+000A at offset 5"});
  ExpectError(Scene(R"("name": "s")", R"("name": "s\u0000")"),
              {"sensors[0].name", "control character U+0000"});
  ExpectError(Scene(R"("name": "box")", R"("name": ")" + std::string(257, 'x') + R"(")"),
              {": name:", "257 bytes long, more than the 256 allowed"});
  ExpectError(Scene(R"({"name": "wall")", R"({"name": "wall\u202e")"),
              {"materials[0].name", "U+202E"});
}

TEST_F(SceneErrorsTest, HugeCoordinatesAndWindows) {
  ExpectError(Scene(R"({"x": 1, "y": 0, "z": 0})", R"({"x": 2e5, "y": 0, "z": 0})"),
              {"surfaces[0].polygon.vertices[1]", "lies beyond 100000 m"});
  ExpectError(Scene(R"("position": {"x": 0.5)", R"("position": {"x": 1e9)"),
              {"sensors[0].position", "lies beyond 100000 m"});
  ExpectError(Scene(R"("widthM": 1)", R"("widthM": 1e6)"), {"window: a corner", "lies beyond"});
  ExpectError(Scene(R"({"x": 1, "y": 0, "z": 0})", R"({"x": 1e300, "y": 0, "z": 0})"),
              {"surfaces[0].polygon.vertices[1]", "lies beyond 100000 m"});
  ExpectError(Scene(R"("depthM": 0.2)", R"("depthM": 50)"),
              {"window.depth_m", "must be in [0, 5] m"});
  ExpectError(Scene(R"("depthM": 0.2)", R"("depthM": 1e308)"),
              {"window.depth_m", "must be in [0, 5] m"});
  // A window normal of huge or subnormal length is normalized, not overflowed to NaN
  for (const char* normal :
       {R"({"x": 0, "y": 5.9e236, "z": 0})", R"({"x": 0, "y": 1e-320, "z": 0})"}) {
    absl::StatusOr<fenestra::Scene> scene = LoadScene(Scene(R"({"x": 0, "y": 1, "z": 0})", normal));
    ASSERT_TRUE(scene.ok()) << scene.status();
    EXPECT_EQ(scene->window().normal.y, 1.0) << normal;
    EXPECT_EQ(scene->window().across.x, -1.0) << normal;
  }
  // Directions of any finite size are normalized without overflow
  absl::StatusOr<fenestra::Scene> scene =
      LoadScene(Scene(R"("direction": {"x": 0, "y": 0, "z": 1})",
                      R"("direction": {"x": 0, "y": 1e300, "z": 1e300})"));
  ASSERT_TRUE(scene.ok()) << scene.status();
  EXPECT_NEAR(scene->sensors[0].direction.y, std::sqrt(0.5), 1e-15);
}

TEST_F(SceneErrorsTest, SensorGridsAreBounded) {
  ExpectError(Scene(R"("sensors": [)", R"("sensorGrids": [{"zM": 0.5, "xMaxM": 1, "yMaxM": 1,
                                          "spacingM": 1e-6}], "sensors": [)"),
              {"sensor_grids[0]", "a scene holds at most 1000000 sensors"});
  ExpectError(Scene(R"("sensors": [)", R"("sensorGrids": [{"zM": 0.5, "xMaxM": 1e300, "yMaxM": 1,
                                          "spacingM": 1}], "sensors": [)"),
              {"sensor_grids[0]", "lies beyond 100000 m"});
}

TEST_F(SceneErrorsTest, NonConvexPolygon) {
  ExpectError(
      Scene(
          R"({"x": 1, "y": 1, "z": 0}]})",
          R"({"x": 1, "y": 1, "z": 0}, {"x": 0.5, "y": 0.2, "z": 0}, {"x": 0, "y": 1, "z": 0}]})"),
      {"surfaces[0].polygon.vertices[3]", "not convex"});
  // A five-pointed star drawn in one stroke turns the same way at every corner, but twice round
  ExpectError(
      Scene(
          R"({"x": 0, "y": 0, "z": 0}, {"x": 1, "y": 0, "z": 0},
                                             {"x": 1, "y": 1, "z": 0}]})",
          R"({"x": 0.500000, "y": 0.900000, "z": 0}, {"x": 0.264886, "y": 0.176393, "z": 0}, {"x": 0.880423, "y": 0.623607, "z": 0}, {"x": 0.119577, "y": 0.623607, "z": 0}, {"x": 0.735114, "y": 0.176393, "z": 0}]})"),
      {"surfaces[0].polygon", "not convex"});
}

TEST_F(SceneErrorsTest, BlindsOutsidePhysicalSense) {
  ExpectError(Scene(R"("tiltRad": {"value": 0, "min": 0, "max": 1.5})",
                    R"("tiltRad": {"value": 0, "min": -2, "max": 1.5})"),
              {"blind.tilt_rad", "[-2, 1.5] must stay within [-1.5708, 1.5708] rad"});
  ExpectError(Scene(R"("slatSpacingM": {"value": 0, "min": 0, "max": 0.1})",
                    R"("slatSpacingM": {"value": 0, "min": 0.1, "max": 0})"),
              {"blind.slat_spacing_m", "min must not exceed max"});
  ExpectError(Scene(R"("slatThicknessM": {"value": 0.01, "min": 0.01, "max": 0.02})",
                    R"("slatThicknessM": {"value": 0.06, "min": 0.01, "max": 0.06})"),
              {"blind:", "slats up to 0.06 m thick and from 0.05 m wide"});
  ExpectError(Scene(R"("heightM": 1)", R"("heightM": 0.12)"),
              {"blind:", "slats up to 0.15 m wide are wider than the window's 0.12 m height"});
  ExpectError(Scene(R"("material": "slat",)", R"("material": "slat", "sideMarginM": 1e9,)"),
              {"blind.side_margin_m", "must be in [0, 1] m, got 1e+09"});
  ExpectError(Scene(R"("material": "slat",)", R"("material": "slat", "wallGapM": -0.01,)"),
              {"blind.wall_gap_m", "must be in [0, 1] m"});
  ExpectError(Scene(R"("tiltRad": {"value": 0,)", R"("tiltRad": {"value": "NaN",)"),
              {"blind.tilt_rad", "finite"});
}

// Radiance's materials of every kind, the blind's slats of metal with white outer faces.
constexpr char kRadianceMaterials[] = R"({"name": "slat", "metal": {"reflectance": 0.8,
                                     "specularity": 0.9, "roughness": 0.05}},
    {"name": "paint", "plastic": {"reflectance": 0.5, "specularity": 0.04, "roughness": 0.1}},
    {"name": "fabric", "trans": {"reflectance": 0.6, "specularity": 0.02, "roughness": 0.2,
                                 "transmissivity": 0.5, "transmittedSpecular": 0.25}},
    {"name": "pane", "glass": {"transmittance": 0.88}},
    {"name": "white", "reflectance": 0.9})";

void ExpectParts(const Material& m, MaterialKind kind, double reflectance, double specular,
                 double roughness, double through, double transmittance) {
  SCOPED_TRACE(m.name);
  EXPECT_EQ(m.kind, kind);
  EXPECT_DOUBLE_EQ(m.reflectance, reflectance);
  EXPECT_DOUBLE_EQ(m.specular, specular);
  EXPECT_DOUBLE_EQ(m.roughness, roughness);
  EXPECT_DOUBLE_EQ(m.through, through);
  EXPECT_DOUBLE_EQ(m.transmittance, transmittance);
}

TEST_F(SceneErrorsTest, RadianceMaterialsBecomeTheirParts) {
  absl::StatusOr<fenestra::Scene> scene =
      LoadScene(Scene(R"({"name": "slat", "reflectance": 0.8})", kRadianceMaterials));
  ASSERT_TRUE(scene.ok()) << scene.status();
  ASSERT_EQ(scene->materials.size(), 6u);
  ExpectParts(scene->materials[0], MaterialKind::kLambertian, 0.5, 0, 0, 0, -1);
  // Metal: diffuse c (1 - s), lobe c s
  ExpectParts(scene->materials[1], MaterialKind::kMetal, 0.08, 0.72, 0.05, 0, -1);
  // Plastic: diffuse c (1 - s), lobe s
  ExpectParts(scene->materials[2], MaterialKind::kPlastic, 0.48, 0.04, 0.1, 0, -1);
  // Trans: c (1 - s) = 0.588 of it diffuse, reflected (1 - T), transmitted T, of that T_s
  // straight
  ExpectParts(scene->materials[3], MaterialKind::kTrans, 0.294, 0.02, 0.2, 0.2205, 0.0735);
  ExpectParts(scene->materials[4], MaterialKind::kGlass, 0, 0, 0, 0, 0.88);
  ExpectParts(scene->materials[5], MaterialKind::kLambertian, 0.9, 0, 0, 0, -1);
  // Described by the parameters the scene gave
  EXPECT_EQ(DescribeMaterial(scene->materials[1]),
            "metal: colour 0.8, specularity 0.9, roughness 0.05");
  EXPECT_EQ(DescribeMaterial(scene->materials[3]),
            "trans: colour 0.6, specularity 0.02, roughness 0.2, transmissivity 0.5, transmitted "
            "specular 0.25");
  EXPECT_EQ(DescribeMaterial(scene->materials[4]), "glass: transmittance 0.88 at normal incidence");
}

TEST_F(SceneErrorsTest, RadianceParametersOutsideTheirRanges) {
  const std::string metal =
      R"("metal": {"reflectance": 0.8, "specularity": 0.9, "roughness": 0.05})";
  const auto bad = [&](const std::string& material, std::initializer_list<std::string> parts) {
    ExpectError(
        Scene(R"({"name": "slat", "reflectance": 0.8})", R"({"name": "slat", )" + material + "}"),
        parts);
  };
  bad(R"("metal": {"reflectance": 1.2, "specularity": 0.9})",
      {"materials[1].metal.reflectance", "must be in [0, 1], got 1.2"});
  bad(R"("metal": {"reflectance": 0.8, "specularity": 1})",
      {"materials[1].metal.specularity", "must be in [0, 1), got 1"});
  bad(R"("plastic": {"reflectance": 0.5, "roughness": 1.5})",
      {"materials[1].plastic.roughness", "must be in [0, 1], got 1.5"});
  bad(R"("plastic": {"reflectance": "NaN"})", {"materials[1].plastic.reflectance", "got nan"});
  bad(R"("trans": {"reflectance": 0.5, "transmissivity": -0.1})",
      {"materials[1].trans.transmissivity", "must be in [0, 1], got -0.1"});
  bad(R"("trans": {"reflectance": 0.5, "transmissivity": 0.5, "transmittedSpecular": 2})",
      {"materials[1].trans.transmitted_specular", "must be in [0, 1], got 2"});
  bad(R"("glass": {"transmittance": 0.95})",
      {"materials[1].glass.transmittance", "must be in (0, 0.9]", "got 0.95"});
  bad(R"("glass": {})", {"materials[1].glass.transmittance", "got 0"});
  // Each parameter in range, but a white plastic or metal would reflect all it gets
  bad(R"("plastic": {"reflectance": 1, "specularity": 0.1})",
      {"materials[1].plastic:", "reflectance + specular must be below 1, got 1"});
  bad(R"("metal": {"reflectance": 1, "specularity": 0.5})",
      {"materials[1].metal:", "reflectance + specular must be below 1, got 1"});
  // One meaning per setting: Lambertian fields or a kind, not both (an explicit 0 too)
  bad(R"("reflectance": 0.8, )" + metal,
      {"materials[1].reflectance",
       "is Lambertian (reflectance, transmittance) or one of "
       "plastic, metal, trans and glass, not both: this one also gives metal"});
  bad(R"("reflectance": 0, )" + metal, {"materials[1].reflectance", "also gives metal"});
  bad(R"("transmittance": 0.5, "glass": {"transmittance": 0.8})",
      {"materials[1].transmittance", "also gives glass"});
}

TEST_F(SceneErrorsTest, SlatsOfGlassAreRefused) {
  const std::string slat = R"({"name": "slat", "reflectance": 0.8})";
  const std::string blind = R"("material": "slat",)";
  ExpectError(Scene(slat, R"({"name": "slat", "glass": {"transmittance": 0.8}})"),
              {"blind.material", "'slat' is a glass: slats of glass make no blind"});
  ExpectError(Scene({{slat, slat + R"(, {"name": "pane", "glass": {"transmittance": 0.8}})"},
                     {blind, blind + R"( "outerMaterial": "pane",)"}}),
              {"blind.outer_material", "'pane' is a glass"});
  ExpectError(Scene(blind, blind + R"( "outerMaterial": "brick",)"),
              {"blind.outer_material", "unknown material 'brick'"});
}

// The outer material covers face 4 of every slat (2 of its 12 triangles), the slat material
// the rest
TEST_F(SceneErrorsTest, OuterMaterialCoversTheSlatsOuterFacesOnly) {
  const std::string blind = R"("material": "slat",)";
  absl::StatusOr<fenestra::Scene> scene =
      LoadScene(Scene({{R"({"name": "slat", "reflectance": 0.8})", kRadianceMaterials},
                       {blind, blind + R"( "outerMaterial": "white",)"}}));
  ASSERT_TRUE(scene.ok()) << scene.status();
  ASSERT_EQ(scene->blind()->material, 1u);
  ASSERT_EQ(scene->blind()->outer_material, 5u);
  const TriangleMesh mesh = AssembleMesh(*scene, DefaultDesign(*scene));
  const size_t first = scene->fixed.TriangleCount();
  const size_t slats = (mesh.TriangleCount() - first) / kTrianglesPerSlat;
  ASSERT_EQ(slats, 10u);
  std::map<uint32_t, size_t> per_material;
  for (size_t t = first; t < mesh.TriangleCount(); ++t) {
    ++per_material[mesh.material[t]];
    const int face = static_cast<int>((t - first) % kTrianglesPerSlat) / 2;
    EXPECT_EQ(mesh.material[t], face == kSlatOuterFace ? 5u : 1u) << "triangle " << t;
  }
  EXPECT_EQ(per_material.size(), 2u);
  EXPECT_EQ(per_material[5], 2 * slats);
  EXPECT_EQ(per_material[1], 10 * slats);
}

TEST_F(SceneErrorsTest, WindowsListGivesTheSameSceneAsTheOneWindowForm) {
  // The window and its blind moved into windows[0]
  const std::string text = R"({
      "name": "box",
      "materials": [{"name": "wall", "reflectance": 0.5}, {"name": "slat", "reflectance": 0.8}],
      "surfaces": [{"name": "floor", "material": "wall", "side": "SIDE_INDOOR",
                    "polygon": {"vertices": [{"x": 0, "y": 0, "z": 0}, {"x": 1, "y": 0, "z": 0},
                                             {"x": 1, "y": 1, "z": 0}]}}],
      "windows": [{"name": "south", "center": {"x": 0, "y": 1, "z": 1},
                   "outwardNormal": {"x": 0, "y": 1, "z": 0}, "up": {"x": 0, "y": 0, "z": 1},
                   "widthM": 1, "heightM": 1, "depthM": 0.2,
                   "blind": {"material": "slat", "group": "south-facade",
                             "tiltRad": {"value": 0, "min": 0, "max": 1.5},
                             "slatWidthM": {"value": 0.1, "min": 0.05, "max": 0.15},
                             "slatSpacingM": {"value": 0, "min": 0, "max": 0.1},
                             "slatThicknessM": {"value": 0.01, "min": 0.01, "max": 0.02}}}],
      "sensors": [{"name": "s", "position": {"x": 0.5, "y": 0.5, "z": 0.5},
                   "direction": {"x": 0, "y": 0, "z": 1}}]
    })";
  absl::StatusOr<fenestra::Scene> listed = LoadScene(Write("listed.json", text));
  absl::StatusOr<fenestra::Scene> single = LoadScene(Scene());
  ASSERT_TRUE(listed.ok()) << listed.status();
  ASSERT_TRUE(single.ok()) << single.status();
  EXPECT_EQ(listed->window().center.y, single->window().center.y);
  EXPECT_EQ(listed->window().depth_m, single->window().depth_m);
  ASSERT_TRUE(listed->blind().has_value());
  const TriangleMesh a = AssembleMesh(*listed, DefaultDesign(*listed));
  const TriangleMesh b = AssembleMesh(*single, DefaultDesign(*single));
  ASSERT_EQ(a.vertices.size(), b.vertices.size());
  for (size_t v = 0; v < a.vertices.size(); ++v) {
    EXPECT_EQ(Length(a.vertices[v] - b.vertices[v]), 0.0) << "vertex " << v;
  }

  // Errors name the field
  auto edited = [&](const std::string& find, const std::string& replace) {
    std::string t = text;
    t.replace(t.find(find), find.size(), replace);
    return Write("edited.json", t);
  };
  ExpectError(edited(R"("widthM": 1,)", R"("widthM": 0.001,)"), {"windows[0].width_m"});
  ExpectError(edited(R"("group": "south-facade")", R"("group": "south facade")"),
              {"windows[0].blind.group"});
  ExpectError(edited(R"("name": "south")", R"("name": "s/../x")"), {"windows[0].name"});
  ExpectError(edited(R"("material": "slat",)", R"("material": "none",)"),
              {"windows[0].blind.material"});
  ExpectError(edited(R"("windows": [)", R"("blind": {"material": "slat"}, "windows": [)"),
              {"blind", "each window has its blind"});
  ExpectError(Scene(R"("sensors": [)", R"("windows": [{"widthM": 1}], "sensors": [)"),
              {"windows", "either window"});
  ExpectError(Scene(R"("window": {)", R"("windowz": {)"), {"malformed scene"});
}

TEST_F(SceneErrorsTest, MissingSceneFile) {
  absl::StatusOr<fenestra::Scene> scene = LoadScene((dir_ / "none.json").string());
  ASSERT_FALSE(scene.ok());
  EXPECT_NE(scene.status().message().find("none.json: cannot open"), std::string::npos);
}

}  // namespace
}  // namespace fenestra
