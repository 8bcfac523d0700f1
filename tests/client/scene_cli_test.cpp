// fenestra scene, run as a user would.
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>

#include "core/geometry/obj_io.h"
#include "tests/client/cli_run.h"

namespace fenestra {
namespace {

namespace fs = std::filesystem;

using SceneCliTest = CliTest;

std::string ReadText(const std::string& path) {
  std::ifstream in(path);
  return std::string(std::istreambuf_iterator<char>(in), {});
}

TEST_F(SceneCliTest, ExportLightwellGives42Triangles) {
  const std::string obj = (dir_ / "x.obj").string();
  const CliRun run = Fenestra("scene export " + kExamples + "/lightwell/scene.json --obj " + obj);
  ASSERT_EQ(run.exit_code, 0) << run.output;
  absl::StatusOr<ObjTriangles> read = ReadObj(obj);
  ASSERT_TRUE(read.ok()) << read.status();
  EXPECT_EQ(read->group.size(), 42u);
}

TEST_F(SceneCliTest, ExportWithDesignValues) {
  const std::string obj = (dir_ / "office.obj").string();
  const CliRun run = Fenestra("scene export " + kExamples + "/city_office/scene.json --obj " + obj +
                              " --set alpha=0.5,width=0.1");
  ASSERT_EQ(run.exit_code, 0) << run.output;
  absl::StatusOr<ObjTriangles> read = ReadObj(obj);
  ASSERT_TRUE(read.ok()) << read.status();
  // 126 fixed triangles + 15 slats (1 + ceil((1.5 - 0.1) / 0.1)) of 12
  EXPECT_EQ(read->group.size(), 126u + 15u * 12u);
}

// The Radiance export of the city office at a design: its 4 materials as plastic, a polygon per
// triangle (126 fixed ones and 15 slats of 12), the 9 sensors as points.
TEST_F(SceneCliTest, ExportsRadianceMaterialsPolygonsAndSensors) {
  const std::string rad = (dir_ / "office.rad").string(), pts = (dir_ / "office.pts").string();
  const std::string scene = kExamples + "/city_office/scene.json";
  const CliRun run =
      Fenestra("scene export " + scene + " --rad " + rad + " --pts " + pts + " --set width=0.1");
  ASSERT_EQ(run.exit_code, 0) << run.output;
  const std::string text = ReadText(rad);
  EXPECT_NE(text.find("void plastic m0_office\n0\n0\n5 0.8 0.8 0.8 0 0\n"), std::string::npos)
      << text.substr(0, 400);
  EXPECT_NE(text.find("void plastic m1_office_floor\n"), std::string::npos);
  size_t polygons = 0;
  for (size_t at = text.find(" polygon t"); at != std::string::npos;
       at = text.find(" polygon t", at + 1)) {
    ++polygons;
  }
  EXPECT_EQ(polygons, 126u + 15u * 12u);
  const std::string points = ReadText(pts);
  EXPECT_EQ(std::count(points.begin(), points.end(), '\n'), 9);
  EXPECT_EQ(points.substr(0, points.find('\n')), "-1 -1 6.7 0 0 1");
  // One of --obj, --rad and --model, and --pts only with --rad or --model
  EXPECT_NE(Fenestra("scene export " + scene).exit_code, 0);
  EXPECT_NE(Fenestra("scene export " + scene + " --obj x.obj --rad y.rad").exit_code, 0);
  EXPECT_NE(Fenestra("scene export " + scene + " --pts " + pts).exit_code, 0);
  EXPECT_NE(Fenestra("scene export " + scene + " --model m.rad --rad y.rad").exit_code, 0);
}

TEST_F(SceneCliTest, CheckPrintsASummary) {
  const CliRun run = Fenestra("scene check " + kExamples + "/city_office/scene.json");
  ASSERT_EQ(run.exit_code, 0) << run.output;
  EXPECT_NE(run.output.find("246 triangles"), std::string::npos) << run.output;
  EXPECT_NE(run.output.find("sensors: 9"), std::string::npos) << run.output;
  EXPECT_NE(run.output.find("10 slats"), std::string::npos) << run.output;
}

TEST_F(SceneCliTest, BadDesignValueFailsAndWritesNothing) {
  const std::string obj = (dir_ / "bad.obj").string();
  const CliRun run = Fenestra("scene export " + kExamples + "/city_office/scene.json --obj " + obj +
                              " --set width=0.3");
  EXPECT_EQ(run.exit_code, 1);
  EXPECT_NE(run.output.find("error: design variable width = 0.3 is outside its range"),
            std::string::npos)
      << run.output;
  EXPECT_FALSE(fs::exists(obj));
  EXPECT_TRUE(fs::is_empty(dir_));
}

TEST_F(SceneCliTest, BadSceneFailsAndWritesNothing) {
  const std::string scene = (dir_ / "scene.json").string();
  std::ofstream(scene) << R"({"name": "x", "materials": [{"name": "m", "reflectance": 1.5}]})";
  const std::string obj = (dir_ / "out.obj").string();
  const CliRun run = Fenestra("scene export " + scene + " --obj " + obj);
  EXPECT_EQ(run.exit_code, 1);
  EXPECT_NE(run.output.find(scene + ": materials[0].reflectance: must be in [0, 1)"),
            std::string::npos)
      << run.output;
  EXPECT_FALSE(fs::exists(obj));
}

TEST_F(SceneCliTest, UnwritableOutputFailsCleanly) {
  const CliRun run = Fenestra("scene export " + kExamples + "/lightwell/scene.json --obj " +
                              (dir_ / "no/such/dir/x.obj").string());
  EXPECT_EQ(run.exit_code, 1);
  EXPECT_NE(run.output.find("cannot open for writing"), std::string::npos) << run.output;
}

}  // namespace
}  // namespace fenestra
