// Every kind of bad scene input gives an error naming the file, the field and the reason.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

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
    if (!find.empty()) {
      const size_t at = text.find(find);
      EXPECT_NE(at, std::string::npos) << find;
      text.replace(at, find.size(), replace);
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

// Coordinates and lengths beyond 1e7 m are refused, so no sum of them overflows; a direction
// may have any finite length.
TEST_F(SceneErrorsTest, HugeCoordinatesAndLengths) {
  ExpectError(Scene(R"({"x": 1, "y": 0, "z": 0})", R"({"x": 1e300, "y": 0, "z": 0})"),
              {"surfaces[0].polygon.vertices[1]", "within ±1e+07 m"});
  ExpectError(Scene(R"("depthM": 0.2)", R"("depthM": 1e308)"), {"window.depth_m", "1e+07"});
  ExpectError(Scene(R"("slatWidthM": {"value": 0.1, "min": 0.05, "max": 0.15})",
                    R"("slatWidthM": {"value": 1e300})"),
              {"blind.slat_width_m", "1e+07"});
  for (const char* normal :
       {R"({"x": 0, "y": 5.9e236, "z": 0})", R"({"x": 0, "y": 1e-320, "z": 0})"}) {
    absl::StatusOr<fenestra::Scene> scene = LoadScene(Scene(R"({"x": 0, "y": 1, "z": 0})", normal));
    ASSERT_TRUE(scene.ok()) << scene.status();
    EXPECT_EQ(scene->window.normal.y, 1.0) << normal;
    EXPECT_EQ(scene->window.across.x, -1.0) << normal;
  }
}

TEST_F(SceneErrorsTest, DegenerateWindow) {
  ExpectError(Scene(R"("widthM": 1)", R"("widthM": 0)"), {"window.width_m", "> 0"});
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
              {"blind.slat_width_m", "> 0"});
  ExpectError(Scene(R"("slatThicknessM": {"value": 0.01, "min": 0.01)",
                    R"("slatThicknessM": {"value": 0.01, "min": -0.01)"),
              {"blind.slat_thickness_m", "below 0"});
  ExpectError(Scene(R"("slatSpacingM": {"value": 0, "min": 0)",
                    R"("slatSpacingM": {"value": 0, "min": -1)"),
              {"blind.slat_spacing_m", "below 0"});
}

// Sizes that would take more memory than a scene may use are errors before any is taken.
TEST_F(SceneErrorsTest, TooManySensorsOrSlats) {
  const std::string sensors = R"("sensors": [)";
  ExpectError(Scene(sensors, R"("sensorGrids": [{"zM": 0.8, "xMinM": 0, "xMaxM": 1.8, "yMinM": 0,
                                                "yMaxM": 2.8, "spacingM": 1e-5}], )" +
                                 sensors),
              {"sensor_grids[0]", "the grid holds 5.04e+10 sensors", "at most 1e+06"});
  // The pitch is at least the width: 1 m / 1e-7 m needs 10^7 slats
  ExpectError(
      Scene(R"("slatWidthM": {"value": 0.1, "min": 0.05)",
            R"("slatWidthM": {"value": 0.1, "min": 1e-7)"),
      {"blind.slat_width_m", "at its narrowest, 1e-07 m", "up to 1e+07 slats", "at most 100000"});
  // Far more slats than an int counts
  ExpectError(Scene(R"("slatWidthM": {"value": 0.1, "min": 0.05, "max": 0.15})",
                    R"("slatWidthM": {"value": 1e-300})"),
              {"blind.slat_width_m", "at most 100000"});
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

TEST_F(SceneErrorsTest, MissingSceneFile) {
  absl::StatusOr<fenestra::Scene> scene = LoadScene((dir_ / "none.json").string());
  ASSERT_FALSE(scene.ok());
  EXPECT_NE(scene.status().message().find("none.json: cannot open"), std::string::npos);
}

}  // namespace
}  // namespace fenestra
