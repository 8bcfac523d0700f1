// fenestra scene import, run as a user would: a public Radiance model and a public Honeybee
// model (tests/data/models/, sources in their READMEs) become scenes that `fenestra dc` traces,
// and the Radiance model, given a blind, runs an optimization.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <string>
#include <tuple>

#include "client/cli_util.h"
#include "core/geometry/scene.h"
#include "tests/client/cli_run.h"

namespace fenestra {
namespace {

using SceneImportTest = CliTest;

const std::string kModels = FENESTRA_SOURCE_DIR "/tests/data/models";
const std::string kWeather = kExamples + "/weather/URY_Montevideo.865800_IWEC.epw";

// The tutorial room's files, materials first, and its outdoor context.
std::string TutorialRoomArgs() {
  const std::string m = kModels + "/matrix_tutorial_room/";
  std::string args = m + "materials.rad";
  for (const char* o : {"Ceiling", "Floor", "InteriorWall", "Glazing"}) {
    args += " " + m + "objects/" + o + ".rad";
  }
  for (const char* o : {"ExteriorWalls", "Ground"})
    args += " --context " + m + "objects/" + o + ".rad";
  return args + " --pts " + m + "points.txt";
}

TEST_F(SceneImportTest, RadianceModelRunsADcAndAJob) {
  const std::string scene = (dir_ / "room.json").string();
  const CliRun imported =
      Fenestra("scene import " + TutorialRoomArgs() + " --weather " + kWeather + " -o " + scene);
  ASSERT_EQ(imported.exit_code, 0) << imported.output;
  EXPECT_NE(imported.output.find("1 windows, 100 sensors"), std::string::npos) << imported.output;
  EXPECT_NE(imported.output.find("the scene is a room"), std::string::npos) << imported.output;

  // Export as a model, import again: the same scene file
  const std::string model = (dir_ / "back.rad").string(), pts = (dir_ / "back.pts").string();
  const std::string again = (dir_ / "again.json").string();
  const CliRun exported = Fenestra("scene export " + scene + " --model " + model + " --pts " + pts);
  ASSERT_EQ(exported.exit_code, 0) << exported.output;
  const CliRun reimported = Fenestra("scene import " + model + " --pts " + pts + " -o " + again);
  ASSERT_EQ(reimported.exit_code, 0) << reimported.output;
  absl::StatusOr<v1::Scene> first = ReadSceneProto(scene), second = ReadSceneProto(again);
  ASSERT_TRUE(first.ok() && second.ok());
  EXPECT_EQ(first->DebugString(), second->DebugString());

  const CliRun dc =
      Fenestra("dc " + scene + " --method one-stage --paths 2000 -o " + (dir_ / "D.txt").string());
  ASSERT_EQ(dc.exit_code, 0) << dc.output;
  EXPECT_NE(dc.output.find("sensor_99"), std::string::npos) << dc.output;

  // The window gets a blind, and a short tilt optimization runs on the imported room
  absl::StatusOr<v1::Scene> proto = ReadSceneProto(scene);
  ASSERT_TRUE(proto.ok()) << proto.status();
  v1::Material& slat = *proto->add_materials();
  slat.set_name("slat");
  slat.set_reflectance(0.7);
  v1::VenetianBlind& blind = *proto->mutable_windows(0)->mutable_blind();
  blind.set_material("slat");
  for (const auto& [p, value, lo, hi] :
       {std::tuple{blind.mutable_tilt_rad(), 0.0, 0.0, 1.5},
        std::tuple{blind.mutable_slat_width_m(), 0.08, 0.08, 0.08},
        std::tuple{blind.mutable_slat_spacing_m(), 0.0, 0.0, 0.0},
        std::tuple{blind.mutable_slat_thickness_m(), 0.005, 0.005, 0.005}}) {
    p->set_value(value), p->set_min(lo), p->set_max(hi);
  }
  ASSERT_TRUE(WriteJsonFile((dir_ / "room_blind.json").string(), *proto).ok());
  const std::string job = (dir_ / "job.json").string();
  {
    std::ofstream out(job);
    out << R"({"sceneFile": "room_blind.json",
      "sampling": {"outdoorPaths": 40000, "indoorPathsPerSensor": 1000, "batches": 4,
                   "windowColumns": 1, "windowRows": 1, "backend": "cpu"},
      "variables": [{"name": "alpha", "lower": 0, "upper": 1.5, "start": 0}],
      "objective": {"metric": "METRIC_UDI", "goal": "GOAL_MAXIMIZE"},
      "budget": {"maxEvaluations": 4}})";
  }
  const CliRun optimized = Fenestra("optimize --local " + job);
  ASSERT_EQ(optimized.exit_code, 0) << optimized.output;
  EXPECT_NE(optimized.output.find("best design: alpha="), std::string::npos) << optimized.output;
}

TEST_F(SceneImportTest, HoneybeeModelRunsADc) {
  const std::string scene = (dir_ / "hb.json").string();
  const CliRun imported = Fenestra("scene import " + kModels +
                                   "/end_windows_hall/end_windows_hall.hbjson --grid core -o " + scene);
  ASSERT_EQ(imported.exit_code, 0) << imported.output;
  EXPECT_NE(imported.output.find("the scene is a room"), std::string::npos) << imported.output;
  const CliRun dc =
      Fenestra("dc " + scene + " --method one-stage --paths 500 -o " + (dir_ / "D.txt").string());
  EXPECT_EQ(dc.exit_code, 0) << dc.output;
}

TEST_F(SceneImportTest, BadArgumentsAndModelsAreRefusedWithNothingWritten) {
  const std::string scene = (dir_ / "x.json").string();
  for (const std::string& args :
       {kModels + "/matrix_tutorial_room/materials.rad -o " + scene,  // no --pts
        kModels + "/end_windows_hall/end_windows_hall.hbjson --pts p.txt -o " + scene,
        kModels + "/matrix_tutorial_room/room.rad --pts " + kModels +
            "/matrix_tutorial_room/points.txt -o " + scene}) {  // !xform
    const CliRun run = Fenestra("scene import " + args);
    EXPECT_NE(run.exit_code, 0) << run.output;
    EXPECT_NE(run.output.find("error:"), std::string::npos) << run.output;
    EXPECT_FALSE(std::filesystem::exists(scene)) << args;
  }
}

}  // namespace
}  // namespace fenestra
